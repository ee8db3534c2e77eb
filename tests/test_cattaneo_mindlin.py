"""The Cattaneo-Mindlin verification case on the test suite's coarse mesh: the stick zone's
half-width c = a sqrt(1 - Q / (mu P)) at Q / (mu P) near 0.5 and the contact half-width against
Hertz, each within 5 % (comove_dolfinx/verify/cattaneo_mindlin.py); its picture is written."""
import pytest

from comove_dolfinx.verify import cattaneo_mindlin


@pytest.mark.mpi
def test_cattaneo_mindlin_small(mpi_tmp, comm):
    checks = cattaneo_mindlin.run(mpi_tmp, small=True)
    assert len(checks) == 2
    for check in checks:
        assert check.ok, check.row()
    assert 0.4 < float(checks[0].quantity.rsplit("=", 1)[1]) < 0.6       # partial slip, Q < mu P
    if comm.rank == 0:
        assert (mpi_tmp / f"{cattaneo_mindlin.NAME}.png").stat().st_size > 0

"""The demo scripts run as a user runs them (a process of their own, serial and on two ranks), leave
their pictures and XDMF file, and end where the physics puts them: the beam's tip and the plate's centre
rest on the obstacle (displacement = gap, to the penalty's penetration), the crushed ring carries more
than the rigid-perfectly-plastic ring (DeRunz-Hodge), and two ranks give the serial history."""
import math
import pathlib

import launch
import pytest
from test_elastica import read_history

DEMOS = pathlib.Path(__file__).resolve().parent.parent / "demos"


def _demo(name, out, sets=(), n=1):
    args = [DEMOS / f"demo_{name}.py", "--out", out]
    for s in sets:
        args += ["--set", s]
    p = launch.run(args, n=n)
    assert p.returncode == 0, p.stdout + p.stderr
    for f in ("results.xdmf", "results.h5", "history.csv", f"{name}_shapes.png", f"{name}_curves.png"):
        assert (out / f).is_file(), f
    return p.stdout, read_history(out / "history.csv")


@pytest.mark.parametrize("name, column, gap", [("beam", "tip_uy", 3.0), ("plate", "center_uz", 1.5)])
def test_elastic_demos_end_on_the_obstacle(tmp_path, name, column, gap):
    out, hist = _demo(name, tmp_path, ["size=0.25"])
    assert "completed" in out
    assert -hist[-1][column] == pytest.approx(gap, abs=1e-3)
    assert hist[-1]["contact_force"] > 0


def test_ring_demo_above_rigid_plastic_and_same_on_two_ranks(tmp_path):
    """A hardening ring carries more than the rigid-perfectly-plastic ring of DeRunz and Hodge once it
    has collapsed: P >= P0 / sqrt(1 - (delta / D)^2), P0 = 4 M_p / R with the plane-strain fully
    plastic moment M_p = (2 / sqrt 3) sigma_0 t^2 / 4 of the initial yield stress (theory 6.4)."""
    out, serial = _demo("ring", tmp_path / "np1")
    t, R_out, s0 = 0.866, 5.715, 2800.0
    R = R_out - t / 2
    P0 = 4 * (2 / math.sqrt(3)) * s0 * t ** 2 / 4 / R
    collapsed = [row for row in serial if row["load"] >= 1.0]
    assert len(collapsed) > 20
    for row in collapsed:
        assert row["force"] > P0 / math.sqrt(1 - (row["load"] / (2 * R)) ** 2), row
    assert "contact zone splits" in out
    _, parallel = _demo("ring", tmp_path / "np2", n=2)
    assert len(parallel) == len(serial)
    for a, b in zip(serial, parallel):
        assert b["force"] == pytest.approx(a["force"], rel=1e-6)

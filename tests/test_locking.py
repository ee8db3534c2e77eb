"""Volumetric locking in plastic flow: Prandtl's smooth flat punch on a perfectly plastic half-space
in plane strain (the verification case comove_dolfinx/verify/punch.py), whose limit pressure is
(2 + pi) k. P2 displacements reach it as the mesh is refined, in 2D and 3D; P1 ones overshoot it
by far (plastic flow keeps the volume), which the job warns of."""
import math

import pytest

import comove_dolfinx as cm
from comove_dolfinx.verify import punch


def test_p2_triangles_reach_prandtls_limit_pressure():
    """P2: 5.8 % above (2 + pi) k on 8 x 8 squares, 1.8 % on 16 x 16, and the pressure has levelled
    off (the last five increments add less than 0.2 %); no locking warning."""
    errors = []
    for n in (8, 16):
        _, p, res, _, _ = punch.press(n, 2)
        errors.append(p[-1] / punch.PRANDTL - 1.0)
        assert not [w for w in res.warnings if w.startswith("locking")], res.warnings
    assert abs(p[-1] / p[-6] - 1.0) < 2e-3, p[-6:]
    assert 0.0 < errors[1] < 0.025 and errors[1] < errors[0] / 2.5, errors


def test_p2_tetrahedra_reach_it_as_the_triangles_do():
    """The slab of P2 tetrahedra in plane strain: 8.3 % above (2 + pi) k at n = 8, 2.6 % at
    n = 16, as P2 triangles with one diagonal (8.9 %, 2.8 %): no locking in 3D either."""
    errors = [punch.press(n, 2, slab=True)[1][-1] / punch.PRANDTL - 1.0 for n in (8, 16)]
    assert 0.0 < errors[1] < 0.035 and errors[1] < errors[0] / 2.5, errors


def test_p1_triangles_lock_and_the_job_says_so():
    """P1 on the same 16 x 16 mesh: the limit pressure comes out over 10 % high, and the job
    warns of locking once, naming the fix."""
    _, p, res, _, _ = punch.press(16, 1, diagonal="right")
    assert p[-1] / punch.PRANDTL - 1.0 > 0.10, p[-1]
    said = [w for w in res.warnings if w.startswith("locking")]
    assert len(said) == 1 and "use degree=2" in said[0], res.warnings


@pytest.mark.parametrize("kind", ["plane_stress", "plane_strain"])
def test_no_locking_warning_where_it_does_not_apply(kind):
    """No warning for P1 in plane stress (the thickness takes the volume change: the body yields
    here) nor for an elastic P1 body."""
    mat = cm.J2(1000.0, 0.3, cm.Hardening.linear(math.sqrt(3.0), 100.0)) if kind == "plane_stress" \
        else cm.Elastic(1000.0, 0.3)
    body = cm.Body(punch.mesh(4), kind, mat, degree=1, update="small_strain")
    items = [cm.Fixed("sym", 0), cm.Fixed("bottom"), cm.Displacement("punch", -0.05, component=1)]
    res = cm.Job(body, items, [cm.Step(5)], probes=[cm.MaxPlasticStrain()], writers=[]).run()
    assert res.completed, res.message
    assert (max(res["max_plastic_strain"]) > 0.0) == (kind == "plane_stress")
    assert not [w for w in res.warnings if w.startswith("locking")], res.warnings

"""F-bar (B-bar under linear kinematics): the stress from the volume change averaged over each cell
(mechanics/volume.py). Its Jacobian (the condensed part through the mean dilatation included) passes
the Taylor test at deformed states with plastic flow and frictional slip; a homogeneous deformation,
whose volume change is the same everywhere, is left exactly as it was; Q1 elements, which lock in the
flat punch's plastic flow, reach Prandtl's limit pressure with it; the same history on two ranks
and after a restart; and where it does not apply, the body says so in one line."""
import math

import numpy as np
import pytest
from mpi4py import MPI

import comove_dolfinx as cm
from comove_dolfinx import geometry
from comove_dolfinx.mechanics.body import Body, BodyError
from comove_dolfinx.mechanics.model import Model
from comove_dolfinx.taylor import taylor_test
from comove_dolfinx.verify import punch
from states import one_correction_into
from test_output3d import _bent_block

E, NU = 1000.0, 0.3
HARDENING = cm.Hardening((0.0, 0.05, 0.2), (15.0, 20.0, 22.0))


@pytest.fixture(scope="module")
def cache(tmp_path_factory):
    return str(tmp_path_factory.mktemp("fbarmeshes"))


# -- Taylor tests -----------------------------------------------------------------------------------
def _bricks(cache, contact, update="sr_log"):
    """A J2 block of Q1 bricks sheared and compressed, with a follower pressure, a dead traction and a
    body force; its bottom held or pressed onto a plane with friction (penalty)."""
    md = geometry.box(1.0, 0.5, 0.5, 0.25, order=1, cache_dir=cache, hexahedra=True)
    items = [cm.Displacement("top", (0.06, 0.03, -0.06)), cm.Pressure("right", 5.0),
             cm.Traction("left", (2.0, -1.0, 0.5)), cm.BodyForce((2.0, -10.0, 3.0))]
    if contact:
        items.append(cm.Contact("bottom", cm.Plane((0.0, 0.0, 0.0), (0.0, 0.0, 1.0)), method="penalty",
                                gamma0=10.0, mu=0.1))
    else:
        items.append(cm.Fixed("bottom"))
    return Body(md, "solid", cm.J2(E, NU, HARDENING), update=update, degree=1, fbar=True), items


def _quads(kind, update="sr_log"):
    """The flat punch's quadrilaterals (4 x 4), pressed by a settlement and sheared along the top,
    J2 with hardening: plastic flow under the punch's edge."""
    md = punch.mesh(4, "none")
    items = [cm.Fixed("sym", 0), cm.Fixed("bottom"), cm.Displacement("punch", (0.02, -0.3))]
    return Body(md, kind, cm.J2(E, NU, cm.Hardening.linear(math.sqrt(3.0), 50.0)), update=update, degree=1,
                fbar=True), items


CASES = {"bricks-held": lambda c: _bricks(c, False), "bricks-friction": lambda c: _bricks(c, True),
         "bricks-hughes_winget": lambda c: _bricks(c, False, "hughes_winget"),
         "quads-plane_strain": lambda c: _quads("plane_strain"),
         "quads-axisymmetric": lambda c: _quads("axisymmetric"),
         "quads-small_strain": lambda c: _quads("plane_strain", "small_strain")}


@pytest.mark.parametrize("case", CASES)
def test_the_jacobian_with_fbar_is_exact(cache, case):
    """Order 2 of the Taylor remainder at a deformed state one Newton correction into an increment,
    points yielding (and, with friction, slipping); without the condensed part through the mean
    dilatation the order falls to 1 (the part is there and is needed)."""
    body, items = CASES[case](cache)
    m = Model(body, items)
    m.finalize()
    one_correction_into(m)
    assert m.comm.allreduce(int(np.sum(m.p.x.array > m.p_n.x.array)), op=MPI.SUM) > 0, "no point yields"
    result = taylor_test(m, h0=1e-4, n=8)
    assert np.all(np.abs(result.orders[-3:] - 2.0) < 0.15), str(result)
    add, m.volume.add_condensed = m.volume.add_condensed, lambda *a: None   # at fixed mean dilatation
    try:
        partial = taylor_test(m, h0=1e-4, n=8)
    finally:
        m.volume.add_condensed = add
    assert np.all(partial.orders[-3:] < 1.2), str(partial)


# -- a homogeneous deformation ----------------------------------------------------------------------------
@pytest.mark.parametrize("update", ["sr_log", "small_strain"])
def test_a_homogeneous_deformation_is_left_as_it_is(update):
    """A uniform stretch and shear of the punch's graded quadrilaterals (every point has the same
    volume change, so F_bar = F): the history with fbar is the one without it, beyond yield, to 1e-9
    of each column's largest value (the interior nodes are Newton's solutions, each to its tolerance)."""
    def run(fbar):
        md = punch.mesh(4, "none")
        body = Body(md, "plane_strain", cm.J2(E, NU, cm.Hardening.linear(math.sqrt(3.0), 50.0)),
                    update=update, degree=1, fbar=fbar)
        g = np.array([[0.004, 0.003], [-0.001, -0.006]])
        items = [cm.Displacement(name, field=lambda x, t: t * (g @ x[:2]))
                 for name in ("sym", "bottom", "right", "punch", "top")]
        res = cm.Job(body, items, [cm.Step(4)], probes=[cm.Reaction("bottom", "b"), cm.MaxPlasticStrain()],
                     writers=[]).run()
        assert res.completed, res.message
        return res
    plain, averaged = run(False), run(True)
    assert plain["max_plastic_strain"][-1] > 0.0
    for col in ("b_fx", "b_fy", "max_plastic_strain"):
        ref = np.asarray(plain[col])
        np.testing.assert_allclose(averaged[col], ref, rtol=0, atol=1e-9 * np.abs(ref).max(), err_msg=col)


# -- the flat punch -----------------------------------------------------------------------------------------
def test_q1_locks_in_the_punch_and_fbar_lifts_it():
    """Q1 quadrilaterals on 16 x 16 squares: the limit pressure comes out over 12 % above (2 + pi) k
    (15.7 %), and the job warns of locking, naming fbar. With fbar the error is below 5 % (4.0 %) and
    falls by more than 2.5 from 8 x 8 (11.6 %): Q1 with F-bar converges as P2 does."""
    _, p, res, _, _ = punch.press(16, 1, diagonal="none")
    assert p[-1] / punch.PRANDTL - 1.0 > 0.12, p[-1]
    said = [w for w in res.warnings if w.startswith("locking")]
    assert len(said) == 1 and "fbar=True" in said[0], res.warnings
    errors = []
    for n in (8, 16):
        _, p, res, _, _ = punch.press(n, 1, diagonal="none", fbar=True)
        errors.append(p[-1] / punch.PRANDTL - 1.0)
        assert not [w for w in res.warnings if w.startswith("locking")], res.warnings
    assert 0.0 < errors[1] < 0.05 and errors[1] < errors[0] / 2.5, errors


# -- refusals -------------------------------------------------------------------------------------------------
def test_where_fbar_does_not_apply_the_body_says_so(cache):
    """One line naming the value and the fix: plane stress, P1 triangles and tetrahedra, a value that
    is not True or False, and Nitsche contact (the job)."""
    law = cm.J2(E, NU, HARDENING)
    cases = [(punch.mesh(2, "none"), "plane_stress", 1, True, "plane stress does not lock"),
             (punch.mesh(2), "plane_strain", 1, True, "use degree=2"),
             (geometry.box(1.0, 0.5, 0.5, 0.5, cache_dir=cache), "solid", 1, True, "use degree=2"),
             (punch.mesh(2, "none"), "plane_strain", 1, "yes", "give True")]
    for md, kind, degree, fbar, fix in cases:
        with pytest.raises(BodyError, match=fix) as err:
            Body(md, kind, law, degree=degree, fbar=fbar)
        assert "\n" not in str(err.value)
    body = Body(punch.mesh(2, "none"), "plane_strain", law, degree=1, fbar=True)
    with pytest.raises(cm.JobError, match="method='penalty'"):
        cm.Job(body, [cm.Contact("punch", cm.Plane((0.0, 0.0), (0.0, -1.0)), method="nitsche")])


# -- ranks and restart -------------------------------------------------------------------------------------------
def _bent(folder, checkpoint=None, stop_after=None, comm=MPI.COMM_WORLD):
    """test_output3d's J2 block, on Q1 bricks with F-bar."""
    return _bent_block(folder, checkpoint, stop_after, comm, hexahedra=True, size=0.1, order=1, degree=1,
                       fbar=True)


COLUMNS = ("clamp_fx", "clamp_fy", "clamp_fz", "tip_ux", "tip_uy", "tip_uz", "max_plastic_strain")


def _same(res, ref, tol):
    assert res.completed and res.newton_its == ref.newton_its
    for col in COLUMNS:
        r = np.asarray(ref[col], float)
        np.testing.assert_allclose(res[col], r, rtol=0, atol=tol * np.abs(r).max(), err_msg=col)


@pytest.mark.mpi
def test_fbar_restarts_to_the_uninterrupted_history_and_ranks_agree(mpi_tmp):
    """Stopped after increment 3 and restarted from its checkpoint: the uninterrupted history and
    Newton iterations to 1e-12 (the mean dilatation of the converged state is recomputed from it);
    on two ranks, the serial run's history to 1e-9."""
    full = _bent(mpi_tmp).run()
    assert full.completed and full["max_plastic_strain"][-1] > 0.0
    folder = mpi_tmp / "checkpoint"
    with pytest.raises(RuntimeError, match="stopped by the test"):
        _bent(mpi_tmp, folder, stop_after=3).run()
    _same(_bent(mpi_tmp, folder).run(restart=folder), full, 1e-12)
    comm = MPI.COMM_WORLD
    if comm.size > 1:
        _same(_bent(mpi_tmp, comm=MPI.COMM_SELF).run(), full, 1e-9)

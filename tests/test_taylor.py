"""Taylor tests of the Jacobian: every residual term, at a deformed mid-increment state.

A block (1 x 0.5; axisymmetric: at radius 0.5 to 1.5) with a follower pressure on its right face and a
dead traction on its left face is pressed onto a rigid plane or circle by its top edge, which moves down
and sideways (without contact, its bottom edge is held); two converged increments build the history
(stress, plastic strain, friction), then the load goes on and one Newton correction gives the state
tested: not converged, points yielding, the contact set partly sticking and partly slipping as each
case asks. The remainder
|R(u + h w) - R(u) - h J w| must fall as h^2 (observed order close to 2 between the smallest steps);
a Jacobian that misses a dependence of the residual on u shows order 1. See comove_dolfinx.taylor.
"""
import numpy as np
import pytest
from mpi4py import MPI

from comove_dolfinx import compat, geometry
from comove_dolfinx.contact import Circle, Contact, Plane
from comove_dolfinx.materials import Elastic, Hardening
from comove_dolfinx.model import Model, Plasticity
from comove_dolfinx.solver import IncrementalSolver, StepSettings
from comove_dolfinx.taylor import taylor_test

HARDENING = Hardening((0.0, 0.05, 0.2), (15.0, 20.0, 22.0))     # yields at 1.5 % strain (E = 1000)
FRICTION = {"none": 0.0, "slip": 0.1, "stick": 5.0}


@pytest.fixture(scope="module")
def meshes(tmp_path_factory):
    cache = str(tmp_path_factory.mktemp("meshes"))
    return {x0: geometry.rectangle(1.0, 0.5, 0.25, order=2, x0=x0, comm=MPI.COMM_WORLD, cache_dir=cache)
            for x0 in (0.0, 0.5)}


def _state(meshes, kind="plane_strain", update="sr", law=None, method="penalty", theta=0,
           friction="slip", obstacle="plane", gamma0=10.0):
    """The model at the tested state, and its contact term (None without contact)."""
    x0 = 0.5 if kind == "axisymmetric" else 0.0
    plast = Plasticity(HARDENING, law) if law else None
    m = Model(meshes[x0], kind, Elastic(1000.0, 0.3), update=update, plasticity=plast)
    m.fix("top", value=(0.06, -0.06))
    m.follower_pressure("right", 5.0)
    m.dead_traction("left", (2.0, -1.0))
    c = None
    if not method:
        m.fix("bottom")                               # sheared between its top and bottom edges
    else:
        obs = Plane((0.0, 0.0), (0.0, 1.0)) if obstacle == "plane" else Circle((x0 + 0.5, -2.0), 2.0)
        c = Contact("bottom", obs, method=method, theta=theta, gamma0=gamma0, mu=FRICTION[friction])
        m.boundary_terms.append(c)
    m.finalize()
    solver = IncrementalSolver(m, StepSettings(n_steps=2, t_end=0.4))
    res = solver.run()
    assert res.completed, res.message
    m.set_load(0.6)                                  # the next increment: one Newton correction
    newton = solver.newton
    newton.residual()
    compat.assemble_matrix(newton.A, m.jacobian_form, m.bcs)
    assert newton._solve_linear() is None
    m.u.x.array[:] += m.du.x.array
    m.evaluate_stress()
    return m, c


def _check(m, c, law, method, friction):
    """The state holds what the case is about (else the test could pass vacuously)."""
    comm = m.comm
    if law:
        yielding = comm.allreduce(int(np.sum(m.p.x.array > m.p_n.x.array)), op=MPI.SUM)
        assert yielding > 0, "no point is yielding"
    if method:
        assert c.zone().in_contact
        stick, slip = c.stick_slip()
        if friction == "slip":
            assert slip > 0.2 * (stick + slip), (stick, slip)
        elif friction == "stick":
            assert slip == 0.0 and stick > 0.0, (stick, slip)


def _order(m):
    result = taylor_test(m, h0=1e-3, n=10)
    return result.orders, str(result)


def _assert_second_order(orders, text):
    # the last three orders: the largest steps may cross a switch (yield, contact, stick/slip) of
    # a point near it, where the residual is only piecewise smooth
    assert np.all(np.abs(orders[-3:] - 2.0) < 0.15), text


CASES = (
    # every stress update in every 2D model (elastic), frictionless penalty contact
    [dict(kind=k, update=u, friction="none") for k in ("plane_strain", "plane_stress", "axisymmetric")
     for u in ("sr", "hughes_winget", "polar", "svk", "neo_hooke")]
    # plasticity: both laws in every model (S-R update), and with Hughes-Winget
    + [dict(kind=k, law=law) for k in ("plane_strain", "plane_stress", "axisymmetric")
       for law in ("j2", "chen")]
    + [dict(update="hughes_winget", law=law) for law in ("j2", "chen")]
    # contact with plasticity: penalty and Nitsche (theta = 0) with each friction state, the other
    # Nitsche variants slipping, and the circle
    + [dict(law="j2", method=meth, theta=0, friction=f) for meth in ("penalty", "nitsche")
       for f in ("none", "slip", "stick")]
    + [dict(law="j2", method="nitsche", theta=th) for th in (1, -1)]
    + [dict(law="j2", method=meth, theta=th, obstacle="circle") for meth, th in
       (("penalty", 0), ("nitsche", -1))]
    # Nitsche's facet stress with both laws in the other models, and with the other updates
    + [dict(kind=k, law=law, method="nitsche", theta=0) for k in ("plane_stress", "axisymmetric")
       for law in ("j2", "chen")]
    + [dict(kind="plane_stress", update=u, method="nitsche", theta=-1, friction="none")
       for u in ("polar", "svk", "neo_hooke")]
    + [dict(method=None), dict(method=None, kind="plane_stress", law="j2")]
)


def _id(case):
    return "-".join("no_contact" if v is None else f"{v}" for v in case.values())


@pytest.mark.parametrize("case", CASES, ids=[_id(c) for c in CASES])
def test_jacobian_is_exact(meshes, case):
    case = dict(case)
    if case.get("method") == "nitsche" and case.get("theta") == 1:
        case["gamma0"] = 100.0                        # the symmetric variant needs a stiffer gamma
    m, c = _state(meshes, **case)
    _check(m, c, case.get("law"), case.get("method", "penalty"), case.get("friction", "slip"))
    _assert_second_order(*_order(m))


@pytest.mark.mpi
def test_jacobian_is_exact_on_two_ranks(meshes):
    """The same state distributed: the direction is drawn from global dof numbers, so the test is
    the serial one; plane-stress plasticity with Nitsche friction."""
    m, c = _state(meshes, kind="plane_stress", law="j2", method="nitsche", theta=0)
    _check(m, c, "j2", "nitsche", "slip")
    _assert_second_order(*_order(m))

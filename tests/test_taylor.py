"""Taylor tests of the Jacobian: every residual term, at a deformed mid-increment state.

A block (1 x 0.5; axisymmetric: at radius 0.5 to 1.5) with a follower pressure on its right face and a
dead traction on its left face is pressed onto a rigid plane, circle or rounded polyline (Profile) by
its top edge, which moves down and sideways, uniformly or along a displacement field (without contact,
its bottom edge is held), in some cases with a point load or a body force too; two converged
increments build the history (stress, plastic strain, friction), then the load goes on and one Newton
correction gives the state tested: not converged, points yielding, the contact set partly sticking
and partly slipping as each case asks. The remainder
|R(u + h w) - R(u) - h J w| must fall as h^2 (observed order close to 2 between the smallest steps);
a Jacobian that misses a dependence of the residual on u shows order 1. See comove_dolfinx.taylor.
"""
import numpy as np
import pytest
from mpi4py import MPI

from comove_dolfinx import geometry
from comove_dolfinx.contact import Circle, Contact, Plane, Profile
from comove_dolfinx.loads import BodyForce, Displacement, Fixed, PointLoad, Pressure, Traction
from comove_dolfinx.mechanics.body import Body
from comove_dolfinx.mechanics.material_data import Hardening
from comove_dolfinx.mechanics.materials import as_material
from comove_dolfinx.mechanics.model import Model
from comove_dolfinx.solver import IncrementalSolver, StepSettings
from comove_dolfinx.taylor import taylor_test
from states import one_correction_into

HARDENING = Hardening((0.0, 0.05, 0.2), (15.0, 20.0, 22.0))     # yields at 1.5 % strain (E = 1000)
# law "j2_saturation": J2 with sigma_y = 15 + 10 p + 10 (1 - exp(-20 p)), the Newton iteration of the
# return map (its slope at yield, 210, is of the order of G = 385)
SATURATION = Hardening.saturation(15.0, 10.0, 10.0, 20.0)
FRICTION = {"none": 0.0, "slip": 0.1, "stick": 5.0}


@pytest.fixture(scope="module")
def meshes(tmp_path_factory):
    cache = str(tmp_path_factory.mktemp("meshes"))
    return {x0: geometry.rectangle(1.0, 0.5, 0.25, order=2, x0=x0, comm=MPI.COMM_WORLD, cache_dir=cache)
            for x0 in (0.0, 0.5)}


def _obstacle(obstacle, x0):
    if obstacle == "plane":
        return Plane((0.0, 0.0), (0.0, 1.0))
    if obstacle == "circle":
        return Circle((x0 + 0.5, -2.0), 2.0)
    if obstacle == "arc":
        # the circle's arc as 7 chords rounded by 0.05 (as a sampled Gmsh curve): the contact set
        # spans several segments, chosen in the tree of Profile._nearest
        th = np.pi / 2 + np.linspace(-0.4, 0.4, 8)
        return Profile(np.c_[x0 + 0.5 + 1.95 * np.cos(th), -2.0 + 1.95 * np.sin(th)], 0.05)
    # a roof of two slopes (1 in 4) with its apex rounded to 0.2, touching the bottom edge at its
    # middle: the contact set crosses from one segment to the other over the arc
    return Profile([(x0 + 0.1, -0.3), (x0 + 0.5, -0.2), (x0 + 0.9, -0.3)], 0.2)


def _top(x0, load):
    """The top edge's motion: down and sideways, uniformly, or (load = "field") along a field that
    also tilts the edge."""
    if load != "field":
        return Displacement("top", (0.06, -0.06))

    def field(x, t):
        return np.vstack([np.full_like(x[0], 0.06 * t), -0.06 * t * (1.0 + 0.5 * (x[0] - x0))])
    return Displacement("top", field=field)


def _state(meshes, kind="plane_strain", update="sr", law=None, method="penalty", theta=0,
           friction="slip", obstacle="plane", gamma0=10.0, load=None, compiled=True,
           friction_law="lagged", gamma0_t=None):
    """The model at the tested state, and its contact term (None without contact). ``load``: an
    extra item, "point" (a point load at a node of the right face), "body" (a body force), or
    "field" (the top edge's motion as a displacement field). ``compiled``: the return map in the
    generated stress evaluation (True, the model's default) or in NumPy (False). ``friction_law``:
    the threshold from the last increment's pressure ("lagged", the default) or from the current
    one ("coulomb", whose derivative the Jacobian carries)."""
    x0 = 0.5 if kind == "axisymmetric" else 0.0
    material = (as_material(1000.0, 0.3, "j2", SATURATION) if law == "j2_saturation"
                else as_material(1000.0, 0.3, law, HARDENING))
    items = [_top(x0, load), Pressure("right", 5.0), Traction("left", (2.0, -1.0))]
    if load == "point":
        items.append(PointLoad((x0 + 1.0, 0.25), (-1.0, -2.0)))
    elif load == "body":
        items.append(BodyForce((2.0, -10.0)))
    c = None
    if not method:
        items.append(Fixed("bottom"))                 # sheared between its top and bottom edges
    else:
        c = Contact("bottom", _obstacle(obstacle, x0), method=method, theta=theta, gamma0=gamma0,
                    mu=FRICTION[friction], friction=friction_law, gamma0_t=gamma0_t)
        items.append(c)
    m = Model(Body(meshes[x0], kind, material, update=update), items)
    m.finalize(compiled_return=compiled)
    one_correction_into(m)
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


def _order(m, h0=1e-4, n=10):
    # steps from 1e-4 of the largest displacement: a friction point that slipped in the last
    # increment starts the next one at its threshold |trial| = s, and a correction that hardly
    # moves it along the obstacle leaves it there; the larger the steps, the likelier one crosses
    # it (from 1e-3, one such point of the Hughes-Winget/Chen state was crossed between h = 2e-6
    # and 8e-6: orders near 1 above it, 2 below)
    result = taylor_test(m, h0=h0, n=n)
    return result.orders, str(result)


def _assert_second_order(orders, text):
    # the last three orders: the largest steps may cross a switch (yield, contact, stick/slip) of
    # a point near it, where the residual is only piecewise smooth
    assert np.all(np.abs(orders[-3:] - 2.0) < 0.15), text


CASES = (
    # every stress update in every 2D model (elastic), frictionless penalty contact
    [dict(kind=k, update=u, friction="none") for k in ("plane_strain", "plane_stress", "axisymmetric")
     for u in ("sr", "sr_log", "hughes_winget", "polar", "svk", "neo_hooke")]
    # plasticity: both laws in every model (S-R update), and with Hughes-Winget
    + [dict(kind=k, law=law) for k in ("plane_strain", "plane_stress", "axisymmetric")
       for law in ("j2", "chen")]
    # the S-R update with logarithmic increments: its closed-form derivative with plasticity in every
    # model, and under Nitsche's facet stress with slip
    + [dict(kind=k, update="sr_log", law="j2") for k in ("plane_strain", "plane_stress", "axisymmetric")]
    + [dict(update="sr_log", law="chen"), dict(update="sr_log", law="j2", method="nitsche", theta=0)]
    + [dict(update="hughes_winget", law=law) for law in ("j2", "chen")]
    # the same laws' NumPy return map (finalize(compiled_return=False))
    + [dict(kind=k, law=law, compiled=False) for k, law in
       (("plane_strain", "j2"), ("plane_strain", "chen"), ("axisymmetric", "j2"))]
    # contact with plasticity: penalty and Nitsche (theta = 0) with each friction state and both
    # friction laws (lagged, the default, and coulomb), the other Nitsche variants slipping, and
    # the circle (whose normal, and so the slip direction t_o, turns with x: its derivative)
    + [dict(law="j2", method=meth, theta=0, friction=f) for meth in ("penalty", "nitsche")
       for f in ("none", "slip", "stick")]
    + [dict(law="j2", method=meth, theta=0, friction=f, friction_law="coulomb")
       for meth in ("penalty", "nitsche") for f in ("slip", "stick")]
    + [dict(method=meth, theta=0, friction="slip", obstacle="circle", friction_law="coulomb")
       for meth in ("penalty", "nitsche")]
    + [dict(law="j2", method="nitsche", theta=th) for th in (1, -1)]
    + [dict(law="j2", method=meth, theta=th, obstacle="circle") for meth, th in
       (("penalty", 0), ("nitsche", -1))]
    # Nitsche's facet stress with both laws in the other models, and with the other updates
    # the facet return maps: J2 and Chen in plane stress (their own branch), J2 in axisymmetry
    + [dict(kind=k, law=law, method="nitsche", theta=0) for k, law in
       (("plane_stress", "j2"), ("plane_stress", "chen"), ("axisymmetric", "j2"))]
    + [dict(kind="plane_stress", update=u, method="nitsche", theta=-1, friction="none")
       for u in ("polar", "svk", "neo_hooke")]
    + [dict(method=None), dict(method=None, kind="plane_stress", law="j2")]
    # linear kinematics (small_strain): its internal force is linear in u (elastic) and its loads
    # dead, so the elastic cases take Nitsche's terms against the circle with friction, which keep the
    # residual nonlinear, and a Jacobian that missed a part of the linear terms would show order 1
    # (steps from 1e-2: the remainder of this mild nonlinearity meets round-off, 2e-12, below 2e-6);
    # the plastic ones the return map (J2 in every model, Chen; Nitsche's facet return in plane stress)
    + [dict(kind=k, update="small_strain", method="nitsche", theta=-1, obstacle="circle", h0=1e-2)
       for k in ("plane_strain", "plane_stress", "axisymmetric")]
    + [dict(kind=k, update="small_strain", law="j2")
       for k in ("plane_strain", "plane_stress", "axisymmetric")]
    + [dict(update="small_strain", law="chen"),
       dict(kind="plane_stress", update="small_strain", law="j2", method="nitsche", theta=0)]
    # the saturation law (Newton on the return's plastic strain): compiled, NumPy, plane stress's
    # return, and the facet return maps of Nitsche's term in axisymmetry and plane stress
    + [dict(kind=k, law="j2_saturation", compiled=comp) for k, comp in
       (("axisymmetric", True), ("axisymmetric", False), ("plane_stress", True))]
    + [dict(kind=k, law="j2_saturation", method="nitsche", theta=0) for k in ("axisymmetric", "plane_stress")]
)


def _id(case):
    return "-".join("no_contact" if v is None else f"{v}" for v in case.values())


@pytest.mark.parametrize("case", CASES, ids=[_id(c) for c in CASES])
def test_jacobian_is_exact(meshes, case):
    case = dict(case)
    if case.get("method") == "nitsche" and case.get("theta") == 1:
        case["gamma0"] = 100.0                        # the symmetric variant needs a stiffer gamma
    steps = dict(h0=case.pop("h0"), n=8) if "h0" in case else {}
    m, c = _state(meshes, **case)
    _check(m, c, case.get("law"), case.get("method", "penalty"), case.get("friction", "slip"))
    _assert_second_order(*_order(m, **steps))


@pytest.mark.parametrize("kind", ["plane_strain", "plane_stress", "axisymmetric"])
def test_small_strain_elastic_residual_is_affine(meshes, kind):
    """Linear kinematics, elastic, without contact (the top edge's motion, a pressure, a traction, a
    body force): the residual is affine in u, so with the exact Jacobian the Taylor remainder is
    round-off at every step, where a Jacobian off by a part of the stiffness leaves h |dJ w|."""
    x0 = 0.5 if kind == "axisymmetric" else 0.0
    m = Model(Body(meshes[x0], kind, as_material(1000.0, 0.3), update="small_strain"),
              [_top(x0, None), Pressure("right", 5.0), Traction("left", (2.0, -1.0)),
               BodyForce((2.0, -10.0)), Fixed("bottom")])
    m.finalize()
    assert IncrementalSolver(m, StepSettings(n_increments=2, t_end=0.4)).run().completed
    m.set_load(0.6)
    m.u.x.array[:] *= 1.5                            # off equilibrium: R(u) is not 0
    result = taylor_test(m, h0=1e-1, n=6)
    assert np.all(result.remainders < 1e-11 * result.first_order), str(result)


# every other kind of item: a point load, a body force, a displacement field (with plasticity and
# penalty contact), and contact with a rounded polyline (penalty; the Nitsche terms are the same
# functions of the obstacle's gap and normal as with the plane and circle cases above, and cost 15 s
# of compilation on a cold cache)
ITEM_CASES = (
    [dict(law="j2", load=load) for load in ("point", "body", "field")]
    + [dict(law="j2", method="penalty", theta=0, obstacle=o) for o in ("profile", "arc")]
)


@pytest.mark.parametrize("case", ITEM_CASES, ids=[_id(c) for c in ITEM_CASES])
def test_jacobian_is_exact_with_every_item(meshes, case):
    m, c = _state(meshes, **case)
    _check(m, c, case.get("law"), case.get("method", "penalty"), case.get("friction", "slip"))
    _assert_second_order(*_order(m))


@pytest.mark.mpi
def test_jacobian_is_exact_on_two_ranks(meshes):
    """The same state distributed: the direction is drawn from global dof numbers, so the test is
    the serial one; plane-stress plasticity with Nitsche friction. On two ranks the direct solver's
    round-off differs from run to run (1e-16), which moves the state built by the two increments
    (points just at the yield surface take the elastic or the plastic tangent), so that in about
    one run in three one of the larger steps of the last three crosses a yield switch (an order
    far from 2, e.g. 9.9). A Jacobian that misses a dependence gives order 1 at the smallest
    steps, whatever the state: the two smallest must show 2."""
    m, c = _state(meshes, kind="plane_stress", law="j2", method="nitsche", theta=0)
    _check(m, c, "j2", "nitsche", "slip")
    orders, text = _order(m)
    assert np.all(np.abs(orders[-2:] - 2.0) < 0.15), text

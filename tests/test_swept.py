"""Rigid 3D obstacles swept from a 2D profile (Extruded, Revolved): their gap against closed-form
distances, the UFL gap against the NumPy one and the normal against the gap's gradient, Taylor
tests of the contact terms with each of them (friction slipping), the same force history as the
Plane and the Sphere they coincide with, two ranks, and the refusals.

* Closed forms: a point extruded is a cylinder; a point (R, z0) revolved is a torus, (0, z0) a
  sphere; a segment parallel to the axis revolved is a cylinder beside it; an extruded polyline's
  gap is the 2D profile's gap of the point's projection onto its plane.
* The normal is the gap's gradient (the gap is a distance function outside the obstacle).
"""
import numpy as np
import pytest
import ufl
from mpi4py import MPI

import comove_dolfinx as cm
from comove_dolfinx import compat
from comove_dolfinx.contact import ContactError, Cylinder, Extruded, Plane, Profile, Revolved, Sphere
from comove_dolfinx.taylor import taylor_test
from states import pressed_block

D = np.array([0.1, -0.2, 0.3])                   # the obstacles' displacement in the checks
ORIGIN = np.array([0.2, 0.1, -0.3])
TILTED = np.array([1.0, 2.0, 2.0]) / 3.0          # an oblique axis


@pytest.fixture(scope="module")
def cache(tmp_path_factory):
    return str(MPI.COMM_WORLD.bcast(str(tmp_path_factory.mktemp("meshes")), root=0))


@pytest.fixture(scope="module")
def cube():
    from dolfinx import mesh
    return mesh.create_box(MPI.COMM_SELF, [np.array([-2.0, -2.0, -2.0]), np.array([2.0, 2.0, 2.0])],
                           [3, 3, 3], mesh.CellType.tetrahedron)


def _ufl_values(obstacle, msh):
    """Points x of the mesh (7 per cell) with the obstacle's UFL gap and normal there, at D."""
    x = ufl.SpatialCoordinate(msh)
    obstacle.bind(msh)
    obstacle.d.value = D
    n = obstacle.normal(x)
    expr = ufl.as_vector([x[0], x[1], x[2], obstacle.gap(x), n[0], n[1], n[2]])
    ref = np.array([[0.25, 0.25, 0.25], [0.1, 0.2, 0.3], [0.6, 0.1, 0.1], [0.1, 0.7, 0.1],
                    [0.2, 0.1, 0.6], [0.05, 0.05, 0.05], [0.3, 0.3, 0.05]])
    cells = np.arange(msh.topology.index_map(3).size_local, dtype=np.int32)
    vals = compat.evaluate(compat.expression(expr, ref), msh, cells).reshape(-1, 7)
    return vals[:, :3], vals[:, 3], vals[:, 4:]


def _torus(x, R, z0, rho):
    rel = x - ORIGIN - D
    z = rel @ TILTED
    r = np.linalg.norm(rel - np.outer(z, TILTED), axis=1)
    return np.hypot(r - R, z - z0) - rho


CLOSED = {
    "extruded point = cylinder": (
        lambda: Extruded(Profile([(0.3, -0.2)], 0.7), origin=ORIGIN),
        lambda x: Cylinder(ORIGIN + (0.3, 0.0, -0.2), (0, 1, 0), 0.7).gap_np(x, D)),
    "tilted extruded point = cylinder": (
        lambda: Extruded(Profile([(0.3, -0.2)], 0.7), u=(0, 0, 2), v=(1, 1, 0), origin=ORIGIN),
        lambda x: Cylinder(ORIGIN + (0.3 * np.array([0, 0, 1]) - 0.2 * np.array([1, 1, 0]) / np.sqrt(2)),
                           (1, -1, 0), 0.7).gap_np(x, D)),
    "revolved point off the axis = torus": (
        lambda: Revolved(Profile([(1.2, 0.3)], 0.4), axis=2 * TILTED, origin=ORIGIN),
        lambda x: _torus(x, 1.2, 0.3, 0.4)),
    "revolved point on the axis = sphere": (
        lambda: Revolved(Profile([(0.0, 0.3)], 0.9), axis=TILTED, origin=ORIGIN),
        lambda x: Sphere(ORIGIN + 0.3 * TILTED, 0.9).gap_np(x, D)),
}


@pytest.mark.parametrize("case", CLOSED)
def test_the_gap_is_the_closed_form_distance(cube, case):
    """gap_np and the UFL gap equal the closed form (to round-off), and the UFL normal is the
    unit gradient of the gap (central differences of gap_np)."""
    make, exact = CLOSED[case]
    obstacle = make()
    x, g, n = _ufl_values(obstacle, cube)
    np.testing.assert_allclose(g, exact(x), atol=1e-12)
    np.testing.assert_allclose(obstacle.gap_np(x, D), exact(x), atol=1e-12)
    h = 1e-6
    grad = np.stack([(obstacle.gap_np(x + h * e, D) - obstacle.gap_np(x - h * e, D)) / (2 * h)
                     for e in np.eye(3)], axis=1)
    np.testing.assert_allclose(n, grad, atol=1e-7)


def test_a_segment_revolved_beside_its_axis_is_a_cylinder(cube):
    """The segment (R, z1)-(R, z2) revolved: beside the segment (z1 < z < z2) and outside, the gap
    is the distance from the axis minus R + rho, the Cylinder's; beyond its ends the rounded rim
    (a torus of the end point)."""
    R, z1, z2, rho = 0.8, -1.0, 0.5, 0.3
    obstacle = Revolved(Profile([(R, z1), (R, z2)], rho), axis=TILTED, origin=ORIGIN)
    x, g, _ = _ufl_values(obstacle, cube)
    rel = x - ORIGIN - D
    z = rel @ TILTED
    r = np.linalg.norm(rel - np.outer(z, TILTED), axis=1)
    beside, above = (z > z1) & (z < z2) & (r > R), z > z2
    assert beside.sum() > 20 and above.sum() > 20
    cyl = Cylinder(ORIGIN, TILTED, R + rho).gap_np(x, D)
    np.testing.assert_allclose(g[beside], cyl[beside], atol=1e-12)
    np.testing.assert_allclose(g[above], _torus(x, R, z2, rho)[above], atol=1e-12)
    np.testing.assert_allclose(obstacle.gap_np(x, D), g, atol=1e-12)


def test_an_extruded_polyline_is_the_profile_of_the_projection(cube):
    """A roof of three segments with rounded corners, drawn in the (x, z) plane: the extruded
    gap of x is the 2D profile's gap of (x, z) - origin, whatever y."""
    prof = Profile([(-1.0, -0.5), (0.0, 0.2), (0.7, 0.1), (1.5, -0.8)], 0.25)
    obstacle = Extruded(prof, origin=ORIGIN)
    x, g, n = _ufl_values(obstacle, cube)
    q = (x - ORIGIN - D)[:, [0, 2]]
    np.testing.assert_allclose(g, prof.gap_np(q, np.zeros(2)), atol=1e-12)
    np.testing.assert_allclose(obstacle.gap_np(x, D), g, atol=1e-12)
    np.testing.assert_allclose(n[:, 1], 0.0, atol=1e-14)                 # square to the axis y
    np.testing.assert_allclose(np.linalg.norm(n, axis=1), 1.0, atol=1e-12)


# -- Taylor tests ------------------------------------------------------------------------------------
def _obstacle(kind):
    """Below the block (1 x 0.5 x 0.5) of the Taylor tests, touching its bottom's middle at z = 0:
    a roof of slopes 1 in 4 with its apex rounded to 0.2, extruded along y (the contact set
    crosses from one slope to the other over the rounded apex), or a cone revolved about the
    vertical through the bottom's centre (a node of the mesh), its apex rounded to 0.2."""
    if kind == "extruded":
        return Extruded(Profile([(0.1, -0.3), (0.5, -0.2), (0.9, -0.3)], 0.2))
    return Revolved(Profile([(0.0, -0.2), (0.6, -0.35)], 0.2), axis=(0, 0, 1), origin=(0.5, 0.25, 0.0))


def _state(cache, obstacle, method, mu=0.1):
    """tests/states.py's pressed block on ``obstacle`` (a name of _obstacle), slipping."""
    m, c = pressed_block(cache, _obstacle(obstacle), method=method, mu=mu)
    stick, slip = c.stick_slip()
    assert slip > 0.2 * (stick + slip), (stick, slip)
    return m


@pytest.mark.parametrize("obstacle, method", [("extruded", "penalty"), ("extruded", "nitsche"),
                                              ("revolved", "penalty"), ("revolved", "nitsche")])
def test_jacobian_of_the_contact_terms_with_a_swept_obstacle_is_exact(cache, obstacle, method):
    result = taylor_test(_state(cache, obstacle, method), h0=1e-4, n=10)
    assert np.all(np.abs(result.orders[-3:] - 2.0) < 0.15), str(result)


# -- the same as the Plane and the Sphere where they coincide ----------------------------------------
MU, DEPTH, DRAG = 0.3, 0.01, (0.03, 0.04)


def _slide(cache, obstacle, method="penalty", comm=MPI.COMM_WORLD):
    """A block (1 x 1 x 0.5, its top held) on an obstacle that rises by DEPTH in 2 increments,
    then slides by DRAG (x, y) in 3; the history of the obstacle's force on the block."""
    md = cm.box(1.0, 1.0, 0.5, 0.25, order=1, comm=comm, cache_dir=cache)
    body = cm.Body(md, "solid", cm.Elastic(1000.0, 0.3), degree=1)
    c = cm.Contact("bottom", obstacle, method=method, mu=MU)
    steps = [cm.Step(2, ramp={c: 1.0}), cm.Step(3, ramp={c: 2.0})]
    res = cm.Job(body, [cm.Fixed("top"), c], steps, [cm.ContactForce(c, "f", component=None)]).run()
    assert res.completed, res.message
    return res


def _motion(f):
    return DRAG[0] * max(f - 1.0, 0.0), DRAG[1] * max(f - 1.0, 0.0), DEPTH * min(f, 1.0)


def test_an_extruded_flat_punch_is_the_plane():
    """A flat face 20 wide, its edges rounded to 0.1, its top at z = 0 under the whole block:
    the same force history as the plane z = 0 with friction slipping, to round-off."""
    flat = Extruded(Profile([(-10.0, -0.1), (10.0, -0.1)], 0.1), motion=_motion)
    plane = Plane((0.0, 0.0, 0.0), (0.0, 0.0, 1.0), motion=_motion)
    _compare(flat, plane)


def test_a_revolved_circle_is_the_sphere():
    """The point (0, -2) of radius 2 revolved about the vertical through the block's centre is the
    sphere of radius 2 touching the block there: the same force history as Sphere, Nitsche with
    friction slipping, the axis through a node of the contact face."""
    axis_point = (0.5, 0.5, 0.0)
    rev = Revolved(Profile([(0.0, -2.0)], 2.0), origin=axis_point, motion=_motion)
    ball = Sphere((0.5, 0.5, -2.0), 2.0, motion=_motion)
    _compare(rev, ball, "nitsche")


_CACHE = {}


def _compare(obstacle, reference, method="penalty"):
    import tempfile
    cache = _CACHE.setdefault("dir", MPI.COMM_WORLD.bcast(tempfile.mkdtemp(), root=0))
    a, b = _slide(cache, obstacle, method), _slide(cache, reference, method)
    assert abs(b["f_fz"][-1]) > 1.0 and np.hypot(b["f_fx"][-1], b["f_fy"][-1]) > 0.1 * abs(b["f_fz"][-1])
    np.testing.assert_array_equal(a.newton_its, b.newton_its)
    for col in ("f_fx", "f_fy", "f_fz"):
        np.testing.assert_allclose(a[col], b[col], rtol=1e-9, atol=1e-10 * abs(b["f_fz"][-1]), err_msg=col)


@pytest.mark.mpi
def test_a_revolved_obstacle_on_two_ranks_is_the_serial_one(cache):
    """The sliding job with a revolved rounded cone distributed over the ranks and, on every rank,
    on its own (COMM_SELF)."""
    def make():
        return Revolved(Profile([(0.0, -0.2), (1.0, -0.45)], 0.2), origin=(0.5, 0.5, 0.0), motion=_motion)
    par = _slide(cache, make(), "nitsche")
    ser = _slide(cache, make(), "nitsche", comm=MPI.COMM_SELF)
    np.testing.assert_array_equal(par.newton_its, ser.newton_its)
    for col in ("f_fx", "f_fy", "f_fz"):
        np.testing.assert_allclose(par[col], ser[col], rtol=1e-7, atol=1e-9, err_msg=col)


# -- refusals ----------------------------------------------------------------------------------------
REFUSED = [
    (lambda: Extruded([(0, 0), (1, 0)]), r"profile = \[\(0, 0\), \(1, 0\)\]: give a Profile"),
    (lambda: Revolved(Profile([(0, 0)], 0.1, motion=(0, 1))), "the Revolved's profile has a motion: give "
                                                              r"motion=\(dx, dy, dz\) to the Revolved"),
    (lambda: Extruded(Profile([(0, 0)], 0.1), u=(1, 0, 0), v=(2, 0, 0)),
     r"v = \(2, 0, 0\) is parallel to u = \(1, 0, 0\)"),
    (lambda: Extruded(Profile([(0, 0)], 0.1), u=(0, 0)), r"the profile's x direction u = \(0, 0\): give 3"),
    (lambda: Extruded(Profile([(0, 0)], 0.1), origin=(0, 0)), r"the Extruded's origin = \(0, 0\): give 3"),
    (lambda: Revolved(Profile([(0, 0)], 0.1), axis=(0, 0, 0)), r"the axis = \(0, 0, 0\) must not be zero"),
    (lambda: Revolved(Profile([(0.5, 0), (-0.1, 1)], 0.1)), r"point \(-0.1, 1\) has x < 0: its x is the "
                                                             "distance from the axis"),
    (lambda: Revolved(Profile([(0.5, 0)], 0.1), motion=(0, 1)), r"motion = \(0, 1\): give 3 finite numbers"),
]


@pytest.mark.parametrize("make, words", REFUSED)
def test_bad_swept_obstacles_are_refused_in_one_line(make, words):
    with pytest.raises(ContactError, match=words) as err:
        make()
    assert "\n" not in str(err.value)


def test_a_swept_obstacle_is_3d(cache):
    """Its dimension is 3, and a 2D body refuses it in one line naming the 2D obstacles."""
    assert Extruded(Profile([(0, 0)], 0.1)).dim == 3 and Revolved(Profile([(0, 0)], 0.1)).dim == 3
    md = cm.rectangle(1.0, 0.5, 0.25, order=1, cache_dir=cache)
    body = cm.Body(md, "plane_strain", cm.Elastic(1000.0, 0.3), degree=1)
    c = cm.Contact("bottom", Revolved(Profile([(0, -1)], 1.0)))
    with pytest.raises(ContactError, match="the obstacle Revolved is 3D, the body 2D: give a 2D obstacle"):
        cm.Job(body, [cm.Fixed("top"), c], [cm.Step(1)]).run()

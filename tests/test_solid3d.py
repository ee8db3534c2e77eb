"""The 3D model "solid": Taylor tests of its residual terms, objectivity of the S-R update under a
rigid rotation about an oblique axis, the plane-strain limit against the 2D body, uniaxial tension
and simple shear against closed forms (docs/theory.md sections 3.2, 3.4 and 7)."""
import numpy as np
import pytest
from mpi4py import MPI

from comove_dolfinx import compat, geometry
from comove_dolfinx.loads import BodyForce, Displacement, Fixed, PointLoad, Pressure, Traction
from comove_dolfinx.mechanics.body import Body, BodyError
from comove_dolfinx.mechanics.material_data import Elastic, Hardening
from comove_dolfinx.mechanics.materials import J2, as_material
from comove_dolfinx.mechanics.model import Model
from comove_dolfinx.probes import NodeDisplacement, ProbeError
from comove_dolfinx.solver import IncrementalSolver, NewtonSettings, StepSettings
from comove_dolfinx.taylor import taylor_test
from states import one_correction_into

HARDENING = Hardening((0.0, 0.05, 0.2), (15.0, 20.0, 22.0))     # yields at 1.5 % strain (E = 1000)
SATURATION = Hardening.saturation(15.0, 10.0, 10.0, 20.0)


@pytest.fixture(scope="module")
def cache(tmp_path_factory):
    return str(tmp_path_factory.mktemp("meshes3d"))


def _tensor(v):
    """Stored 6-vectors (xx, yy, zz, xy, yz, xz) -> symmetric 3x3 tensors."""
    xx, yy, zz, xy, yz, xz = v.T
    return np.stack([np.stack([xx, xy, xz], -1), np.stack([xy, yy, yz], -1), np.stack([xz, yz, zz], -1)], -2)


def _rotation(axis, angle):
    n = np.asarray(axis, float) / np.linalg.norm(axis)
    K = np.array([[0, -n[2], n[1]], [n[2], 0, -n[0]], [-n[1], n[0], 0]])
    return np.eye(3) + np.sin(angle) * K + (1 - np.cos(angle)) * K @ K


def _homogeneous(F_of_t):
    """Displacement items holding every face of the box at u = (F(t) - I) X."""
    def field(x, t):
        return (F_of_t(t) - np.eye(3)) @ x
    return [Displacement(face, field=field) for face in ("left", "right", "front", "back", "bottom", "top")]


# -- mesh and input ----------------------------------------------------------------------------------
def test_box_faces(cache):
    md = geometry.box(1.0, 0.5, 0.25, 0.25, cache_dir=cache)
    from dolfinx import mesh as dmesh
    assert md.mesh.topology.dim == 3 and compat.cell_name(md.mesh) == "tetrahedron"
    where = {"left": (0, 0.0), "right": (0, 1.0), "front": (1, 0.0), "back": (1, 0.5), "bottom": (2, 0.0),
             "top": (2, 0.25)}
    for name, (axis, value) in where.items():
        f = md.facet_tags.indices[md.facet_tags.values == md.tags[name]]
        mid = dmesh.compute_midpoints(md.mesh, 2, f)
        assert len(f) > 0 and np.allclose(mid[:, axis], value), name


def test_solid_needs_a_3d_mesh(cache):
    with pytest.raises(BodyError, match="kind = 'solid' on a mesh of dimension 2"):
        Body(geometry.rectangle(1.0, 0.5, 0.25, cache_dir=cache), "solid", Elastic(1.0, 0.3))
    with pytest.raises(BodyError, match="kind = 'plane_strain' on a mesh of dimension 3"):
        Body(geometry.box(1.0, 0.5, 0.25, 0.25, cache_dir=cache), "plane_strain", Elastic(1.0, 0.3))
    with pytest.raises(ProbeError, match="component = 2 needs a 3D point"):
        NodeDisplacement("tip", (1.0, 0.0), component=2)


def test_a_2d_obstacle_with_a_3d_body_is_refused_in_one_line(cache):
    """A 3D job whose contact item has a 2D obstacle (a plane of 2-vectors) stops with the project's
    error naming the dimensions and the fix, before any increment."""
    import comove_dolfinx as cm
    from comove_dolfinx.contact.obstacles import ContactError
    md = geometry.box(1.0, 0.5, 0.25, 0.25, order=1, cache_dir=cache)
    body = Body(md, "solid", Elastic(1.0, 0.3), degree=1)
    contact = cm.Contact("bottom", cm.Plane((0.0, -1.0), (0.0, 1.0)))
    with pytest.raises(ContactError, match="the obstacle Plane is 2D, the body 3D: give a 3D obstacle"):
        cm.Job(body, [Fixed("left"), contact], [cm.Step(1)]).run()


# -- Taylor tests ------------------------------------------------------------------------------------
def _state(cache, update="sr_log", law=None, extra=None):
    """A block sheared and compressed between its bottom (held) and its top (moved), with a follower
    pressure on one face, a dead traction on another, and a body force or a point load: two converged
    increments, then one Newton correction into the next."""
    md = geometry.box(1.0, 0.5, 0.5, 0.25, cache_dir=cache)
    material = (as_material(1000.0, 0.3, "j2", SATURATION) if law == "j2_saturation"
                else as_material(1000.0, 0.3, law, HARDENING))
    items = [Fixed("bottom"), Displacement("top", (0.06, 0.03, -0.06)), Pressure("right", 5.0),
             Traction("left", (2.0, -1.0, 0.5))]
    if extra == "body":
        items.append(BodyForce((2.0, -10.0, 3.0)))
    elif extra == "point":
        items.append(PointLoad((1.0, 0.5, 0.25), (-1.0, -2.0, 1.0)))
    m = Model(Body(md, "solid", material, update=update), items)
    m.finalize()
    one_correction_into(m)
    return m


TAYLOR = ([dict(update=u) for u in ("sr", "sr_log", "hughes_winget", "polar", "svk", "neo_hooke",
                                    "small_strain")]
          + [dict(update=u, law="j2") for u in ("sr", "sr_log", "hughes_winget", "small_strain")]
          + [dict(update="sr_log", law="chen", extra="body"), dict(update="sr_log", law="j2_saturation"),
             dict(update="sr_log", extra="point")])


@pytest.mark.parametrize("case", TAYLOR, ids=["-".join(map(str, c.values())) for c in TAYLOR])
def test_jacobian_is_exact_3d(cache, case):
    m = _state(cache, **case)
    if case.get("law"):
        yielding = m.comm.allreduce(int(np.sum(m.p.x.array > m.p_n.x.array)), op=MPI.SUM)
        assert yielding > 0, "no point is yielding"
    result = taylor_test(m, h0=1e-4, n=8)
    if case == {"update": "small_strain"}:
        # linear kinematics, elastic, dead loads: the residual is linear in u, the remainder is
        # round-off from the first step on (a Jacobian missing a part would leave it at O(h))
        assert result.remainders.max() < 1e-10 * result.first_order.max(), str(result)
        return
    assert np.all(np.abs(result.orders[-3:] - 2.0) < 0.15), str(result)


# -- objectivity ------------------------------------------------------------------------------------
F0 = np.array([[1.02, 0.01, 0.0], [0.0, 0.99, 0.005], [0.003, 0.0, 1.0]])
AXIS = np.array([1.0, 2.0, 3.0])


@pytest.mark.parametrize("update,law", [("sr", None), ("sr_log", None), ("sr_log", "j2")])
def test_rigid_rotation_rotates_the_stress(cache, update, law):
    """A block deformed homogeneously by F0 (4 increments; beyond yield for J2), then turned rigidly by
    90 degrees about the oblique axis (1, 2, 3) in 4 increments: every S-R increment is a rotation,
    split exactly (dS = 0), so the stress is the pre-stress turned with the block."""
    md = geometry.box(1.0, 1.0, 1.0, 0.5, cache_dir=cache)
    material = Elastic(1000.0, 0.3) if law is None else J2(1000.0, 0.3, Hardening.linear(8.0, 100.0))

    def F(t):
        return np.eye(3) + t * (F0 - np.eye(3)) if t <= 1.0 else _rotation(AXIS, (t - 1.0) * np.pi / 2) @ F0
    m = Model(Body(md, "solid", material, update=update), _homogeneous(F))
    m.finalize()
    before = {}

    def keep(model, inc):
        if abs(inc.load - 1.0) < 1e-12:
            before["sigma"] = _tensor(model.cauchy_stress().copy())
            before["p"] = None if law is None else model.p.x.array.copy()
    # Newton to round-off: the points on the yield surface switch between the elastic and the
    # plastic tangent from iterate to iterate (q_tr = sigma_y to round-off), which slows it down
    newton = NewtonSettings(rtol=1e-13, atol=1e-13)
    res = IncrementalSolver(m, StepSettings(n_increments=8, t_end=2.0), newton).run([keep])
    assert res.completed and len(res.increments) == 8, res.message
    s0 = before["sigma"]
    assert np.abs(s0).max() > 1.0 and (law is None or before["p"].max() > 1e-3)
    Q = _rotation(AXIS, np.pi / 2)
    expected = Q @ s0 @ Q.T
    err = np.abs(_tensor(m.cauchy_stress()) - expected).max() / np.abs(s0).max()
    assert err < 1e-8, err
    if law is not None:
        assert np.allclose(m.p.x.array, before["p"], rtol=0, atol=1e-12)


# -- uniaxial tension -------------------------------------------------------------------------------
def _bar(cache, material, update, n=4, stretch=1.2):
    md = geometry.box(1.0, 0.25, 0.25, 0.125, cache_dir=cache)
    items = [Fixed("left", 0), Fixed("front", 1), Fixed("bottom", 2),
             Displacement("right", stretch - 1.0, component=0)]
    m = Model(Body(md, "solid", material, update=update), items)
    m.finalize()
    res = IncrementalSolver(m, StepSettings(n_increments=n), NewtonSettings(rtol=1e-13, atol=1e-13)).run()
    assert res.completed, res.message
    lam = 1.0 + (stretch - 1.0) * np.arange(n + 1) / n
    ratio = lam[1:] / lam[:-1] - 1.0
    return m, 2.0 * ratio / (2.0 + ratio)      # sr_log's strain increments: Pade logarithms


def test_uniaxial_tension_elastic(cache):
    """sr_log in coaxial stretching: sigma = E eps, eps = sum_k 2 x_k / (2 + x_k) (x_k the increments'
    stretch minus one) exactly, ln(1.2) to O(x^3); the other stresses zero; the force sigma times the
    current area, whose lateral stretch increments y_k have 2 y_k / (2 + y_k) = -nu 2 x_k / (2 + x_k)."""
    E, nu = 1000.0, 0.3
    m, de = _bar(cache, Elastic(E, nu), "sr_log")
    eps = de.sum()
    s = m.cauchy_stress()
    assert np.allclose(s[:, 0], E * eps, rtol=1e-10, atol=0)
    assert np.abs(s[:, 1:]).max() < 1e-9 * E * eps
    assert abs(E * eps / (E * np.log(1.2)) - 1.0) < 1e-3
    z = -nu * de
    area = 0.25 ** 2 * np.prod(1.0 + 2.0 * z / (2.0 - z)) ** 2
    assert abs(m.reaction("right")[0] / (E * eps * area) - 1.0) < 1e-9


def test_uniaxial_tension_j2_linear_hardening(cache):
    """J2 with sigma_y = 8 + 200 p under the same stretching: the radial return is exact in a
    proportional path, sigma = (sigma_y0 + H eps) / (1 + H / E) and p = eps - sigma / E."""
    E, sy, H = 1000.0, 8.0, 200.0
    m, de = _bar(cache, J2(E, 0.3, Hardening.linear(sy, H)), "sr_log", n=8)
    eps = de.sum()
    sigma = (sy + H * eps) / (1.0 + H / E)
    assert np.allclose(m.cauchy_stress()[:, 0], sigma, rtol=1e-10, atol=0)
    assert np.allclose(m.p.x.array, eps - sigma / E, rtol=1e-9, atol=0)


# -- the plane-strain limit ---------------------------------------------------------------------------
def _cantilever(cache, kind, size, material, q, p):
    """(tip deflection, vertical support reaction) of a cantilever 1 x 0.5 under an end traction q
    and a follower pressure p on its upper face: plane strain of thickness 0.25, or the slab 0.25
    thick with u_z = 0 on both faces (its sections are the 2D mesh: cm.box extrudes cm.rectangle's)."""
    solid = kind == "solid"
    md = geometry.box(1.0, 0.5, 0.25, size, cache_dir=cache) if solid else \
        geometry.rectangle(1.0, 0.5, size, cache_dir=cache)
    items = [Traction("right", (0.0, -q, 0.0) if solid else (0.0, -q)), Pressure("back" if solid else "top", p)]
    items += [Fixed("left", 0), Fixed("left", 1), Fixed("bottom", 2), Fixed("top", 2)] if solid \
        else [Fixed("left")]
    m = Model(Body(md, kind, material, update="sr_log", thickness=0.25), items)
    m.finalize()
    assert IncrementalSolver(m, StepSettings(n_increments=4)).run().completed
    tip = NodeDisplacement("tip", (1.0, 0.5, 0.0) if solid else (1.0, 0.5))
    tip.attach(m)
    u = tip(m)
    if solid:
        assert u["tip_uz"] == 0.0 and m.reaction("left")[2] == 0.0      # left holds x and y only
    return u["tip_uy"], m.reaction("left")[1], m


@pytest.mark.parametrize("law", [None, "j2"])
def test_slab_with_fixed_faces_is_plane_strain(cache, law):
    """The slab against the plane-strain body: the 3D space contains the 2D solution but is richer
    (the in-plane displacement may vary through the tetrahedra of a layer), so the two agree to the
    discretisation error, which falls as the mesh is refined (measured, elastic: 1.7e-3, 7.9e-4,
    3.6e-4 of the tip deflection at sizes 0.25, 0.125, 0.0625); the reaction balances the same loads."""
    E, nu = 1000.0, 0.3
    material = Elastic(E, nu) if law is None else J2(E, nu, HARDENING)
    # J2: the root's moment 0.9 per unit thickness lies between the first yield, about 0.7 in plane
    # strain, and the limit, about 1.05 (sigma_y = 15): a partly plastic section
    q, p = (8.0, 2.0) if law is None else (1.3, 0.5)
    diffs = []
    for size in (0.25, 0.125):
        u2, r2, _ = _cantilever(cache, "plane_strain", size, material, q, p)
        u3, r3, m3 = _cantilever(cache, "solid", size, material, q, p)
        assert abs(u2) > 0.02
        assert abs(r3 / r2 - 1.0) < 2e-5, (r2, r3)
        diffs.append(abs(u3 / u2 - 1.0))
        if law:
            assert m3.p.x.array.max() > 0.0
    assert diffs[0] < 3e-3 and diffs[1] < 0.6 * diffs[0], diffs


# -- simple shear ------------------------------------------------------------------------------------
A_SHEAR, B_SHEAR = np.array([1.0, -1.0, 1.0]) / np.sqrt(3.0), np.array([1.0, 1.0, 0.0]) / np.sqrt(2.0)


def _simple_shear(cache, update, gamma, n):
    """Simple shear x = X + gamma (a . X) b on an oblique plane (a normal to it, b along it), every
    face prescribed: (the shear stress b.sigma.a, the normal stress b.sigma.b) at every point."""
    md = geometry.box(1.0, 1.0, 1.0, 1.0, cache_dir=cache)
    shear = np.outer(B_SHEAR, A_SHEAR)
    m = Model(Body(md, "solid", Elastic(2.6, 0.3), update=update),
              _homogeneous(lambda t: np.eye(3) + t * gamma * shear))      # mu = 1
    m.finalize()
    assert IncrementalSolver(m, StepSettings(n_increments=n)).run().completed
    s = _tensor(m.cauchy_stress())
    return s @ A_SHEAR @ B_SHEAR, np.einsum("i,pij,j->p", B_SHEAR, s, B_SHEAR)


def test_simple_shear_sr_tends_to_jaumann(cache):
    """The S-R update integrates the Jaumann rate at first order: at gamma = 1.5 the error in
    sigma_ab = mu sin(gamma) halves as the increments double (docs/theory.md 3.2: 1.0317 at 20)."""
    errs = []
    for n in (20, 40):
        s12, _ = _simple_shear(cache, "sr", 1.5, n)
        assert np.ptp(s12) < 1e-10
        errs.append(s12[0] - np.sin(1.5))
    assert abs(errs[0] + np.sin(1.5) - 1.0317) < 1e-4, errs
    assert abs(errs[0] / errs[1] - 2.0) < 0.1, errs


def test_simple_shear_polar_is_green_naghdi(cache):
    """The polar update against Dienes' Green-Naghdi closed form at gamma = 1 (100 increments)."""
    s12, s11 = _simple_shear(cache, "polar", 1.0, 100)
    b = np.arctan(0.5)
    gn12 = 2 * np.cos(2 * b) * (2 * b - 2 * np.tan(2 * b) * np.log(np.cos(b)) - np.tan(b))
    gn11 = 4 * (np.cos(2 * b) * np.log(np.cos(b)) + b * np.sin(2 * b) - np.sin(b) ** 2)
    assert np.allclose(s12, gn12, atol=2e-3) and np.allclose(s11, gn11, atol=2e-3), (s12[0], gn12, s11[0], gn11)

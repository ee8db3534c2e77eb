"""The rigid triangulated surface (Surface): its closest points against a search over every triangle,
its signed distance against a sphere's, the force history of a triangulated plane against Plane's,
a triangulated sphere's force converging to Sphere's as the chord error predicts, Taylor tests on a
flat part, two ranks, a problem file, and the refusals.

* The search (a k-d tree of centroids) finds the nearest of all the triangles (brute force).
* A flat surface's gap is the plane's, at the nodes and between them: the same history as Plane.
* A sphere triangulated with its vertices on it lies inside it, on average by the chord error
  h^2 / (8 R) (measured here from the triangles): the force is Sphere's with the sphere moved
  back by that mean deviation, and its difference from Sphere's falls as h^2.
* On a flat part the closest point moves in the plane and the normal is fixed: the Jacobian that
  holds them fixed is exact (Taylor remainders of order 2).
"""
import numpy as np
import pytest
from mpi4py import MPI

import comove_dolfinx as cm
from comove_dolfinx.contact import ContactError, Plane, Sphere, Surface
from comove_dolfinx.contact import trimesh
from comove_dolfinx.taylor import taylor_test
from states import pressed_block
from test_swept import MU, _motion, _slide

R_BALL = 1.0
BALL_GEO = f"""SetFactory("OpenCASCADE");
Sphere(1) = {{0.5, 0.5, {-R_BALL}, {R_BALL}}};
Physical Surface("ball") = {{1}};
"""


@pytest.fixture(scope="module")
def cache(tmp_path_factory):
    return str(MPI.COMM_WORLD.bcast(str(tmp_path_factory.mktemp("meshes")), root=0))


@pytest.fixture(scope="module")
def ball_geo(cache):
    path = f"{cache}/ball.geo"
    if MPI.COMM_WORLD.rank == 0:
        with open(path, "w") as f:
            f.write(BALL_GEO)
    MPI.COMM_WORLD.barrier()
    return path


def grid(half: float, n: int, normal=(0.0, 0.0, 1.0), point=(0.0, 0.0, 0.0), jitter: float = 0.0):
    """The square [-half, half]^2 of the plane through ``point`` square to ``normal``, cut into
    2 (n - 1)^2 triangles (their inner vertices moved by up to ``jitter`` of a cell in the plane),
    oriented with the normal: (points, triangles)."""
    s = np.linspace(-half, half, n)
    a, b = (v.ravel() for v in np.meshgrid(s, s, indexing="ij"))
    inner = (np.abs(a) < half) & (np.abs(b) < half)
    rng = np.random.default_rng(3)
    a, b = (v + inner * rng.uniform(-jitter, jitter, v.shape) * (s[1] - s[0]) for v in (a, b))
    nrm = np.asarray(normal, float) / np.linalg.norm(normal)
    e1 = np.cross(nrm, (1.0, 0.0, 0.0) if abs(nrm[0]) < 0.9 else (0.0, 1.0, 0.0))
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(nrm, e1)
    pts = np.asarray(point, float) + np.outer(a, e1) + np.outer(b, e2)
    k = np.arange(n * n).reshape(n, n)[:-1, :-1].ravel()
    tris = np.r_[np.c_[k, k + n, k + n + 1], np.c_[k, k + n + 1, k + 1]]
    return pts, tris


# -- the geometry ------------------------------------------------------------------------------------
def test_the_search_finds_the_nearest_of_all_triangles(ball_geo):
    """Closest points, normals and signed distances of points near and far from a triangulated
    sphere, against the nearest of every triangle measured one by one; the gap is (x - p) . n, the
    normal of unit length, negative inside."""
    s = Surface.from_gmsh(ball_geo, "ball", size=0.3).surface
    x = np.random.default_rng(0).normal(size=(200, 3)) * np.r_[[0.6] * 100, [3.0] * 100][:, None] \
        + (0.5, 0.5, -R_BALL)
    p, n, g = s.closest(x)
    tri = s.points[s.triangles]
    every = [trimesh.closest_on_triangles(np.repeat(xi[None], len(tri), 0), tri[:, 0], tri[:, 1], tri[:, 2])[3]
             for xi in x]
    np.testing.assert_allclose(np.abs(g), np.sqrt([d.min() for d in every]), rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(np.einsum("ij,ij->i", x - p, n), g, rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(np.linalg.norm(n, axis=1), 1.0, rtol=1e-12)


def test_a_triangulated_sphere_lies_between_its_spheres_and_flips(ball_geo):
    """The triangles of a sphere (vertices on it) bound a convex body between the ball of radius R
    and that of r_in, the least distance of their planes from the centre: the signed distance of a
    point at rho from the centre lies between rho - R and rho - r_in, inside and outside (the
    closed surface faces outwards); flip turns the side."""
    surf = Surface.from_gmsh(ball_geo, "ball", size=0.3)
    s, c = surf.surface, np.array((0.5, 0.5, -R_BALL))
    r_in = np.abs(np.einsum("ij,ij->i", s.points[s.triangles[:, 0]] - c, s.face_normals)).min()
    assert 0.5 * R_BALL < r_in < R_BALL
    x = c + np.random.default_rng(1).normal(size=(300, 3))
    rho, g = np.linalg.norm(x - c, axis=1), surf.gap_np(x, np.zeros(3))
    assert np.all(g >= rho - R_BALL - 1e-12) and np.all(g <= rho - r_in + 1e-12)
    assert np.sum(rho < r_in) > 20 and np.sum(rho > R_BALL) > 20
    d = np.array([0.1, -0.2, 0.3])
    flipped = Surface.from_gmsh(ball_geo, "ball", size=0.3, flip=True)
    np.testing.assert_allclose(flipped.gap_np(x + d, d), -g, rtol=1e-12, atol=1e-14)


# -- the same as Plane -----------------------------------------------------------------------------
# the block sliding on an obstacle, as test_swept runs it against Plane and Sphere


def test_a_triangulated_plane_is_the_plane(cache):
    """The plane z = 0 as 72 triangles of a jittered grid, 6 x 6 about the block: the same force
    history as Plane with friction slipping, and the same Newton iterations."""
    pts, tris = grid(3.0, 7, jitter=0.2)
    a = _slide(cache, Surface(pts, tris, motion=_motion))
    b = _slide(cache, Plane((0.0, 0.0, 0.0), (0.0, 0.0, 1.0), motion=_motion))
    assert abs(b["f_fz"][-1]) > 1.0 and np.hypot(b["f_fx"][-1], b["f_fy"][-1]) > 0.1 * abs(b["f_fz"][-1])
    np.testing.assert_array_equal(a.newton_its, b.newton_its)
    for col in ("f_fx", "f_fy", "f_fz"):
        np.testing.assert_allclose(a[col], b[col], rtol=1e-8, atol=1e-8 * abs(b["f_fz"][-1]), err_msg=col)


# -- a triangulated sphere converges to Sphere -------------------------------------------------------
DEPTH_BALL = 0.05


def _press(cache, obstacle):
    """A block (1 x 1 x 0.5, linear tetrahedra of 0.125, its top held) that the obstacle, rising by
    DEPTH_BALL in 2 increments, presses from below (penalty, frictionless); the force's z."""
    md = cm.box(1.0, 1.0, 0.5, 0.125, order=1, cache_dir=cache)
    body = cm.Body(md, "solid", cm.Elastic(1000.0, 0.3), degree=1)
    c = cm.Contact("bottom", obstacle, method="penalty")
    res = cm.Job(body, [cm.Fixed("top"), c], [cm.Step(2, ramp={c: 1.0})], [cm.ContactForce(c, "f", component=2)]).run()
    assert res.completed, res.message
    return res["f"][-1]


def _mean_deviation(s, centre, radius, cap: float) -> float:
    """The mean distance of the triangles (their centroids within ``cap`` of the sphere's top) inside
    the sphere, over their area (a lattice of 45 points on each)."""
    t = s.points[s.triangles]
    near = np.linalg.norm(t.mean(axis=1) - centre - (0.0, 0.0, radius), axis=1) < cap
    m = 8
    bary = np.array([(i, j, m - i - j) for i in range(m + 1) for j in range(m + 1 - i)]) / m
    dev = radius - np.linalg.norm(np.einsum("kv,tvd->tkd", bary, t[near]) - centre, axis=2)
    return float((dev.mean(axis=1) * s.areas[near]).sum() / s.areas[near].sum())


def test_a_triangulated_sphere_converges_to_the_sphere(cache, ball_geo):
    """The sphere (R = 1) from Gmsh in triangles of h = 0.1 and 0.05 pressed 0.05 into the block: the
    force's difference from Sphere's falls as h^2 (order 1.6 to 2.4), and at h = 0.05 it is about
    that of Sphere moved back by the triangles' mean deviation inside it over the contact zone
    (the chord error, about h^2 / (8 R); within 0.8 to 1.5 times)."""
    centre = np.array((0.5, 0.5, -R_BALL))
    ref = _press(cache, Sphere(centre, R_BALL, motion=(0.0, 0.0, DEPTH_BALL)))
    diffs = {}
    for h in (0.1, 0.05):
        surf = Surface.from_gmsh(ball_geo, "ball", size=h, motion=(0.0, 0.0, DEPTH_BALL))
        diffs[h] = _press(cache, surf) - ref
    order = np.log2(diffs[0.1] / diffs[0.05])
    assert diffs[0.1] < diffs[0.05] < 0.0 and 1.6 < order < 2.4, (ref, diffs, order)
    shift = _mean_deviation(surf.surface, centre, R_BALL, cap=0.3)
    predicted = _press(cache, Sphere(centre, R_BALL, motion=(0.0, 0.0, DEPTH_BALL - shift))) - ref
    assert 0.8 < diffs[0.05] / predicted < 1.5, (diffs, predicted)
    assert abs(diffs[0.05]) < 0.015 * ref


# -- Taylor tests on a flat part ---------------------------------------------------------------------
def _tilted():
    """A plane of 72 triangles (a jittered grid) below the block of tests/states.py, tilted by about
    1/50 so that it touches the block's bottom near one corner first."""
    return grid(3.0, 7, normal=(0.02, 0.01, 1.0), point=(0.5, 0.25, -0.015), jitter=0.2)


@pytest.mark.parametrize("method", ["penalty", "nitsche"])
def test_jacobian_with_a_flat_surface_is_exact(cache, method):
    """Friction slipping, every node of the contact on one plane of several triangles: Taylor
    remainders of order 2."""
    m, c = pressed_block(cache, Surface(*_tilted()), method=method, mu=0.1)
    stick, slip = c.stick_slip()
    assert slip > 0.2 * (stick + slip), (stick, slip)
    result = taylor_test(m, h0=1e-4, n=10)
    assert np.all(np.abs(result.orders[-3:] - 2.0) < 0.15), str(result)


def test_jacobian_across_a_curved_surface_leaves_out_the_normals_turning(cache, tmp_path):
    """A sphere in triangles of 0.1 under the block: the nodes' closest points lie on many faces and
    edges, whose normals turn with u in the residual and not in the Jacobian. The remainders fall
    as h (the fields do follow u: frozen, they would fall as h^2), at under 1 % of the first-order
    change (Newton converges more slowly there, to the same solution)."""
    path = tmp_path / "ball.geo"
    path.write_text(BALL_GEO.replace("0.5, 0.5,", "0.5, 0.25,"))
    m, _ = pressed_block(cache, Surface.from_gmsh(path, "ball", size=0.1), method="penalty", mu=0.1)
    result = taylor_test(m, h0=1e-4, n=6)
    assert np.all(np.abs(result.orders[-3:] - 1.0) < 0.1), str(result)
    assert np.all(result.remainders < 0.01 * result.first_order), str(result)


# -- two ranks -------------------------------------------------------------------------------------
@pytest.mark.mpi
def test_a_surface_on_two_ranks_is_the_serial_one(cache, ball_geo):
    """The sliding job (friction slipping, Nitsche) on a triangulated sphere, distributed over the
    ranks and, on every rank, on its own (COMM_SELF): each rank finds the closest points of its own
    nodes, the same history."""
    def make():
        return Surface.from_gmsh(ball_geo, "ball", size=0.1, motion=_motion)
    par = _slide(cache, make(), "nitsche")
    ser = _slide(cache, make(), "nitsche", comm=MPI.COMM_SELF)
    np.testing.assert_array_equal(par.newton_its, ser.newton_its)
    for col in ("f_fx", "f_fy", "f_fz"):
        np.testing.assert_allclose(par[col], ser[col], rtol=1e-7, atol=1e-9, err_msg=col)


# -- a restart -------------------------------------------------------------------------------------
@pytest.mark.parametrize("method", ["nitsche", "penalty"])
def test_a_run_on_a_surface_restarts_to_the_uninterrupted_history(cache, ball_geo, tmp_path, method):
    """The sliding job on a triangulated sphere (lagged friction slipping; with penalty its stick
    part, a vector field of the contact's nodes, is in the checkpoint too), stopped after increment
    4 and restarted from its checkpoint: the history and Newton's iterations of the run that was not
    stopped, to 1e-12 (the closest points are recomputed at the checkpoint's iterates)."""
    from comove_dolfinx.io.checkpoint import Checkpoint
    from comove_dolfinx.io.writers import Writer

    class Stop(Writer):
        def write(self, run, row, increment):
            if row["increment"] == 4:
                raise RuntimeError("stopped by the test")

    def job(writers=()):
        md = cm.box(1.0, 1.0, 0.5, 0.25, order=1, cache_dir=cache)
        body = cm.Body(md, "solid", cm.Elastic(1000.0, 0.3), degree=1)
        c = cm.Contact("bottom", Surface.from_gmsh(ball_geo, "ball", size=0.1, motion=_motion), method, mu=MU)
        steps = [cm.Step(2, ramp={c: 1.0}), cm.Step(3, ramp={c: 2.0})]
        return cm.Job(body, [cm.Fixed("top"), c], steps, [cm.ContactForce(c, "f", component=None)],
                      writers=list(writers))
    full = job().run()
    folder = tmp_path / "checkpoint"
    with pytest.raises(RuntimeError, match="stopped by the test"):
        job([Checkpoint(folder, every=1, interval=0.0), Stop()]).run()
    again = job([Checkpoint(folder, every=1, interval=0.0)]).run(restart=folder)
    assert full.completed and again.completed and again.newton_its == full.newton_its
    for col in ("f_fx", "f_fy", "f_fz"):
        np.testing.assert_allclose(again[col], full[col], rtol=0, atol=1e-12 * abs(full["f_fz"]).max(), err_msg=col)


# -- refusals --------------------------------------------------------------------------------------
def _geo(tmp_path):
    path = tmp_path / "ball.geo"
    path.write_text(BALL_GEO)
    return path


REFUSED = [
    (lambda p: Surface.from_gmsh(p / "none.geo", "ball"),
     r"surface file .*none.geo: no such file: give the path of a .geo, .brep, .step or .msh file"),
    (lambda p: Surface.from_gmsh(_geo(p), "bal"),
     r"surface file .*ball.geo: no physical surface named 'bal': give one of the file's named surfaces \(ball\)"),
    (lambda p: Surface.from_gmsh(_geo(p), [7]), r"surface tags \[7\]: give tags of the file's surfaces \[1\]"),
    (lambda p: Surface.from_gmsh(_geo(p), 1.5), r"surface = 1.5: give the name of a physical surface or a list"),
    (lambda p: Surface.from_gmsh(_geo(p), "ball", size=0.0),
     r"size = 0.0: give the triangles' size, a finite number > 0"),
    (lambda p: Surface([(0, 0, 0), (1, 0, 0), (0, 1, 0)], [(0, 1, 3)]),
     r"surface triangles of shape \(1, 3\): give \(M, 3\) indices of the points, from 0 to 2"),
    (lambda p: Surface([(0, 0), (1, 0), (0, 1)], [(0, 1, 2)]), r"surface points of shape \(3, 2\): give \(N, 3\)"),
    (lambda p: Surface([(0, 0, 0), (1, 0, 0), (0, 1, 0), (1, 1, 0)], [(0, 1, 2), (1, 2, 3)]),
     r"triangles at the edge between points \[1, 2\] are oriented oppositely: give all the triangles one orientation"),
    (lambda p: Surface(*grid(1.0, 3), flip=1), r"flip = 1: give True"),
    (lambda p: Surface(*grid(1.0, 3), motion=(0, 1)), r"motion = \(0, 1\): give 3 finite numbers"),
]


@pytest.mark.parametrize("make, words", REFUSED)
def test_bad_surfaces_are_refused_in_one_line(tmp_path, make, words):
    with pytest.raises(ContactError, match=words) as err:
        make(tmp_path)
    assert "\n" not in str(err.value)


def test_a_surface_is_3d(cache):
    """A 2D body refuses it in one line naming the 2D obstacles."""
    md = cm.rectangle(1.0, 0.5, 0.25, order=1, cache_dir=cache)
    body = cm.Body(md, "plane_strain", cm.Elastic(1000.0, 0.3), degree=1)
    c = cm.Contact("bottom", Surface(*grid(1.0, 3)))
    with pytest.raises(ContactError, match="the obstacle Surface is 3D, the body 2D: give a 2D obstacle"):
        cm.Job(body, [cm.Fixed("top"), c], [cm.Step(1)]).run()


# -- a problem file ----------------------------------------------------------------------------------
BLOCK_ON_BALL = """
[mesh]
builder = "box"
Lx = 1.0
Ly = 1.0
Lz = 0.5
size = 0.25
order = 1
[body]
kind = "solid"
degree = 1
material = { E = 1000.0, nu = 0.3 }
[[items]]
type = "fixed"
boundary = "top"
[[items]]
type = "contact"
name = "ball"
boundary = "bottom"
method = "nitsche"
mu = 0.2
OBSTACLE
[[steps]]
n = 2
[[probes]]
type = "contact_force"
item = "ball"
component = 2
column = "Pz"
[[probes]]
type = "contact_force"
item = "ball"
component = 0
column = "Px"
[[probes]]
type = "contact_area"
item = "ball"
column = "A"
"""
BALL_LINE = ('obstacle = { type = "surface", file = "ball.geo", surface = "ball", size = 0.1, '
             'motion = [0.01, 0.0, 0.03] }')


def test_a_surface_from_a_problem_file_runs_the_job_of_the_api(tmp_path):
    """A triangulated ball rising and moving sideways under a block: the file's history (force and
    contact area) is that of the same job built with the API, the force pushing up and along."""
    from comove_dolfinx import problem
    _geo(tmp_path)
    path = tmp_path / "ball.toml"
    path.write_text(BLOCK_ON_BALL.replace("OBSTACLE", BALL_LINE))
    from_file = problem.build(problem.read(path), MPI.COMM_WORLD).run()
    body = cm.Body(cm.box(1.0, 1.0, 0.5, 0.25, order=1), "solid", cm.Elastic(1000.0, 0.3), degree=1)
    ball = Surface.from_gmsh(tmp_path / "ball.geo", "ball", size=0.1, motion=(0.01, 0.0, 0.03))
    c = cm.Contact("bottom", ball, method="nitsche", mu=0.2)
    probes = [cm.ContactForce(c, "Pz", component=2), cm.ContactForce(c, "Px", component=0), cm.ContactArea(c, "A")]
    from_api = cm.Job(body, [cm.Fixed("top"), c], [cm.Step(2)], probes=probes, writers=[]).run()
    assert from_file.completed and from_api.completed
    for column in ("Px", "Pz", "A"):
        assert np.array_equal(from_file[column], from_api[column]), column
    assert from_file["Pz"][-1] > 1.0 and from_file["Px"][-1] > 0.0 and 0.0 < from_file["A"][-1] < 1.0


@pytest.mark.parametrize("line, words", [
    ('obstacle = { type = "surface", file = "ball.geo", size = 0.1 }', "obstacle: surface is missing: add it"),
    ('obstacle = { type = "surface", file = "ball.geo", surface = "ball", size = -0.1 }',
     "obstacle: size = -0.1: give the triangles' size, a number > 0"),
    ('obstacle = { type = "surface", file = "nowhere.geo", surface = "ball" }', "nowhere.geo' does not exist"),
    ('obstacle = { type = "surface", file = "ball.geo", surface = "ball", flip = 1 }', "flip = 1: give true or false"),
])
def test_bad_surfaces_in_a_problem_file_get_one_line(tmp_path, line, words):
    """Exit code 2 and one line naming the key, dolfinx never imported."""
    import subprocess
    import sys
    _geo(tmp_path)
    path = tmp_path / "bad.toml"
    path.write_text(BLOCK_ON_BALL.replace("OBSTACLE", line))
    code = ("import sys; from comove_dolfinx import cli; rc = cli.main(sys.argv[1:]); "
            "assert 'dolfinx' not in sys.modules, 'dolfinx was imported'; sys.exit(rc)")
    p = subprocess.run([sys.executable, "-c", code, "run", str(path), "--out", str(tmp_path / "run")],
                       capture_output=True, text=True, timeout=120)
    assert p.returncode == 2, p.stdout + p.stderr
    assert words in p.stderr and len(p.stderr.strip().splitlines()) == 1, p.stderr


def test_a_missing_surface_name_in_a_problem_file_gets_one_line(tmp_path):
    """The surface's name is checked when the file's geometry is read: exit code 2, one line."""
    import subprocess
    import sys
    _geo(tmp_path)
    path = tmp_path / "bad.toml"
    path.write_text(BLOCK_ON_BALL.replace("OBSTACLE", BALL_LINE.replace('surface = "ball"', 'surface = "face"')))
    p = subprocess.run([sys.executable, "-m", "comove_dolfinx", "run", str(path), "--out", str(tmp_path / "run")],
                       capture_output=True, text=True, timeout=300)
    assert p.returncode == 2, p.stdout + p.stderr
    assert "no physical surface named 'face': give one of the file's named surfaces (ball)" in p.stderr
    assert len(p.stderr.strip().splitlines()) == 1, p.stderr

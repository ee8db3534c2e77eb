"""Problem files of 3D bodies (kind = "solid"): the file runs the job that the same problem written
in Python runs (the same history), and a file that mixes dimensions gets one line naming the key and
the fix, before dolfinx is loaded."""
import subprocess
import sys

import numpy as np
import pytest

import comove_dolfinx as cm
from comove_dolfinx import problem

BLOCK = """
[mesh]
builder = "box"
Lx = 2.0
Ly = 0.5
Lz = 0.5
size = 0.25
order = 1
[body]
kind = "solid"
degree = 1
material = {{ law = "j2", E = 1000.0, nu = 0.3, hardening = [[0, 1.0], [1.0, 11.0]] }}
[[items]]
type = "fixed"
boundary = "left"
[[items]]
type = "displacement"
boundary = "right"
value = {value}
[[items]]
type = "pressure"
boundary = "top"
p = 0.2
[[steps]]
n = 4
[[probes]]
type = "node"
name = "tip"
point = [2.0, 0.5, 0.5]
[[probes]]
type = "reaction"
boundary = "left"
name = "clamp"
"""


def test_a_3d_problem_file_runs_the_job_written_in_python(tmp_path):
    """A bent, pressed block of J2: the problem file's history equals the history of the same job
    built with the API, column by column, with the three components of the tip's displacement and
    of the clamp's reaction; the prescribed end is where the file puts it."""
    path = tmp_path / "block.toml"
    path.write_text(BLOCK.format(value="[0.0, 0.0, -0.06]"))
    from mpi4py import MPI
    job = problem.build(problem.read(path), MPI.COMM_WORLD)
    from_file = job.run()
    mesh = cm.box(2.0, 0.5, 0.5, 0.25, order=1)
    body = cm.Body(mesh, "solid", cm.J2(1000.0, 0.3, cm.Hardening((0.0, 1.0), (1.0, 11.0))), degree=1)
    items = [cm.Fixed("left"), cm.Displacement("right", (0.0, 0.0, -0.06)), cm.Pressure("top", 0.2)]
    probes = [cm.NodeDisplacement("tip", (2.0, 0.5, 0.5)), cm.Reaction("left", "clamp", dim=3)]
    from_api = cm.Job(body, items, [cm.Step(4)], probes=probes, writers=[]).run()
    assert from_file.completed and from_api.completed
    for column in ("tip_ux", "tip_uy", "tip_uz", "clamp_fx", "clamp_fy", "clamp_fz"):
        assert np.array_equal(from_file[column], from_api[column]), column
    assert from_file["tip_uz"][-1] == pytest.approx(-0.06, abs=1e-12)     # the prescribed end
    assert from_file["clamp_fz"][-1] > 0.0                                   # the clamp holds it up


BAD = [('value = [0.0, -0.06]', "value = [0.0, -0.06]: give 3 numbers (the body is 3D)"),
       ('value = -0.06\ncomponent = 3', "component = 3"),
       ('kind = "plane_strain"', "builder = 'box' for a body of kind = 'plane_strain': give a 2D builder")]


@pytest.mark.parametrize("change, words", BAD)
def test_a_file_that_mixes_dimensions_gets_one_line(tmp_path, change, words):
    """A 2-vector for a 3D body, a component beyond z, a 3D builder for a plane body: exit code 2,
    one line naming the key, dolfinx never imported."""
    text = BLOCK.format(value="[0.0, 0.0, -0.06]")
    if change.startswith("kind"):
        text = text.replace('kind = "solid"', change)
    else:
        text = text.replace("value = [0.0, 0.0, -0.06]", change)
    path = tmp_path / "bad.toml"
    path.write_text(text)
    code = ("import sys; from comove_dolfinx import cli; rc = cli.main(sys.argv[1:]); "
            "assert 'dolfinx' not in sys.modules, 'dolfinx was imported'; sys.exit(rc)")
    p = subprocess.run([sys.executable, "-c", code, "run", str(path), "--out", str(tmp_path / "run")],
                       capture_output=True, text=True, timeout=120)
    assert p.returncode == 2, p.stdout + p.stderr
    assert words in p.stderr and len(p.stderr.strip().splitlines()) == 1, p.stderr


# -- 3D obstacles and the contact area -----------------------------------------------------------------
BALL = """
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
OBSTACLE
[[steps]]
n = 2
[[probes]]
type = "contact_force"
item = "ball"
component = 2
column = "P"
[[probes]]
type = "contact_area"
item = "ball"
column = "A"
[[probes]]
type = "contact_radius"
item = "ball"
column = "a"
origin = [0.5, 0.5, 0.0]
"""
SPHERE = 'obstacle = { type = "sphere", centre = [0.5, 0.5, -2.0], radius = 2.0, motion = [0.0, 0.0, 0.02] }'


def test_a_sphere_pressed_on_a_block_from_a_problem_file(tmp_path):
    """A ball rising under a block: the file's force, contact area and contact radius (along the
    meridian from the ball's axis towards +x, across the bottom face) are those of the same job
    built with the API, the area in the history a part of the bottom face that grows as the
    ball rises, and so does the radius."""
    path = tmp_path / "ball.toml"
    path.write_text(BALL.replace("OBSTACLE", SPHERE))
    from mpi4py import MPI
    from_file = problem.build(problem.read(path), MPI.COMM_WORLD).run()
    body = cm.Body(cm.box(1.0, 1.0, 0.5, 0.25, order=1), "solid", cm.Elastic(1000.0, 0.3), degree=1)
    c = cm.Contact("bottom", cm.Sphere((0.5, 0.5, -2.0), 2.0, motion=(0.0, 0.0, 0.02)), method="nitsche")
    probes = [cm.ContactForce(c, "P", component=2), cm.ContactArea(c, "A"),
              cm.ContactRadius(c, "a", origin=(0.5, 0.5, 0.0))]
    from_api = cm.Job(body, [cm.Fixed("top"), c], [cm.Step(2)], probes=probes, writers=[]).run()
    assert from_file.completed and from_api.completed
    for column in ("P", "A", "a"):
        assert np.array_equal(from_file[column], from_api[column]), column
    assert 0.0 < from_file["A"][-2] < from_file["A"][-1] < 1.0 and from_file["P"][-1] > 0.0
    assert 0.0 < from_file["a"][-2] < from_file["a"][-1] < 0.5


ARC_GEO = """
Point(1) = {0.0, 0.2, 0};
Point(2) = {0.5, 0.0, 0};
Point(3) = {1.0, 0.2, 0};
Line(1) = {1, 2};
Line(2) = {2, 3};
Physical Curve("face") = {1, 2};
"""


def test_the_3d_obstacles_of_a_file_are_those_of_the_api(tmp_path):
    """Cylinder, an extruded profile from points and a revolved one from a Gmsh file: the file's
    obstacles have the API's geometry (built, not run)."""
    (tmp_path / "die.geo").write_text(ARC_GEO)
    from mpi4py import MPI
    cases = {
        'obstacle = { type = "cylinder", point = [0.5, 0, -1], axis = [0, 2, 0], radius = 1.0 }':
            cm.Cylinder((0.5, 0, -1), (0, 1, 0), 1.0),
        'obstacle = { type = "extruded", points = [[0, -1], [1, -1.2]], radius = 0.1, u = [0, 1, 0], '
        'v = [0, 0, 1], origin = [0.5, 0, 0] }':
            cm.Extruded(cm.Profile([(0, -1), (1, -1.2)], 0.1), u=(0, 1, 0), v=(0, 0, 1), origin=(0.5, 0, 0)),
        'obstacle = { type = "revolved", file = "die.geo", curve = "face", radius = 0.05, spacing = 0.1, '
        'axis = [1, 0, 0], origin = [0, 0.5, -0.3] }':
            cm.Revolved(cm.Profile.from_gmsh(tmp_path / "die.geo", "face", 0.05, 0.1), axis=(1, 0, 0),
                        origin=(0, 0.5, -0.3))}
    x = np.random.default_rng(1).uniform(-1.0, 1.0, (50, 3))
    for k, (line, api) in enumerate(cases.items()):
        path = tmp_path / f"o{k}.toml"
        path.write_text(BALL.replace("OBSTACLE", line))
        obstacle = problem.build(problem.read(path), MPI.COMM_WORLD).items[1].obstacle
        assert type(obstacle) is type(api)
        np.testing.assert_array_equal(obstacle.gap_np(x, np.zeros(3)), api.gap_np(x, np.zeros(3)), err_msg=line)


BAD_3D = [
    ('radius = 2.0', 'radius = -1.0', "obstacle: radius = -1.0: give a finite number > 0"),
    (SPHERE, 'obstacle = { type = "cylinder", point = [0, 0, -1], radius = 1.0 }', "obstacle: axis is missing: add it"),
    (SPHERE, 'obstacle = { type = "cylinder", point = [0, 0, -1], axis = [0, 0, 0], radius = 1.0 }',
     "obstacle: axis = [0, 0, 0]: give the axis's direction"),
    (SPHERE, 'obstacle = { type = "extruded", radius = 0.1 }',
     "obstacle: give the profile as points = [[x, y], ...] or as file and curve"),
    (SPHERE, 'obstacle = { type = "extruded", points = [[0, 0], [1, 0]], file = "a.geo", curve = "c", radius = 0.1 }',
     "or as file and curve, not both"),
    (SPHERE, 'obstacle = { type = "revolved", file = "a.geo", radius = 0.1 }', "obstacle: curve is missing"),
    (SPHERE, 'obstacle = { type = "extruded", points = [[0, 0], [1, 0]], radius = 0.1, u = [1, 1, 0], v = [2, 2, 0] }',
     "u = [1, 1, 0] and v = [2, 2, 0] are parallel"),
    (SPHERE, 'obstacle = { type = "extruded", points = [[0, 0], [1, 0]], radius = 0.1, u = [1, 0] }',
     "u = [1, 0]: give 3 numbers (the body is 3D)"),
    (SPHERE, 'obstacle = { type = "revolved", points = [[0.5, 0], [-0.1, 1]], radius = 0.1 }',
     "points: [-0.1, 1] has x < 0: x is the distance from the axis"),
    (SPHERE, 'obstacle = { type = "revolved", points = [[0, 0], [1, 0]], radius = 0.1, axis = [0, 0, 1], '
     'origin = [0, 0, 0], u = [1, 0, 0] }', "obstacle: unknown key 'u'"),
    (SPHERE, 'obstacle = { type = "circle", centre = [0, -1], radius = 1.0 }',
     "type = 'circle' is a 2D obstacle, the body is 3D (kind = 'solid'): choose one of plane, sphere, cylinder"),
    ('type = "contact_area"', 'type = "contact_length"',
     "type = 'contact_length' is not defined when the body is 3D (kind = 'solid'): use contact_area"),
]


@pytest.mark.parametrize("old, new, words", BAD_3D)
def test_bad_3d_obstacles_and_probes_get_one_line(tmp_path, old, new, words):
    """Exit code 2, one line naming the key, dolfinx never imported."""
    text = BALL.replace("OBSTACLE", SPHERE)
    assert old in text
    path = tmp_path / "bad.toml"
    path.write_text(text.replace(old, new, 1))
    code = ("import sys; from comove_dolfinx import cli; rc = cli.main(sys.argv[1:]); "
            "assert 'dolfinx' not in sys.modules, 'dolfinx was imported'; sys.exit(rc)")
    p = subprocess.run([sys.executable, "-c", code, "run", str(path), "--out", str(tmp_path / "run")],
                       capture_output=True, text=True, timeout=120)
    assert p.returncode == 2, p.stdout + p.stderr
    assert words in p.stderr and len(p.stderr.strip().splitlines()) == 1, p.stderr

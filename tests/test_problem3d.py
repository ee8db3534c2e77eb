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

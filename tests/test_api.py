"""The public API as a user meets it: the README's example runs as written and balances its forces,
a problem file gives the ring's stored history, bad problem files and steps are refused with one
line naming the key, and steps ramp, hold and reverse the items' factors as documented."""
import csv
import pathlib
import re

import launch
import numpy as np
import pytest
from mpi4py import MPI

ROOT = pathlib.Path(__file__).resolve().parent.parent
REFERENCE = pathlib.Path(__file__).resolve().parent / "reference"


def _history(path):
    with open(path, newline="") as fh:
        rows = list(csv.DictReader(fh))
    return {k: np.array([float(r[k]) for r in rows]) for k in rows[0]}


def test_readme_example_runs_and_balances(tmp_path):
    """The punch's force is carried by the floor (nothing else loads the pad), and nothing is left
    once the punch is back where it started."""
    text = (ROOT / "README.md").read_text()
    code = re.search(r"## Your own problem.*?```python\n(.*?)```", text, re.S).group(1)
    (tmp_path / "example.py").write_text(code)
    p = launch.run([tmp_path / "example.py"], cwd=tmp_path)
    assert p.returncode == 0, p.stdout + p.stderr
    assert "completed 18 increments" in p.stdout
    h = _history(tmp_path / "pad_history.csv")
    assert h["punch_force"].max() > 1.0
    np.testing.assert_allclose(h["floor_fy"], h["punch_force"], rtol=1e-6, atol=1e-8 * h["punch_force"].max())
    assert abs(h["punch_force"][-1]) < 1e-8 * h["punch_force"].max()
    assert np.all(np.abs(h["floor_fx"]) < 1e-6 * h["punch_force"].max())    # frictionless, symmetric
    # the hold step keeps the punch where it was: the force does not move
    held = (h["time"] > 1.0) & (h["time"] <= 2.0)
    np.testing.assert_allclose(h["punch_force"][held], h["punch_force"][h["time"] == 1.0][0], rtol=1e-8)


def test_problem_file_gives_the_ring_history(tmp_path):
    """demos/ring.toml describes the ring scene; it must give the stored history of `comove run ring`
    (same increments, same Newton iterations, every column to 1e-8 of its largest value)."""
    p = launch.run(["-m", "comove_dolfinx.cli", "run", ROOT / "demos" / "ring.toml", "--out", tmp_path,
                    "--no-progress"])
    assert p.returncode == 0, p.stdout + p.stderr
    new, ref = _history(tmp_path / "history.csv"), _history(REFERENCE / "ring.csv")
    assert len(new["step"]) == len(ref["step"])
    np.testing.assert_array_equal(new["newton_its"], ref["newton_its"])
    np.testing.assert_allclose(new["time"] * 6.6, ref["load"], rtol=1e-9)    # 10 printed digits
    for col in ("force", "contact_width", "max_plastic_strain"):
        assert np.abs(new[col] - ref[col]).max() <= 1e-8 * np.abs(ref[col]).max(), col


BAD = [
    ("[mesh]\nbuilder = 'rectangle'\nL = 1.0\nH = 1.0\nsize = 0.5\n[body]\nkind = 'plane_strain'\n"
     "material = {E = 1.0, nu = 0.3}\n[[items]]\ntype = 'fixed'\nboundry = 'left'\n", "unknown key 'boundry'"),
    ("[mesh]\nbuilder = 'rectangle'\nL = 1.0\nH = 1.0\nsize = nan\n", "size = nan: give a finite number"),
    ("[mesh]\nbuilder = 'square'\n", "builder = 'square'"),
    ("[mesh]\nbuilder = 'rectangle'\nL = 1.0\nH = 1.0\nsize = 0.5\n[body]\nkind = 'plane_strain'\n"
     "material = {E = 1.0, nu = 0.3}\n[[items]]\ntype = 'contact'\nboundary = 'top'\n"
     "obstacle = {type = 'plane', point = [0, 2]}\n", "normal is missing"),
    ("[mesh]\nbuilder = 'rectangle'\nL = 1.0\nH = 1.0\nsize = 0.5\n[body]\nkind = 'plane_strain'\n"
     "material = {E = 1.0, nu = 0.3}\n[[items]]\ntype = 'pressure'\nboundary = 'top'\np = 1.0\n"
     "[[steps]]\nramp = {load = 1.0}\n", "no item named 'load'"),
    ("[mesh]\nbuilder = 'rectangle'\nL = 1.0\nH = 1.0\nsize = 0.5\n[body]\nkind = 'plane_strain'\n"
     "material = {E = -1.0, nu = 0.3}\n[[items]]\ntype = 'fixed'\nboundary = 'left'\n", "E = -1"),
    ("[mesh\n", "not valid TOML"),
]


@pytest.mark.parametrize("text, words", BAD)
def test_bad_problem_files_get_one_line(tmp_path, text, words):
    f = tmp_path / "p.toml"
    f.write_text(text)
    p = launch.run(["-m", "comove_dolfinx.cli", "run", f, "--out", tmp_path / "out", "--no-progress"])
    assert p.returncode == 2, p.stdout + p.stderr
    assert words in p.stderr and "Traceback" not in p.stderr
    assert len(p.stderr.strip().splitlines()) == 1, p.stderr


def test_steps_ramp_hold_and_reverse():
    """An elastic strip pulled by a prescribed end displacement in three steps (to 1, held, back to
    0.5): the reaction follows the factor and returns along the same path (elastic), and the
    history's time runs over the steps."""
    import comove_dolfinx as cm
    mesh = cm.rectangle(2.0, 0.5, 0.25, order=2)
    body = cm.Body(mesh, "plane_strain", cm.Elastic(100.0, 0.3), update="svk")
    pull = cm.Displacement("right", 0.1, component=0)
    items = [cm.Fixed("left"), pull]
    steps = [cm.Step(4), cm.Step(2, ramp={pull: 1.0}), cm.Step(2, ramp={pull: 0.5})]
    res = cm.Job(body, items, steps, [cm.Reaction("right", "end")]).run()
    assert res.completed
    np.testing.assert_allclose(res["time"], [0.25, 0.5, 0.75, 1.0, 1.5, 2.0, 2.5, 3.0])
    f = res["end_fx"]
    assert f[3] > 0 and f[4] == pytest.approx(f[3], rel=1e-10) and f[5] == pytest.approx(f[3], rel=1e-10)
    assert f[7] == pytest.approx(f[1], rel=1e-8)       # back at factor 0.5: the same state as on the way up
    with pytest.raises(cm.JobError, match="n = 0"):
        cm.Step(0)
    with pytest.raises(cm.JobError, match="not an item of the job"):
        cm.Job(body, items, [cm.Step(1, ramp={cm.Pressure("top", 1.0): 1.0})]).run()


def test_a_mesh_made_with_dolfinx():
    """A strip made by dolfinx itself (create_rectangle, facet tags by hand) stretched by 1e-4 in
    plane stress, with rollers on its left and bottom edges: the uniaxial closed form, end force
    E eps H (the finite-strain terms are 1e-4 of it). A tag value that no facet carries is refused."""
    import dolfinx

    import comove_dolfinx as cm
    L, H, E, eps = 2.0, 0.5, 100.0, 1e-4
    msh = dolfinx.mesh.create_rectangle(MPI.COMM_WORLD, [np.array([0.0, 0.0]), np.array([L, H])], [8, 2],
                                        cell_type=dolfinx.mesh.CellType.triangle)
    edges = {1: lambda x: np.isclose(x[0], 0.0), 2: lambda x: np.isclose(x[0], L),
             3: lambda x: np.isclose(x[1], 0.0)}
    found = [(dolfinx.mesh.locate_entities_boundary(msh, 1, where), tag) for tag, where in edges.items()]
    facets = np.concatenate([f for f, _ in found])
    values = np.concatenate([np.full(len(f), tag, dtype=np.int32) for f, tag in found])
    order = np.argsort(facets)
    tags = dolfinx.mesh.meshtags(msh, 1, facets[order].astype(np.int32), values[order])
    mesh = cm.from_dolfinx(msh, tags, {"left": 1, "right": 2, "bottom": 3})
    body = cm.Body(mesh, "plane_stress", cm.Elastic(E, 0.3), update="sr")
    items = [cm.Fixed("left", component=0), cm.Fixed("bottom", component=1),
             cm.Displacement("right", eps * L, component=0)]
    res = cm.Job(body, items, [cm.Step(1)], [cm.Reaction("right", "end")]).run()
    assert res.completed
    assert res["end_fx"][-1] == pytest.approx(E * eps * H, rel=1e-3)
    with pytest.raises(cm.MeshError, match="no facet carries"):
        cm.from_dolfinx(msh, tags, {"left": 1, "top": 9})

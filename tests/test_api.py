"""The public API as a user meets it: the README's example runs as written and retraces its path,
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


def test_readme_example_runs_and_retraces(tmp_path):
    """A neo-Hookean pad under a frictionless punch is hyperelastic: the force is a function of the
    punch's position alone, so the release retraces the press increment by increment (to Newton's
    tolerance), the hold keeps the force, nothing is left once the punch is back, and the symmetric
    problem has no horizontal reaction."""
    text = (ROOT / "README.md").read_text()
    code = re.search(r"## Your own problem.*?```python\n(.*?)```", text, re.S).group(1)
    (tmp_path / "example.py").write_text(code)
    p = launch.run([tmp_path / "example.py"], cwd=tmp_path)
    assert p.returncode == 0, p.stdout + p.stderr
    assert "completed 18 increments" in p.stdout
    h = _history(tmp_path / "pad_history.csv")
    F = h["punch_force"]
    assert F.max() > 1.0
    press = F[(h["time"] > 0.0) & (h["time"] < 1.0)]             # factors 1/8 .. 7/8, going down
    release = F[(h["time"] > 2.0) & (h["time"] < 3.0)][::-1]     # the same factors, coming back up
    assert len(press) == len(release) == 7
    np.testing.assert_allclose(release, press, rtol=0, atol=1e-6 * F.max())
    assert np.all(np.diff(press) > 0)                            # the force grows as the punch goes down
    assert abs(F[-1]) < 1e-6 * F.max()
    assert np.all(np.abs(h["floor_fx"]) < 1e-6 * F.max())        # frictionless, symmetric
    held = (h["time"] > 1.0) & (h["time"] <= 2.0)
    np.testing.assert_allclose(F[held], F[h["time"] == 1.0][0], rtol=1e-8)


def test_problem_file_gives_the_ring_history(tmp_path):
    """demos/ring.toml describes the ring scene; it must give the stored history of `comove run ring`
    (same increments, same Newton iterations, every column to 1e-8 of its largest value)."""
    p = launch.run(["-m", "comove_dolfinx.cli", "run", ROOT / "demos" / "ring.toml", "--out", tmp_path,
                    "--no-progress"])
    assert p.returncode == 0, p.stdout + p.stderr
    new, ref = _history(tmp_path / "history.csv"), _history(REFERENCE / "ring.csv")
    assert len(new["increment"]) == len(ref["increment"])
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
    ("[mesh]\nbuilder = 'rectangle'\nL = 1.0\nH = 1.0\nsize = 0.5\n[body]\nkind = 'plane_strain'\n"
     "material = {E = 1.0, nu = 0.3}\n[[items]]\ntype = 'pressure'\nboundary = 'top'\np = 1.0\n"
     "[[steps]]\nrelease = ['pressure1']\n", "'pressure1' is not a support item"),
    ("[mesh]\nbuilder = 'rectangle'\nL = 1.0\nH = 1.0\nsize = 0.5\n[body]\nkind = 'plane_strain'\n"
     "material = {E = 1.0, nu = 0.3}\n[[items]]\ntype = 'contact'\nboundary = 'top'\n"
     "obstacle = {type = 'gmsh_profile', file = 'die.geo', curve = 'face', radius = 0.1}\n", "does not exist"),
    ("[mesh]\nbuilder = 'rectangle'\nL = 1.0\nH = 1.0\nsize = 0.5\n[body]\nkind = 'plane_strain'\n"
     "material = {E = 1.0, nu = 0.3}\n[[items]]\ntype = 'fixed'\nboundary = 'left'\n"
     "[[steps]]\nfirst = 0.3\n", "first = 0.3: give the first increment as 1, 0.5, 0.25"),
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


def _stretch_and_release(checkpoint=None, stop_after=None):
    """An elastic strip (plane stress, rollers on its left and bottom edges) stretched by a
    prescribed end displacement d in 2 increments, then let go: step 2 releases that support."""
    import comove_dolfinx as cm
    from comove_dolfinx.io.writers import Writer
    L, H, E, d = 2.0, 0.5, 100.0, 2e-4
    body = cm.Body(cm.rectangle(L, H, 0.25, order=2), "plane_stress", cm.Elastic(E, 0.3), update="sr")
    pull = cm.Displacement("right", d, component=0)
    items = [cm.Fixed("left", component=0), cm.Fixed("bottom", component=1), pull]

    class Stop(Writer):
        def write(self, run, row, increment):
            if stop_after is not None and row["increment"] == stop_after:
                raise RuntimeError("stopped by the test")
    writers = ([checkpoint] if checkpoint is not None else []) + [Stop()]
    probes = [cm.Reaction("right", "end"), cm.Reaction("left", "clamp"),
              cm.NodeDisplacement("tip", (L, H), component=0)]
    return cm.Job(body, items, [cm.Step(2), cm.Step(4, release=[pull])], probes, writers=writers), (E, H, L, d)


def test_a_released_support_lets_the_body_go_along_the_elastic_line(tmp_path):
    """Step 2 takes away the support that stretched the strip: its force (E d / L H at the end of
    step 1) becomes a nodal force ramped to zero, so the support reports no force, the clamp
    balances the ramped force exactly (equilibrium), and the end comes back along the elastic line
    u = (1 - s) d to the unstretched strip. A checkpoint taken inside the release step restarts
    to the same history; releasing what is not a support is refused."""
    import comove_dolfinx as cm
    from comove_dolfinx.io.checkpoint import Checkpoint
    job, (E, H, L, d) = _stretch_and_release()
    res = job.run()
    assert res.completed and len(res) == 6
    F1 = res["end_fx"][1]
    assert F1 == pytest.approx(E * d / L * H, rel=1e-3)
    s = res["time"][2:] - 1.0                                    # the release step's fraction
    assert np.all(np.abs(res["end_fx"][2:]) <= 1e-8 * F1)       # gone (Newton tolerance)
    np.testing.assert_allclose(res["clamp_fx"][2:], -(1.0 - s) * F1, atol=1e-8 * F1)
    np.testing.assert_allclose(res["tip_ux"][2:], (1.0 - s) * d, atol=1e-3 * d)
    # the same job run again: its new model starts with the support in place
    again = job.run()
    assert again.newton_its == res.newton_its
    np.testing.assert_allclose(again["end_fx"], res["end_fx"], rtol=0, atol=1e-12 * F1)
    # killed (here: a writer fails) in the middle of the release step, then restarted
    folder = tmp_path / "checkpoint"
    stopped, _ = _stretch_and_release(Checkpoint(folder, every=1, interval=0.0), stop_after=4)
    with pytest.raises(RuntimeError, match="stopped by the test"):
        stopped.run()
    again, _ = _stretch_and_release(Checkpoint(folder, every=1, interval=0.0))
    res2 = again.run(restart=folder)
    assert res2.completed and res2.newton_its == res.newton_its
    for col in ("end_fx", "clamp_fx", "tip_ux"):
        np.testing.assert_allclose(res2[col], res[col], rtol=0, atol=1e-12 * max(abs(res[col]).max(), 1e-300))
    # the same problem from a problem file: the same history
    from comove_dolfinx import problem
    toml = tmp_path / "release.toml"
    toml.write_text(
        "[mesh]\nbuilder = 'rectangle'\nL = 2.0\nH = 0.5\nsize = 0.25\norder = 2\n"
        "[body]\nkind = 'plane_stress'\nupdate = 'sr'\nmaterial = {E = 100.0, nu = 0.3}\n"
        "[[items]]\ntype = 'fixed'\nboundary = 'left'\ncomponent = 0\n"
        "[[items]]\ntype = 'fixed'\nboundary = 'bottom'\ncomponent = 1\n"
        "[[items]]\ntype = 'displacement'\nname = 'pull'\nboundary = 'right'\nvalue = 2e-4\ncomponent = 0\n"
        "[[steps]]\nn = 2\n[[steps]]\nn = 4\nrelease = ['pull']\n"
        "[[probes]]\ntype = 'reaction'\nboundary = 'left'\nname = 'clamp'\n")
    res3 = problem.build(problem.read(toml), MPI.COMM_WORLD).run()
    assert res3.completed and res3.newton_its == res.newton_its
    np.testing.assert_allclose(res3["clamp_fx"], res["clamp_fx"], rtol=0, atol=1e-12 * F1)
    with pytest.raises(cm.JobError, match="only supports"):
        pressure = cm.Pressure("top", 1.0)
        body = cm.Body(cm.rectangle(1.0, 1.0, 0.5), "plane_strain", cm.Elastic(1.0, 0.3))
        cm.Job(body, [cm.Fixed("bottom"), pressure], [cm.Step(1, release=[pressure])]).run()


@pytest.mark.mpi
def test_a_released_support_on_two_ranks():
    """The release of the test above on however many ranks run it: the same elastic line."""
    job, (E, H, L, d) = _stretch_and_release()
    res = job.run()
    F1 = res["end_fx"][1]
    s = res["time"][2:] - 1.0
    assert res.completed and F1 == pytest.approx(E * d / L * H, rel=1e-3)
    np.testing.assert_allclose(res["clamp_fx"][2:], -(1.0 - s) * F1, atol=1e-8 * F1)
    np.testing.assert_allclose(res["tip_ux"][2:], (1.0 - s) * d, atol=1e-3 * d)

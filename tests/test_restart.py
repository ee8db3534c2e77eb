"""A restart goes on only from a checkpoint of the same run: another scene, problem file or set of
parameters is refused in one line that names each difference, before anything in the folder is
touched; ``--allow-change`` lets named parameters change where the checkpoint can take it (a larger
final load goes on along the same path as a run to that load from the start)."""
import csv
import json
import subprocess
import sys

import launch
import numpy as np
import pytest

RUN = ["-m", "comove_dolfinx.cli", "run"]
# a small elastica: 3 increments to lam = 5
FIRST = ["--set", "n_increments=3", "--set", "size=0.25"]
# the command, with a check that dolfinx was never imported (a refusal comes before it)
LIGHT = ("import sys; from comove_dolfinx import cli; rc = cli.main(sys.argv[1:]); "
         "assert rc != 2 or 'dolfinx' not in sys.modules, 'dolfinx was imported'; sys.exit(rc)")


def _rows(path):
    with open(path, newline="") as fh:
        return list(csv.DictReader(fh))


def _command(args):
    return subprocess.run([sys.executable, "-c", LIGHT, *map(str, args)], capture_output=True, text=True,
                          env=launch.ENV, timeout=300)


def _files(out):
    """The bytes of every file of a run folder (the checkpoint's too)."""
    return {str(f.relative_to(out)): f.read_bytes() for f in sorted(out.rglob("*")) if f.is_file()}


@pytest.fixture(scope="module")
def elastica(tmp_path_factory):
    """A finished elastica run (3 increments to lam = 5) and the bytes of its folder."""
    out = tmp_path_factory.mktemp("restart") / "elastica"
    p = _command(["run", "elastica", "--out", out, "--no-progress", *FIRST])
    assert p.returncode == 0, p.stdout + p.stderr
    return out, _files(out)


@pytest.mark.parametrize("args, words", [
    # the --set of the first run forgotten: both named, with both values and the way back
    ([], ["n_increments 3 (now 10)", "size 0.25 (now 0.125)", "--set n_increments=3 --set size=0.25",
          "--allow-change n_increments to go on with the new value (size cannot change at a restart)"]),
    (FIRST + ["--set", "lam=8"], ["lam 5 (now 8)", "--allow-change lam"]),
    (FIRST + ["--set", "E=2000"], ["E 1000 (now 2000)"]),
    (FIRST + ["--set", "update=svk"], ["update 'sr' (now 'svk'): restart with --set update=sr (update cannot"]),
    # allowed, but meaningless: a final load below the one reached, another mesh
    (FIRST + ["--set", "lam=2", "--allow-change", "lam"], ["lam = 2 is short of the load the run has reached (5)"]),
    (["--set", "n_increments=3", "--set", "size=0.5", "--allow-change", "size"], ["size cannot change at a restart"]),
    (FIRST + ["--set", "lam=8", "--allow-change", "lam,colour"], ["--allow-change colour: not a parameter"]),
])
def test_a_restart_with_other_parameters_is_refused(elastica, args, words):
    """Exit code 2, one line naming each difference and the fix, no traceback, dolfinx never
    loaded, and the folder (history, run.json, checkpoint) exactly as it was."""
    out, before = elastica
    p = _command(["run", "elastica", "--out", out, "--no-progress", "--restart", *args])
    assert p.returncode == 2, p.stdout + p.stderr
    assert len(p.stderr.strip().splitlines()) == 1 and "Traceback" not in p.stderr, p.stderr
    for w in words:
        assert w in p.stderr, p.stderr
    assert _files(out) == before


def test_a_restart_of_another_scene_is_refused_before_the_folder_is_touched(elastica):
    """The beam pointed at the elastica's folder: refused (it used to rewrite history.csv with the
    beam's header and end in a KeyError)."""
    out, before = elastica
    p = _command(["run", "beam", "--out", out, "--no-progress", "--restart"])
    assert p.returncode == 2, p.stdout + p.stderr
    assert "holds a run of the scene 'elastica', not of the scene 'beam'" in p.stderr, p.stderr
    assert len(p.stderr.strip().splitlines()) == 1
    assert _files(out) == before


def test_a_larger_final_load_goes_on_along_the_same_path(tmp_path):
    """The elastica run to lam = 5 in 3 increments, then restarted to lam = 10 in increments of
    the same size (n_increments = 6): the history is that of the run to lam = 10 in 6 increments from
    the start (same Newton iterations, every column to 1e-10 of its largest value), and both
    summaries record the change."""
    out = tmp_path / "run"
    assert _command(["run", "elastica", "--out", out, "--no-progress", *FIRST]).returncode == 0
    new = ["--set", "n_increments=6", "--set", "size=0.25", "--set", "lam=10"]
    p = _command(["run", "elastica", "--out", out, "--no-progress", "--restart", *new,
                  "--allow-change", "lam", "--allow-change", "n_increments"])
    assert p.returncode == 0, p.stdout + p.stderr
    assert "warning: the restart goes on with lam 5 (now 10), n_increments 3 (now 6)" in p.stderr
    ref = tmp_path / "ref"
    assert _command(["run", "elastica", "--out", ref, "--no-progress", *new]).returncode == 0
    a, b = _rows(out / "history.csv"), _rows(ref / "history.csv")
    assert len(a) == len(b) == 6
    assert [r["newton_its"] for r in a] == [r["newton_its"] for r in b]
    for col in ("time", "load", "tip_ux", "tip_uy"):
        x, y = (np.array([float(r[col]) for r in rows]) for rows in (a, b))
        assert np.abs(x - y).max() <= 1e-10 * np.abs(y).max(), col
    change = [{"increment": 3, "parameters": {"lam": [5.0, 10.0], "n_increments": [3, 6]}}]
    info = json.loads((out / "run.json").read_text())
    assert info["status"] == "completed" and info["identity"]["changes"] == change
    meta = json.loads((out / "checkpoint" / "meta.json").read_text())
    assert meta["identity"]["parameters"]["lam"] == 10.0 and meta["identity"]["changes"] == change


def test_a_checkpoint_without_parameters_is_accepted_with_a_warning(tmp_path):
    """A checkpoint written before runs recorded their parameters: the restart cannot check them,
    says so in one warning line, and goes on."""
    out = tmp_path / "run"
    assert _command(["run", "elastica", "--out", out, "--no-progress", *FIRST]).returncode == 0
    meta_path = out / "checkpoint" / "meta.json"
    meta = json.loads(meta_path.read_text())
    for key in ("identity", "columns", "steps", "force_level"):
        del meta[key]
    meta_path.write_text(json.dumps(meta))
    p = _command(["run", "elastica", "--out", out, "--no-progress", "--restart", *FIRST])
    assert p.returncode == 0, p.stdout + p.stderr
    warnings = [line for line in p.stderr.splitlines() if "warning" in line]
    assert len(warnings) == 1 and "records no parameters" in warnings[0], p.stderr
    assert len(_rows(out / "history.csv")) == 3


PULL = """[mesh]
builder = "rectangle"
L = 2.0
H = 0.5
size = 0.25
order = 1

[body]
kind = "plane_strain"
update = "sr"
degree = 1
material = {{ E = {E}, nu = 0.3 }}

[[items]]
type = "fixed"
boundary = "left"

[[items]]
type = "displacement"
boundary = "right"
value = 0.05
component = 0

[[steps]]
n = 2

[[probes]]
type = "reaction"
boundary = "left"
name = "clamp"
"""


def test_a_problem_file_whose_content_changed_is_refused(tmp_path):
    """A problem file edited between the run and its restart: refused (its hash differs), unless
    --allow-change problem; a scene pointed at a problem file's folder: refused."""
    toml = tmp_path / "pull.toml"
    toml.write_text(PULL.format(E=100.0))
    out = tmp_path / "run"
    assert _command(["run", toml, "--out", out, "--no-progress"]).returncode == 0
    before = _files(out)
    toml.write_text(PULL.format(E=200.0))
    p = _command(["run", toml, "--out", out, "--no-progress", "--restart"])
    assert p.returncode == 2 and f"the problem file {toml}" in p.stderr and "--allow-change problem" in p.stderr, \
        p.stderr
    scene = _command(["run", "elastica", "--out", out, "--no-progress", "--restart"])
    assert scene.returncode == 2 and f"holds a run of the problem file {toml}" in scene.stderr, scene.stderr
    assert _files(out) == before
    ok = _command(["run", toml, "--out", out, "--no-progress", "--restart", "--allow-change", "problem"])
    assert ok.returncode == 0 and "goes on with changed content" in ok.stderr, ok.stdout + ok.stderr


def _strip_job(writers, size=0.5, probes=None):
    """An elastic strip pulled in 4 increments (the Python API)."""
    import comove_dolfinx as cm
    mesh = cm.rectangle(2.0, 0.5, size, order=1)
    body = cm.Body(mesh, "plane_strain", cm.Elastic(100.0, 0.3), update="svk", degree=1)
    probes = [cm.Reaction("left", "clamp")] if probes is None else probes
    return cm.Job(body, [cm.Fixed("left"), cm.Displacement("right", 0.05, component=0)], [cm.Step(4)],
                  probes=probes, writers=writers)


def test_the_api_refuses_a_checkpoint_of_another_job(tmp_path):
    """Job.run(restart=folder) with other history columns, or on another mesh: a JobError of one
    line that names the columns (or the mesh), raised before the writers touch their files."""
    import comove_dolfinx as cm
    from comove_dolfinx.io.checkpoint import Checkpoint
    folder, history = tmp_path / "checkpoint", tmp_path / "history.csv"
    assert _strip_job([cm.HistoryCSV(history), Checkpoint(folder)]).run().completed
    before = history.read_bytes()
    other = _strip_job([cm.HistoryCSV(history), Checkpoint(folder)],
                       probes=[cm.NodeDisplacement("end", (2.0, 0.0))])
    with pytest.raises(cm.JobError) as err:
        other.run(restart=folder)
    text = str(err.value)
    assert "\n" not in text and "clamp_fx, clamp_fy" in text and "end_ux, end_uy" in text, text
    finer = _strip_job([cm.HistoryCSV(history), Checkpoint(folder)], size=0.25)
    with pytest.raises(cm.JobError, match="nodes are not those of this job's mesh"):
        finer.run(restart=folder)
    assert history.read_bytes() == before
    again = _strip_job([cm.HistoryCSV(history), Checkpoint(folder)]).run(restart=folder)
    assert again.completed and len(again) == 4

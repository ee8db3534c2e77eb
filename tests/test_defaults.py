"""Increment control at its defaults: a failed increment retried from the other start before it is
halved, the failed attempts counted per cause (Results, run.json, the console), a stop message that
names what to change, and a job that prints nothing of the form compiler.

The bar: a round tensile bar (axisymmetric, finite-strain J2 with saturating hardening, half of it,
its radius 1.8 % smaller at the middle, pulled 7 mm), on a coarse mesh. Started from the last
converged state, an increment near 3 mm of pull gives an iterate whose stress update returns NaN,
and no smaller increment helps (halved six times it still stops near 3 mm); started from the linear
extrapolation of the last two states, every increment converges."""
import json
import logging
import subprocess
import sys
import textwrap

import launch
import numpy as np
import pytest
from mpi4py import MPI

import comove_dolfinx as cm
from comove_dolfinx.solver import failures

R, LH, PULL = 6.413, 26.667, 7.0


def _bar(cache, size=2.0):
    """Body and items of the bar (mm, GPa): radius R at the ends, 0.982 R at the middle (z = 0)."""
    md = cm.rectangle(R, LH, size, order=2, comm=MPI.COMM_WORLD, cache_dir=cache)
    x = md.mesh.geometry.x
    x[:, 0] *= 1.0 - 0.018 * (1.0 - x[:, 1] / LH)
    ep = np.concatenate([np.linspace(0.0, 0.1, 41), np.linspace(0.1, 1.0, 46)[1:], np.linspace(1.0, 4.0, 31)[1:]])
    sy = 0.45 + 0.12924 * ep + 0.265 * (1.0 - np.exp(-16.93 * ep))
    body = cm.Body(md, "axisymmetric", cm.J2(206.9, 0.29, cm.Hardening(ep, sy, tail_slope=0.12924)))
    return body, [cm.Fixed("left", component=0), cm.Fixed("bottom", component=1),
                  cm.Displacement("top", PULL, component=1)]


def _pull(cache, writers=(), **step):
    body, items = _bar(cache)
    return cm.Job(body, items, [cm.Step(20, **step)], probes=[cm.Reaction("top", "pull")],
                  writers=writers).run()


@pytest.fixture(scope="module")
def cache(tmp_path_factory):
    return str(tmp_path_factory.mktemp("meshes"))


def test_step_defaults_start_on_the_tangent_and_retry():
    step = cm.Step(5)
    assert step.predictor == "tangent" and step.retry is True
    with pytest.raises(cm.JobError, match="retry = 'yes'"):
        cm.Step(5, retry="yes")


def test_a_failed_increment_converges_on_the_retry_without_halving(cache, tmp_path):
    """From the last state one increment fails (NaN in the stress update); retried at the same size
    from the extrapolation it converges, no increment is halved, and the run ends where a run that
    extrapolates from the start ends (the same converged increments, to Newton's tolerance)."""
    out = tmp_path / "run.json"
    res = _pull(cache, writers=[cm.RunInfo(out), cm.Console("bar")], predictor="none")
    assert res.completed and len(res) == 20
    assert res.cutbacks == 0 and res.retries == 1
    assert res.failures == {failures.INADMISSIBLE: 1}
    ref = _pull(cache, predictor="linear")
    assert ref.completed and ref.failures == {} and ref.retries == 0
    assert res["pull_fy"][-1] == pytest.approx(ref["pull_fy"][-1], rel=1e-7)
    info = json.loads(out.read_text())
    assert info["failures"] == {"inadmissible": 1} and info["retries"] == 1 and info["cutbacks"] == 0


def test_without_the_retry_the_same_bar_stops_and_says_what_to_change(cache, tmp_path):
    """The bar from the last state without the retry: halving does not get past the NaN; the
    message names the remedies (more increments, a predictor), which the test above confirms."""
    out = tmp_path / "run.json"
    res = _pull(cache, writers=[cm.RunInfo(out)], predictor="none", retry=False, max_cutbacks=1)
    assert not res.completed and list(res.failures) == [failures.INADMISSIBLE]
    # every failed attempt was halved but the last one, which is the message's
    in_a_row = int(res.message.split("after ")[1].split(" cut-backs")[0])
    assert res.failures[failures.INADMISSIBLE] == res.cutbacks + in_a_row + 1
    assert "Step n = 40 instead of 20" in res.message and 'predictor="tangent"' in res.message
    assert "\n" not in res.message
    info = json.loads(out.read_text())
    assert info["status"] == "stopped" and info["failures"] == res.failures
    assert info["advice"] == res.advice and res.advice in res.message


def _sheared_block(max_it, cache):
    """An elastic square (plane strain), clamped at the bottom, its top moved by (0.5, 0.6) in one
    increment."""
    md = cm.rectangle(1.0, 1.0, 0.5, order=1, comm=MPI.COMM_WORLD, cache_dir=cache)
    body = cm.Body(md, "plane_strain", cm.Elastic(1000.0, 0.3), degree=1)
    items = [cm.Fixed("bottom"), cm.Displacement("top", (0.5, 0.6))]
    return cm.Job(body, items, [cm.Step(1, max_cutbacks=0)], newton=cm.NewtonSettings(max_it=max_it)).run()


def test_max_it_with_a_steadily_falling_residual_names_the_iterations_it_needs(cache):
    """Newton cut off while converging: the message says to raise max_it to a number, and at that
    number the same increment converges."""
    res = _sheared_block(3, cache)
    assert not res.completed and res.failures == {failures.MAX_IT: 1}
    assert "raise NewtonSettings.max_it from 3 to about" in res.message
    enough = int(res.message.split("to about ")[1].split()[0].rstrip(";,."))
    assert enough > 3
    ok = _sheared_block(enough, cache)
    assert ok.completed and ok.failures == {}


def test_advice_follows_the_cause():
    """One line each: a contact set that keeps switching asks for a softer penalty or more
    increments; a stalled residual under a force-controlled load names the limit load."""
    chatter = failures.Failure(failures.MAX_IT, "no convergence in 25 iterations",
                               [1.0, 0.5, 0.8, 0.4, 0.9, 0.5, 0.7], set_changes=4, max_it=25)
    text = failures.advice(chatter, contact=True, friction=True, n=10)
    assert "contact set kept switching (4 changes" in text and "lower gamma0" in text and "n = 20" in text
    assert "mu" in text and "\n" not in text
    stalled = failures.Failure(failures.MAX_IT, "no convergence", [1.0, 0.5, 0.6, 0.55, 0.6, 0.58], max_it=25)
    assert not stalled.steady
    assert "limit load" in failures.advice(stalled, force_controlled=True, n=10)
    assert "limit load" not in failures.advice(stalled, force_controlled=False, n=10)


def test_the_console_closes_with_the_failures(cache, capsys):
    res = _pull(cache, writers=[cm.Console("bar")], predictor="none")
    last = [line for line in capsys.readouterr().out.splitlines() if line.startswith("bar: completed")]
    assert res.retries == 1
    assert last and "1 failed attempt (inadmissible 1), 0 cut-backs, 1 retry" in last[0]


QUIET = textwrap.dedent("""
    import logging, sys
    mine = logging.getLogger("mine")
    mine.setLevel(logging.INFO)
    mine.propagate = False
    mine.addHandler(logging.StreamHandler(sys.stderr))
    mine.handlers[0].setFormatter(logging.Formatter("USER %(name)s %(message)s"))
    mine.info("before")
    import comove_dolfinx as cm
    md = cm.rectangle(1.0, 1.0, 0.5, order=1, cache_dir=sys.argv[1])
    body = cm.Body(md, "plane_strain", cm.Elastic(1000.0, 0.3), degree=1)
    res = cm.Job(body, [cm.Fixed("bottom"), cm.Displacement("top", (0.0, 0.01))], [cm.Step(2)]).run()
    assert res.completed, res.message
    logging.getLogger("mine").info("after")
    assert logging.getLogger().level == logging.WARNING
""")


def test_a_job_from_a_script_prints_nothing_of_the_form_compiler(tmp_path):
    """Forms compiled anew (an empty cache): stdout stays empty, and stderr has the script's own
    log lines (a logger of its own at INFO), before and after the run, and nothing else; the root
    logger keeps its level (the C build lowers it to INFO)."""
    script = tmp_path / "quiet.py"
    script.write_text(QUIET)
    env = dict(launch.ENV, XDG_CACHE_HOME=str(tmp_path / "cache"))
    p = subprocess.run([sys.executable, str(script), str(tmp_path / "meshes")], capture_output=True, text=True,
                       env=env, timeout=600, cwd=tmp_path)
    assert p.returncode == 0, p.stderr
    assert any((tmp_path / "cache").rglob("*.so"))           # it did compile
    assert p.stdout == ""
    assert p.stderr.splitlines() == ["USER mine before", "USER mine after"], p.stderr[:2000]


@pytest.mark.mpi
def test_the_retry_and_the_counts_are_the_same_on_two_ranks(cache):
    res = _pull(cache, predictor="none")
    assert res.completed and res.cutbacks == 0 and res.retries == 1
    assert res.failures == {failures.INADMISSIBLE: 1}
    assert MPI.COMM_WORLD.allgather(res.failures) == [res.failures] * MPI.COMM_WORLD.size


def test_the_filter_lets_the_users_records_through():
    from comove_dolfinx.process import _CompilerLines
    f = _CompilerLines()
    mine = logging.LogRecord("mine", logging.INFO, "/home/me/script.py", 1, "x", None, None)
    build = logging.LogRecord("root", logging.INFO, "/x/setuptools/_distutils/ccompiler.py", 1, "gcc", None, None)
    warn = logging.LogRecord("root", logging.WARNING, "/x/setuptools/_distutils/ccompiler.py", 1, "w", None, None)
    assert f.filter(mine) and not f.filter(build) and f.filter(warn)


def test_a_contact_set_that_keeps_switching_is_named_in_the_message(tmp_path):
    """The beam scene (coarse) pressed onto its foundation in 5 increments with a stiff penalty and
    no cut-back: its first increment runs out of iterations while the contact set changes from
    iterate to iterate. The message says so and asks for a softer penalty or more increments; the
    stability monitor, which records the contact set at every iterate on its own, saw at least as
    many changes over the whole solve."""
    from comove_dolfinx.presets import get_scene
    from comove_dolfinx.stability import Recorder
    scene = get_scene("beam", ["size=0.25", "gamma0=100000", "n_increments=5", "max_cutbacks=0"])
    job = scene.job(scene.mesh_data(MPI.COMM_WORLD))
    rec = Recorder()
    job.newton.monitor = rec
    res = job.run()
    assert not res.completed and res.failures == {failures.MAX_IT: 1}
    assert "the contact set kept switching (" in res.message
    assert "lower gamma0" in res.message and "Step n = 10 instead of 5" in res.message
    changes = int(res.message.split("kept switching (")[1].split(" changes")[0])
    assert 2 <= changes <= rec.last_failed_changes


class _StopAt(cm.Writer):
    """Ctrl-C once increment ``k`` has been written by the writers before this one."""

    def __init__(self, k):
        self.k = k

    def write(self, run, row, increment):
        if row["increment"] == self.k:
            raise KeyboardInterrupt("test")


def test_a_restart_goes_on_as_the_run_would_have(cache, tmp_path):
    """The bar's run from the last state (its one failed attempt retried from the extrapolation,
    which then starts every increment) interrupted after increment 12 and restarted from its
    checkpoint: the restart keeps the failed attempt of the run before and starts from the
    extrapolation as that run had come to, so that it repeats the uninterrupted run (the same
    Newton iterations in every increment, the same force)."""
    from comove_dolfinx.io.checkpoint import Checkpoint
    full = _pull(cache, predictor="none")
    retried = [k for k, inc in enumerate(full.increments) if inc.retries]
    assert full.failures == {failures.INADMISSIBLE: 1} and len(retried) == 1 and retried[0] < 11
    folder = tmp_path / "checkpoint"
    with pytest.raises(KeyboardInterrupt):
        _pull(cache, writers=[Checkpoint(folder, every=1, interval=0.0), _StopAt(12)], predictor="none")
    meta = json.loads((folder / "meta.json").read_text())
    assert meta["increment"] == 12 and meta["failures"] == {"inadmissible": 1}
    assert meta["resume"]["use_pred"] is True
    body, items = _bar(cache)
    again = cm.Job(body, items, [cm.Step(20, predictor="none")], probes=[cm.Reaction("top", "pull")]).run(
        restart=folder)
    assert again.completed and again.failures == full.failures
    assert again.newton_its == full.newton_its
    assert again["pull_fy"][-1] == pytest.approx(full["pull_fy"][-1], rel=1e-12)


def test_a_step_under_loads_alone_is_force_controlled():
    """The limit-load hint is given only when nothing but loads move: a pressure against a fixed
    support and a fixed obstacle is force-controlled; a prescribed displacement or an obstacle that
    moves with its factor controls the motion."""
    from comove_dolfinx.solver.failures import force_controlled
    floor = cm.Plane((0.0, -3.0), (0.0, 1.0))
    assert force_controlled([cm.Fixed("left"), cm.Pressure("top", 0.5), cm.Contact("bottom", floor)])
    assert not force_controlled([cm.Fixed("left"), cm.Pressure("top", 0.5), cm.Displacement("right", 0.1, component=0)])
    punch = cm.Plane((0.0, 1.0), (0.0, -1.0), motion=(0.0, -0.5))
    assert not force_controlled([cm.Fixed("bottom"), cm.Pressure("right", 0.1), cm.Contact("top", punch)])
    assert not force_controlled([cm.Fixed("left")])                  # nothing loads the body

"""Runs that are killed, interrupted or pointed at a folder in use: every converged increment stays
readable (history, one .vtu per increment, a run.json that says the run is incomplete), SIGTERM and
Ctrl-C end with one line and their exit codes, and no run writes into another's folder or mixes its
files with an earlier run's."""
import csv
import fcntl
import json
import os
import shutil
import signal
import subprocess
import time
import xml.etree.ElementTree as ET

import launch
import pytest

RUN = ["-m", "comove_dolfinx.cli", "run"]


def _rows(path):
    with open(path, newline="") as fh:
        return list(csv.DictReader(fh))


def _start(out, scene="ring", sets=("n_increments=200",)):
    args = [*RUN, scene, "--out", out, "--no-progress"]
    for s in sets:
        args += ["--set", s]
    return subprocess.Popen(launch.command(args), stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True, env=launch.ENV)


def _wait_rows(p, history, n, timeout=300):
    t0 = time.time()
    while time.time() - t0 < timeout:
        if history.exists() and len(_rows(history)) >= n:
            return
        assert p.poll() is None, p.communicate()
        time.sleep(0.05)
    raise AssertionError("the run did not converge enough increments in time")


def _check_readable(out):
    """Every increment listed in the .pvd reads back; the history's rows are complete."""
    import meshio
    rows = _rows(out / "history.csv")
    files = [d.get("file") for d in ET.parse(out / "results.pvd").getroot().iter("DataSet")]
    # every row has its dataset (written first); a kill between them leaves one dataset more
    assert len(rows) <= len(files) <= len(rows) + 1 and len(rows) >= 1
    for f in files:
        m = meshio.read(out / f)
        assert "displacement" in m.point_data and "plastic_strain_cell_avg" in m.cell_data
    for r in rows:
        assert all(v not in (None, "") for v in r.values()), r
    return rows, json.loads((out / "run.json").read_text()), files


@pytest.mark.parametrize("sig", [signal.SIGKILL, signal.SIGTERM, signal.SIGINT])
def test_killed_or_interrupted_run_keeps_its_increments(tmp_path, sig):
    out = tmp_path / "run"
    p = _start(out)
    _wait_rows(p, out / "history.csv", 4)
    p.send_signal(sig)
    stdout, stderr = p.communicate(timeout=120)
    rows, info, files = _check_readable(out)
    assert not info["completed"]
    if sig == signal.SIGKILL:
        assert p.returncode == -signal.SIGKILL
        assert info["status"] == "running"                 # it never got to say more
    else:
        assert p.returncode == (143 if sig == signal.SIGTERM else 130), stderr
        assert info["status"] == "interrupted" and info["increments"] == len(rows)
        assert "Traceback" not in stderr and len(stderr.strip().splitlines()) == 1, stderr
        assert "interrupted" in stderr
        # a signal waits while an increment goes to the writers, so the files agree on the last
        # increment: its row, its dataset and the checkpoint saved on the way out (the default
        # interval between saves is longer than this run)
        meta = json.loads((out / "checkpoint" / "meta.json").read_text())
        assert len(rows) >= 4 and len(files) == len(rows) and meta["increment"] == len(rows)


def test_two_runs_started_together_cannot_both_take_a_folder(tmp_path, monkeypatch):
    """Both runs passed their checks before either took the folder: the second to take it is
    refused and the first keeps its lock; once the first ends, the folder is free again."""
    from comove_dolfinx.io import folder
    lock = tmp_path / "run" / ".lock"
    first, second = folder.RunFolder(tmp_path / "run"), folder.RunFolder(tmp_path / "run")
    monkeypatch.setattr(folder, "check", lambda *args, **kwargs: None)
    first._take()
    with pytest.raises(folder.FolderError, match="another run"):
        second._take()
    assert folder._holder(lock) == os.getpid()
    first.__exit__(None, None, None)
    assert not lock.exists() and folder._holder(lock) is None
    second._take()
    assert folder._holder(lock) == os.getpid()
    second.__exit__(None, None, None)


def test_a_folder_in_use_or_with_old_results_is_refused(tmp_path):
    out = tmp_path / "run"
    first = launch.run([*RUN, "elastica", "--out", out, "--no-progress", "--set", "n_increments=4"])
    assert first.returncode == 0, first.stderr
    again = launch.run([*RUN, "elastica", "--out", out, "--no-progress", "--set", "n_increments=2"])
    assert again.returncode == 2 and "--overwrite" in again.stderr and "Traceback" not in again.stderr
    assert len(_rows(out / "history.csv")) == 4                       # untouched
    over = launch.run([*RUN, "elastica", "--out", out, "--no-progress", "--set", "n_increments=2",
                       "--overwrite"])
    assert over.returncode == 0, over.stderr
    assert len(_rows(out / "history.csv")) == 2
    assert sorted(f.name for f in out.glob("results_*.vtu")) == ["results_00000.vtu", "results_00001.vtu"]
    # a live run's lock (held by this test's own process) is refused; the file a killed run left
    # (no process holds it) is taken over
    with open(out / ".lock", "w") as held:
        held.write(f"{os.getpid()}\n")
        held.flush()
        fcntl.flock(held, fcntl.LOCK_EX)
        busy = launch.run([*RUN, "elastica", "--out", out, "--no-progress", "--overwrite"])
    assert busy.returncode == 2 and f"another run (process {os.getpid()})" in busy.stderr, busy.stderr
    (out / ".lock").write_text(f"{os.getpid()}\n")                    # a pid alone holds nothing
    stale = launch.run([*RUN, "elastica", "--out", out, "--no-progress", "--overwrite", "--set", "n_increments=1"])
    assert stale.returncode == 0, stale.stderr
    assert not (out / ".lock").exists()
    afile = tmp_path / "a_file"
    afile.write_text("x")
    bad = launch.run([*RUN, "elastica", "--out", afile, "--no-progress"])
    assert bad.returncode == 2 and "not a folder" in bad.stderr
    # results without a checkpoint (as a run killed before its first save leaves them): --restart
    # is refused with the way out, and the results are left as they were
    shutil.rmtree(out / "checkpoint")
    norestart = launch.run([*RUN, "elastica", "--out", out, "--no-progress", "--restart"])
    assert norestart.returncode == 2 and "--overwrite instead of --restart" in norestart.stderr, norestart.stderr
    assert len(_rows(out / "history.csv")) == 1


def test_guards_stop_folding_and_warn_of_untrustworthy_results(tmp_path):
    """The ring crushed to delta = 10 folds elements at their nodes near the end (the quadrature
    points alone let it pass before): the run cuts back, then stops with a message, and it has said
    that the plastic strain left the hardening table (last point 0.5). A mesh of one element across
    the wall lets the plate sink into it by a few percent of the element: warned."""
    out = tmp_path / "fold"
    p = launch.run([*RUN, "ring", "--out", out, "--no-progress", "--set", "delta_max=10"])
    assert p.returncode == 1, p.stdout + p.stderr
    assert "element folds" in p.stderr and "Traceback" not in p.stderr
    info = json.loads((out / "run.json").read_text())
    assert info["status"] == "stopped" and "element folds" in info["message"]
    rows = _rows(out / "history.csv")
    assert 0.9 < float(rows[-1]["time"]) < 1.0
    assert [w for w in info["warnings"] if w.startswith("plastic strain")]
    assert "warning: plastic strain" in p.stdout
    coarse = launch.run([*RUN, "ring", "--out", tmp_path / "coarse", "--no-progress", "--set", "size=100"])
    assert coarse.returncode == 0
    assert "warning: penetration" in coarse.stdout


@pytest.mark.parametrize("n, n_restart", [(1, 1), (2, 2), (1, 2)])
def test_restart_repeats_the_uninterrupted_run(tmp_path, n, n_restart):
    """The ring killed (kill -9) after a dozen increments and restarted from its last checkpoint
    (--restart, on the same ranks or on two after a serial start) gives the history of the
    uninterrupted run on the restart's ranks: the same increments and Newton iterations, every
    column to 1e-12 of its largest value in serial (1e-6 on two ranks, where the parallel direct
    solver's round-off differs from run to run)."""
    import tempfile

    import numpy as np

    from comove_dolfinx.presets import get_scene
    ring = get_scene("ring", [])
    # the ring's default run: 36 nominal increments, the first taken in four, 1/8, 1/8, 1/4 and 1/2
    # of it (first = 0.125, doubled back after easy increments), so 39 increments
    incs = 39
    out = tmp_path / "run"
    # The killed launcher cannot remove its session directory (Open MPI's, under TMPDIR, named by its
    # pid), and a later mpirun that gets the same pid refuses to start (PRRTE: PMIX_ERR_EXISTS). So
    # the killed run gets a TMPDIR of its own, removed below; short, as it holds PMIx's sockets.
    mpi_tmp = tempfile.mkdtemp(prefix="comove-")
    try:
        p = subprocess.Popen(launch.command([*RUN, "ring", "--out", out, "--no-progress",
                                             "--checkpoint-interval", "0"], n=n),
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                             env=dict(launch.ENV, TMPDIR=mpi_tmp), start_new_session=True)
        _wait_rows(p, out / "history.csv", 12)
        # the launcher and every rank (Open MPI puts ranks in sessions of their own), as a crash would
        os.killpg(p.pid, signal.SIGKILL)
        subprocess.run(["pkill", "-9", "-f", str(out)], check=False)
        p.communicate(timeout=60)
        for _ in range(100):                       # until no process of the run is left
            if subprocess.run(["pgrep", "-f", str(out)], capture_output=True).returncode != 0:
                break
            time.sleep(0.05)
    finally:
        shutil.rmtree(mpi_tmp, ignore_errors=True)
    meta = json.loads((out / "checkpoint" / "meta.json").read_text())
    assert 10 <= meta["increment"] < incs          # the kill may land between the history and the checkpoint
    r = launch.run([*RUN, "ring", "--out", out, "--no-progress", "--restart"], n=n_restart)
    assert r.returncode == 0, r.stdout + r.stderr
    # the uninterrupted run on this platform (the stored history agrees with it to the tolerance
    # of test_histories: the dolfinx versions round differently)
    full = launch.run([*RUN, "ring", "--out", tmp_path / "full", "--no-progress"], n=n_restart)
    assert full.returncode == 0, full.stdout + full.stderr
    new = _rows(out / "history.csv")
    ref = _rows(tmp_path / "full" / "history.csv")
    assert len(new) == len(ref) == incs
    assert [r["newton_its"] for r in new] == [r["newton_its"] for r in ref]
    tol = 1e-12 if n == n_restart == 1 else 1e-6
    for col in ("force", "contact_width", "crown_gap", "max_plastic_strain"):
        a, b = (np.array([float(r[col]) for r in rows]) for rows in (new, ref))
        assert np.abs(a - b).max() <= tol * np.abs(b).max(), col
    files = [d.get("file") for d in ET.parse(out / "results.pvd").getroot().iter("DataSet")]
    assert len(files) == incs and len(set(files)) == incs
    info = json.loads((out / "run.json").read_text())
    assert info["status"] == "completed" and info["first_contact_load"] == pytest.approx(
        ring.delta_max / ring.n_increments * ring.first)       # the plate starts tangent to the crown
    # the uninterrupted run with the default interval between checkpoints (longer than the run)
    # saved its last increment when it ended, and nothing older is left
    meta = json.loads((tmp_path / "full" / "checkpoint" / "meta.json").read_text())
    assert meta["increment"] == incs
    assert sorted(f.name for f in (tmp_path / "full" / "checkpoint").glob("state_*")) == \
        [f"state_{incs:05d}_rank{r}.npz" for r in range(n_restart)]


def test_checkpoint_arrays_keep_their_shape_and_type():
    """The checkpoint's archive (all arrays in one buffer and their layout) gives back every array
    as it was: 0-d numbers stay 0-d (a restart takes float() of them), and shapes and types hold."""
    import numpy as np

    from comove_dolfinx.io.checkpoint import _pack, _unpack
    arrays = {"load": np.asarray(0.25), "i": np.asarray(7), "d": np.array([0.0, -0.1875]),
              "X": np.arange(12.0).reshape(6, 2)[::2], "flags": np.array([True, False, True]),
              "empty": np.zeros((0, 4))}
    layout, data = _pack(arrays)
    back = _unpack(layout, data)
    assert set(back) == set(arrays)
    for k, a in arrays.items():
        assert back[k].shape == a.shape and back[k].dtype == a.dtype and np.array_equal(back[k], a), k
    assert float(back["load"]) == 0.25


def _interrupted(first_writer=None, monitor=None):
    """An elastic strip pulled in 5 increments, in this process, and a Ctrl-C sent by a writer that
    comes before the others or by the Newton monitor: (the increments the last writer got, what the
    writers' close saw: interrupted and the number of rows)."""
    import comove_dolfinx as cm
    from comove_dolfinx.io import Writer

    class Record(Writer):
        def __init__(self):
            self.increments, self.closed = [], None

        def write(self, run, row, inc):
            self.increments.append(row["increment"])

        def close(self, run, results):
            self.closed = (results.interrupted, len(results.rows))

    mesh = cm.rectangle(2.0, 0.5, 0.5, order=1)
    body = cm.Body(mesh, "plane_strain", cm.Elastic(100.0, 0.3), update="svk", degree=1)
    record = Record()
    job = cm.Job(body, [cm.Fixed("left"), cm.Displacement("right", 0.2, component=0)], [cm.Step(5)],
                 writers=[w for w in (first_writer, record) if w is not None],
                 newton=cm.NewtonSettings(monitor=monitor))
    # Python's Ctrl-C handler, as in a fresh interpreter (a gmsh session of another test, in this
    # process, may have left the system's default action, which would end pytest itself)
    before = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        with pytest.raises(KeyboardInterrupt):
            job.run()
    finally:
        signal.signal(signal.SIGINT, before)
    return record.increments, record.closed


def test_a_signal_waits_until_the_increment_is_written():
    """Ctrl-C arriving while a converged increment goes to the writers (here sent by the first
    writer itself) ends the run only after the last writer has it: the files of an interrupted run
    never disagree on its last increment. Without the wait the last writer misses increment 2."""
    from comove_dolfinx.io import Writer

    class Kick(Writer):
        def write(self, run, row, inc):
            if row["increment"] == 2:
                signal.raise_signal(signal.SIGINT)

    assert _interrupted(first_writer=Kick()) == ([1, 2], (True, 2))


class KickInNewton:
    """A Newton monitor that sends this process Ctrl-C after the first correction of increment 3
    (on one MPI rank only if ``rank`` is given)."""

    def __init__(self, rank=None):
        self.rank, self.increments = rank, 0

    def iteration(self, newton, it, rnorm):
        if self.increments == 2 and it == 1 and self.rank in (None, newton.model.comm.rank):
            signal.raise_signal(signal.SIGINT)

    def solved(self, newton, ok, its, reason):
        self.increments += ok


def test_a_signal_during_newton_stops_at_the_next_iteration():
    """Ctrl-C in the middle of an increment's Newton iterations (sent by the monitor after the
    first correction of increment 3) ends the run at the next iteration: increment 3 reaches no
    writer, the first two are complete. (On two ranks, with the signal on one of them only:
    test_parallel_failures.)"""
    assert _interrupted(monitor=KickInNewton()) == ([1, 2], (True, 2))


def test_building_a_mesh_keeps_pythons_ctrl_c_handler():
    """Gmsh sets Ctrl-C to the system's default action (4.8 on import, 4.13 in initialize, and
    4.13 never gives it back): the builders and the .msh reader keep whatever handler Python had,
    so an interrupted run still ends cleanly with its increments written."""
    import comove_dolfinx as cm
    import comove_dolfinx.geometry  # noqa: F401  (gmsh imported before the handler is set)

    def mine(signum, frame):
        raise KeyboardInterrupt

    before = signal.signal(signal.SIGINT, mine)
    try:
        cm.rectangle(1.0, 0.25, 0.25, order=1)             # gmsh starts at least to read the cache
        assert signal.getsignal(signal.SIGINT) is mine
    finally:
        signal.signal(signal.SIGINT, before)


def test_a_rank_without_a_python_handler_still_stops():
    """A signal recorded elsewhere (on another rank: simulated by setting it pending) for which this
    rank has no Python handler (SIGTERM at the system's default) still stops this rank, with
    KeyboardInterrupt naming it; a handler that returns lets the job go on."""
    from mpi4py import MPI

    from comove_dolfinx.parallel import Interrupts

    before = signal.signal(signal.SIGTERM, signal.SIG_DFL)
    try:
        with pytest.raises(KeyboardInterrupt, match="SIGTERM"):
            with Interrupts(MPI.COMM_SELF) as it:
                it.pending = int(signal.SIGTERM)
                it.check()
        seen = []
        signal.signal(signal.SIGTERM, lambda signum, frame: seen.append(signum))
        with Interrupts(MPI.COMM_SELF) as it:
            signal.raise_signal(signal.SIGTERM)         # recorded, not acted on yet
            assert seen == [] and it.pending == signal.SIGTERM
            it.check()
            assert seen == [signal.SIGTERM] and it.pending == 0
    finally:
        signal.signal(signal.SIGTERM, before)

"""A run that ends for a reason that is not a bug (Ctrl-C at any moment of its start-up or run, a
full disk, input that PETSc refuses) ends with one line and its exit code, never a traceback, and
leaves a run.json (if it wrote one) that says how it ended and no temporary file; on two MPI ranks
too, where nothing waits for ever."""
import errno
import json
import signal
import subprocess
import time

import launch
import pytest

# an elastica of 1000 small increments: it runs longer than the latest signal below
LONG = ["-m", "comove_dolfinx.cli", "run", "elastica", "--no-progress", "--set", "n_increments=1000",
        "--set", "size=0.25"]
DELAYS = [0.2, 0.5, 0.8, 1.2, 1.6, 2.0, 3.0]


def _interrupt(out, delay, n=1, after_first_line=False):
    """Start the long run on n ranks, send the launcher Ctrl-C after ``delay`` seconds (or as soon
    as the first console line is out); (exit code, stdout, stderr). A run that does not end within
    two minutes of the signal fails the test (a deadlock)."""
    p = subprocess.Popen(launch.command([*LONG, "--out", out], n=n), stdout=subprocess.PIPE,
                         stderr=subprocess.PIPE, text=True, env=launch.ENV)
    first = ""
    if after_first_line:
        first = p.stdout.readline()
        assert first, p.communicate()
    else:
        time.sleep(delay)
    p.send_signal(signal.SIGINT)
    try:
        stdout, stderr = p.communicate(timeout=120)
    except subprocess.TimeoutExpired:
        p.kill()
        p.communicate()
        raise AssertionError(f"the run did not end after Ctrl-C at {delay} s (n = {n})") from None
    return p.returncode, first + stdout, stderr


def _before_the_command(stderr) -> bool:
    """Whether the signal came before the command had installed its handler (the interpreter's
    start, its site imports, the first lines of the command), where Python's own handling is all
    there is: a traceback of a KeyboardInterrupt that Python's default handler raised (the
    command's handler, ``on_signal``, is not in it), or nothing at all (ranks that mpirun's SIGTERM
    ended first)."""
    if stderr.startswith("comove:"):
        return False
    return not stderr.strip() or (stderr.rstrip().endswith("KeyboardInterrupt") and "in on_signal" not in stderr)


def _status(out):
    """run.json's status, or None without one."""
    path = out / "run.json"
    return json.loads(path.read_text())["status"] if path.exists() else None


@pytest.mark.parametrize("delay", DELAYS)
def test_ctrl_c_at_any_moment_ends_with_one_line(tmp_path, delay):
    """From the imports (0.2 s) through the mesh and the form compiler to the increments (3 s):
    exit code 130, one line on stderr, no traceback, and run.json, if the run got to write it,
    says interrupted (it once said running for ever when the signal came before the first
    increment, and the process died without a word or with a traceback in 6 of 13 tries)."""
    out = tmp_path / "run"
    code, _, stderr = _interrupt(out, delay)
    if _before_the_command(stderr) and not out.exists():
        pytest.skip(f"the signal at {delay} s came while the interpreter was starting (a loaded machine)")
    assert code == 130, stderr
    assert "Traceback" not in stderr and len(stderr.strip().splitlines()) == 1, stderr
    assert stderr.startswith("comove: interrupted (Ctrl-C)"), stderr
    assert _status(out) in (None, "interrupted")
    assert not [f for f in out.rglob(".*") if f.name.endswith((".tmp", ".tmp.npz"))]


def test_ctrl_c_before_the_first_increment_leaves_run_json_interrupted(tmp_path):
    """Ctrl-C as soon as the run's first console line is out (run.json then says running, the
    solver and the first increment are still to come): run.json says interrupted."""
    for k in range(3):
        out = tmp_path / f"run{k}"
        code, stdout, stderr = _interrupt(out, 0.0, after_first_line=True)
        assert stdout.startswith("elastica:") and code == 130, stdout + stderr
        info = json.loads((out / "run.json").read_text())
        assert info["status"] == "interrupted" and not info["completed"], info
        assert info["message"].startswith("interrupted (Ctrl-C)"), info["message"]


@pytest.mark.parametrize("delay", [0.5, 1.2, 2.0, 3.0])
def test_ctrl_c_on_two_ranks_ends_every_rank(tmp_path, delay):
    """Under mpirun, Ctrl-C reaches the ranks as SIGTERM (Open MPI's launcher forwards it so)
    wherever each stands: every rank ends (no deadlock: the launcher returns), with a non-zero code
    and no traceback. What the ranks write after the signal reaches the terminal only if the
    launcher still passes it on (Open MPI 5's stops at the signal; Open MPI 4's may end the ranks
    first on a loaded machine); where rank 0's one line arrives, run.json says interrupted."""
    out = tmp_path / "run"
    code, _, stderr = _interrupt(out, delay, n=2)
    assert code != 0
    assert "Traceback" not in stderr, stderr
    if [line for line in stderr.splitlines() if line.startswith("comove: interrupted")]:
        assert _status(out) in (None, "interrupted")


@pytest.mark.mpi
def test_a_full_disk_ends_the_run_with_one_line(mpi_tmp, comm, monkeypatch, capsys):
    """A write that fails with ENOSPC at the third increment (rank 0's history file here, after it
    has begun a temporary file; on two ranks the other rank learns it at the same point): exit code
    1 on every rank, one line naming the file and the fix, run.json says failed with that message,
    the temporary file is gone and the two increments before are kept."""
    from comove_dolfinx import cli
    from comove_dolfinx.io import writers
    out = mpi_tmp / "run"
    write, rows = writers.HistoryCSV._write, []

    def full(self, values):                 # rank 0's part of the history's writer
        rows.append(values)
        if len(rows) == 3:
            (out / ".history.csv.tmp").write_text("half a row")
            raise OSError(errno.ENOSPC, "No space left on device", str(out / "history.csv"))
        write(self, values)
    monkeypatch.setattr(writers.HistoryCSV, "_write", full)
    code = cli.main(["run", "elastica", "--out", str(out), "--no-progress", "--set", "n_increments=5",
                     "--set", "size=0.25"])
    err = capsys.readouterr().err
    assert code == 1
    comm.barrier()
    if comm.rank == 0:
        assert len(err.strip().splitlines()) == 1, err
        assert f"cannot write {out / 'history.csv'}: No space left on device (ENOSPC): free some space" in err
    info = json.loads((out / "run.json").read_text())
    assert info["status"] == "failed" and "No space left on device" in info["message"]
    assert not list(out.glob(".*.tmp"))
    assert len((out / "history.csv").read_text().splitlines()) == 3      # the header and two rows


def test_options_that_petsc_refuses_end_with_one_line(tmp_path):
    """A problem file whose linear solver options PETSc refuses (an unknown preconditioner): exit
    code 2, one line with PETSc's reason, run.json says failed."""
    toml = tmp_path / "pull.toml"
    toml.write_text('[mesh]\nbuilder = "rectangle"\nL = 2.0\nH = 0.5\nsize = 0.5\norder = 1\n'
                    '[body]\nkind = "plane_strain"\ndegree = 1\nmaterial = { E = 100.0, nu = 0.3 }\n'
                    '[[items]]\ntype = "fixed"\nboundary = "left"\n'
                    '[[items]]\ntype = "displacement"\nboundary = "right"\nvalue = 0.05\ncomponent = 0\n'
                    '[newton]\npetsc_options = { pc_type = "nosuch" }\n')
    out = tmp_path / "run"
    p = launch.run(["-m", "comove_dolfinx.cli", "run", toml, "--out", out, "--no-progress"])
    assert p.returncode == 2 and "Traceback" not in p.stderr, p.stderr
    assert len(p.stderr.strip().splitlines()) == 1 and "PC type nosuch" in p.stderr, p.stderr
    info = json.loads((out / "run.json").read_text())
    assert info["status"] == "failed" and "pc_type=nosuch" in info["message"]

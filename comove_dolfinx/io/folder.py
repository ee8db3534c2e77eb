"""A run's output folder: one run at a time, and never the files of two runs mixed.

``RunFolder(path, overwrite)`` (a context manager, collective) takes the folder for a run:

* a folder that another live run holds is refused: the run holds an exclusive ``flock`` on the
  folder's ``.lock`` (which names its process) for as long as it runs, and the system releases it
  when the process ends in any way, so a lock file left by a run that was killed is free and is
  taken over; two runs started together cannot both take the folder (the lock is taken atomically,
  after the checks);
* a folder that holds the results of an earlier run is refused unless ``overwrite``, which first
  removes those results (history, run summary, VTK and XDMF files, checkpoints), so that no file of
  the old run sits beside the new one;
* a path that exists but is not a folder, or cannot be written, is refused.

:func:`check` asks the same without writing anything (the command, before it loads dolfinx).
The refusals are :class:`FolderError` with the path and the fix; every rank raises the same.

A run that ends by an exception (Ctrl-C or SIGTERM, a full disk, an error of PETSc or of the input)
leaves a ``run.json`` that says so: if this run wrote the folder's ``run.json`` and it still says
``running`` (the signal came before the job's writers could close) or the exception came after the
writers closed, ``status`` becomes ``interrupted`` (a signal) or ``failed`` (an error) with the
one-line ``message`` of :func:`failure_line`; the temporary files of interrupted writes are removed.
"""
from __future__ import annotations

import errno
import fcntl
import json
import os
import pathlib
import shutil

RESULTS = ("history.csv", "run.json", "results.pvd", "results.xdmf", "results.h5")
RESULT_GLOBS = ("results_*.vtu", ".results_*.tmp", "checkpoint")
#: the temporary names of files being written (renamed into place once complete)
TEMPORARY_GLOBS = (".*.tmp", "checkpoint/.*.tmp.npz", "checkpoint/.*.tmp")


class FolderError(ValueError):
    """An output folder that cannot be used; the message names it and the fix."""


def _holder(lock: pathlib.Path) -> int | None:
    """The process holding the lock ``lock`` (its pid as the file names it, -1 if unreadable), or None
    when no live process holds it (no file, or one left by a run that ended or was killed)."""
    try:
        fd = os.open(lock, os.O_RDONLY)
    except OSError:
        return None
    try:
        fcntl.flock(fd, fcntl.LOCK_SH | fcntl.LOCK_NB)
        return None
    except BlockingIOError:
        try:
            return int(os.read(fd, 64).split()[0])
        except (ValueError, IndexError, OSError):
            return -1
    finally:
        os.close(fd)                         # (releases the shared lock if it was taken)


def _busy(p: pathlib.Path, pid: int) -> str:
    who = f"process {pid}" if pid > 0 else "a process"
    return f"--out {p}: another run ({who}) is writing there: wait for it or choose another folder"


def _old_results(p: pathlib.Path) -> list[str]:
    return [f for f in RESULTS if (p / f).exists()] + [g.name for pat in RESULT_GLOBS for g in p.glob(pat)]


def check(path, overwrite: bool = False, restart: bool = False, lock: bool = True) -> str | None:
    """Why ``path`` cannot take a run (the message, naming the fix), or None; reads, never writes
    (the standard library only: the command asks before it loads dolfinx). ``lock=False``: whether
    another run holds the folder is not asked; the command's ranks other than 0 do so, since rank 0
    of their own run may hold it already (it takes the lock before the other ranks join it), and
    rank 0's answer is every rank's when the run takes the folder."""
    p = pathlib.Path(path)
    if p.exists() and not p.is_dir():
        return f"--out {p}: this is a file, not a folder: choose a folder"
    parent = p
    while not parent.exists() and parent != parent.parent:
        parent = parent.parent
    if not parent.is_dir():
        return f"--out {p}: cannot create the folder ({parent} is a file): choose another place"
    if not os.access(parent, os.W_OK | os.X_OK):
        return f"--out {p}: {'the folder' if parent == p else parent} is not writable: choose another place"
    pid = _holder(p / ".lock") if lock else None     # (a folder still to be made has no lock and no results)
    if pid is not None:
        return _busy(p, pid)
    old = _old_results(p)
    if restart:
        if not (p / "checkpoint" / "meta.json").exists():
            return f"--out {p}: no checkpoint to restart from" + (
                " (none was saved: a run killed within its first --checkpoint-interval seconds leaves "
                "none): run it again with --overwrite instead of --restart" if old else ": run without --restart")
    elif old and not overwrite:
        return (f"--out {p}: holds the results of an earlier run ({', '.join(sorted(old)[:3])}"
                f"{', ...' if len(old) > 3 else ''}): pass --overwrite to replace them, or choose another folder")
    return None


def failure_line(err: BaseException) -> str:
    """One line that says why a run ended by the exception ``err`` and, for a failed write, what
    to do."""
    if isinstance(err, KeyboardInterrupt):
        return f"interrupted ({str(err) or 'Ctrl-C'})"
    if isinstance(err, BrokenPipeError):
        return "the output's pipe was closed (the command's lines went to a reader that ended): go on with --restart"
    if isinstance(err, OSError) and err.strerror:
        where = f" {err.filename}" if err.filename else ""
        fix = ("free some space, or choose another --out, then go on with --restart"
               if err.errno in (errno.ENOSPC, errno.EDQUOT) else "check the folder, then go on with --restart")
        return f"cannot write{where}: {err.strerror} ({errno.errorcode.get(err.errno, err.errno)}): {fix}"
    text = " ".join(str(err).split())
    return text if isinstance(err, ValueError) and text else f"{type(err).__name__}: {text}"


def _stamp(path: pathlib.Path):
    """What identifies this version of a file (each write_atomic makes a new inode), or None."""
    try:
        st = os.stat(path)
    except OSError:
        return None
    return st.st_ino, st.st_mtime_ns


class RunFolder:
    """The output folder held for a run (the module docstring)."""

    def __init__(self, path, overwrite: bool = False, comm=None, restart: bool = False):
        from mpi4py import MPI
        self.path, self.overwrite, self.restart = pathlib.Path(path), overwrite, restart
        self.comm = comm or MPI.COMM_WORLD
        self.lock = self.path / ".lock"
        self._fd = None
        self._summary = None                 # run.json as it was when the folder was taken

    def _acquire(self) -> int:
        """Take the folder's lock (an exclusive flock on .lock, held until the run ends); its file
        descriptor. Another run may have taken it since the checks, or may be removing the file as
        it ends (then the lock taken is on a file no longer in the folder: try again)."""
        for _ in range(20):
            fd = os.open(self.lock, os.O_CREAT | os.O_RDWR, 0o644)
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except BlockingIOError:
                os.close(fd)
                raise FolderError(_busy(self.path, _holder(self.lock) or -1)) from None
            try:
                current = os.stat(self.lock).st_ino == os.fstat(fd).st_ino
            except FileNotFoundError:
                current = False
            if current:
                os.ftruncate(fd, 0)
                os.write(fd, f"{os.getpid()}\n".encode())
                return fd
            os.close(fd)
        raise FolderError(f"--out {self.path}: could not take the folder's lock: choose another folder")

    def _take(self) -> None:
        p = self.path
        why = check(p, self.overwrite, self.restart)
        if why is not None:
            raise FolderError(why)
        try:
            p.mkdir(parents=True, exist_ok=True)
        except OSError as err:
            raise FolderError(f"--out {p}: cannot create the folder ({err.strerror}): choose another "
                              "place") from None
        self._fd = self._acquire()
        self._summary = _stamp(p / "run.json")
        old = [] if self.restart else _old_results(p)      # a restart goes on where it stopped
        for f in old:
            target = p / f
            if target.is_dir():
                shutil.rmtree(target)
            else:
                target.unlink(missing_ok=True)

    def __enter__(self):
        from ..parallel import on_root
        on_root(self.comm, self._take)
        return self

    def __exit__(self, exc_type, exc, tb):
        if self._fd is not None:             # rank 0: remove the file while still holding it
            if exc is not None:
                try:
                    self._ended_by(exc)
                except OSError:              # (a full disk): the exception says it already
                    pass
            self.lock.unlink(missing_ok=True)
            os.close(self._fd)
            self._fd = None
        return False

    def _ended_by(self, exc: BaseException) -> None:
        """run.json says how the run ended, if this run wrote it (the module docstring); the
        temporary files of unfinished writes are removed."""
        for pattern in TEMPORARY_GLOBS:
            for f in self.path.glob(pattern):
                f.unlink(missing_ok=True)
        path = self.path / "run.json"
        if _stamp(path) in (None, self._summary):
            return                           # not written by this run: left as it was
        try:
            info = json.loads(path.read_text())
        except ValueError:
            info = {}
        signal = isinstance(exc, KeyboardInterrupt)
        if signal and info.get("status") != "running":
            return                           # the writers said it (interrupted) already
        info.update(status="interrupted" if signal else "failed", completed=False, message=failure_line(exc))
        from .writers import write_atomic
        write_atomic(path, json.dumps(info, indent=1, default=str))

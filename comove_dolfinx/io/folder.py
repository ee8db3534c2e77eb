"""A run's output folder: one run at a time, and never the files of two runs mixed.

``RunFolder(path, overwrite)`` (a context manager, collective) takes the folder for a run:

* a folder that another live run holds (its ``.lock`` names a process that still exists) is refused;
  a lock left by a run that was killed is taken over;
* a folder that holds the results of an earlier run is refused unless ``overwrite``, which first
  removes those results (history, run summary, VTK and XDMF files, checkpoints), so that no file of
  the old run sits beside the new one;
* a path that exists but is not a folder, or cannot be written, is refused.

:func:`check` asks the same without writing anything (the command, before it loads dolfinx).
The refusals are :class:`FolderError` with the path and the fix; every rank raises the same.
"""
from __future__ import annotations

import os
import pathlib
import shutil

RESULTS = ("history.csv", "run.json", "results.pvd", "results.xdmf", "results.h5")
RESULT_GLOBS = ("results_*.vtu", ".results_*.tmp", "checkpoint")


class FolderError(ValueError):
    """An output folder that cannot be used; the message names it and the fix."""


def _alive(pid: int) -> bool:
    """Whether a process ``pid`` runs (a zombie, killed but not yet reaped, does not)."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    try:
        state = pathlib.Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except (OSError, IndexError):
        return True
    return state not in ("Z", "X")


def _old_results(p: pathlib.Path) -> list[str]:
    return [f for f in RESULTS if (p / f).exists()] + [g.name for pat in RESULT_GLOBS for g in p.glob(pat)]


def check(path, overwrite: bool = False, restart: bool = False) -> str | None:
    """Why ``path`` cannot take a run (the message, naming the fix), or None; reads, never writes
    (the standard library only: the command asks before it loads dolfinx)."""
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
    lock = p / ".lock"                       # (a folder still to be made has no lock and no results)
    if lock.exists():
        try:
            pid = int(lock.read_text().split()[0])
        except (ValueError, IndexError, OSError):
            pid = -1
        if pid > 0 and _alive(pid):
            return f"--out {p}: another run (process {pid}) is writing there: wait for it or choose another folder"
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


class RunFolder:
    def __init__(self, path, overwrite: bool = False, comm=None, restart: bool = False):
        from mpi4py import MPI
        self.path, self.overwrite, self.restart = pathlib.Path(path), overwrite, restart
        self.comm = comm or MPI.COMM_WORLD
        self.lock = self.path / ".lock"

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
        old = [] if self.restart else _old_results(p)      # a restart goes on where it stopped
        self.lock.unlink(missing_ok=True)                   # left by a run that was killed (check)
        try:
            fd = os.open(self.lock, os.O_CREAT | os.O_EXCL | os.O_WRONLY)
        except FileExistsError:
            raise FolderError(f"--out {p}: another run took the folder just now: choose another "
                              "folder") from None
        with os.fdopen(fd, "w") as fh:
            fh.write(f"{os.getpid()}\n")
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

    def __exit__(self, *exc):
        if self.comm.rank == 0:
            self.lock.unlink(missing_ok=True)
        return False

"""A run's output folder: one run at a time, and never the files of two runs mixed.

``RunFolder(path, overwrite)`` (a context manager, collective) takes the folder for a run:

* a folder that another live run holds (its ``.lock`` names a process that still exists) is refused;
  a lock left by a run that was killed is taken over;
* a folder that holds the results of an earlier run is refused unless ``overwrite``, which first
  removes those results (history, run summary, VTK and XDMF files, checkpoints), so that no file of
  the old run sits beside the new one;
* a path that exists but is not a folder, or cannot be written, is refused.

The refusals are :class:`FolderError` with the path and the fix; every rank raises the same.
"""
from __future__ import annotations

import os
import pathlib
import shutil

from ..parallel import on_root

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


class RunFolder:
    def __init__(self, path, overwrite: bool = False, comm=None, restart: bool = False):
        from mpi4py import MPI
        self.path, self.overwrite, self.restart = pathlib.Path(path), overwrite, restart
        self.comm = comm or MPI.COMM_WORLD
        self.lock = self.path / ".lock"

    def _take(self) -> None:
        p = self.path
        if p.exists() and not p.is_dir():
            raise FolderError(f"--out {p}: this is a file, not a folder: choose a folder")
        try:
            p.mkdir(parents=True, exist_ok=True)
        except OSError as err:
            raise FolderError(f"--out {p}: cannot create the folder ({err.strerror}): choose another "
                              "place") from None
        if not os.access(p, os.W_OK | os.X_OK):
            raise FolderError(f"--out {p}: the folder is not writable: choose another place")
        if self.lock.exists():
            try:
                pid = int(self.lock.read_text().split()[0])
            except (ValueError, IndexError, OSError):
                pid = -1
            if pid > 0 and _alive(pid):
                raise FolderError(f"--out {p}: another run (process {pid}) is writing there: wait for it "
                                  "or choose another folder")
            self.lock.unlink(missing_ok=True)              # left by a run that was killed
        old = [f for f in RESULTS if (p / f).exists()] + [
            g.name for pat in RESULT_GLOBS for g in p.glob(pat)]
        if self.restart:
            if not (p / "checkpoint" / "meta.json").exists():
                raise FolderError(
                    f"--out {p}: no checkpoint to restart from" + (
                        " (none was saved: a run killed within its first --checkpoint-interval seconds "
                        "leaves none): run it again with --overwrite instead of --restart" if old else
                        ": run without --restart"))
            old = []                                     # the run goes on where it stopped
        elif old and not self.overwrite:
            raise FolderError(f"--out {p}: holds the results of an earlier run ({', '.join(sorted(old)[:3])}"
                              f"{', ...' if len(old) > 3 else ''}): pass --overwrite to replace them, or "
                              "choose another folder")
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
        on_root(self.comm, self._take)
        return self

    def __exit__(self, *exc):
        if self.comm.rank == 0:
            self.lock.unlink(missing_ok=True)
        return False

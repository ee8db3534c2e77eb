"""Ctrl-C and SIGTERM in the ``comove`` command: one line and an exit code at any moment.

The command installs :func:`on_signal` for SIGINT and SIGTERM as the first thing it does, so that
a signal during the imports, the mesh, the form compiler or the run raises KeyboardInterrupt
(``"SIGTERM"`` or ``"Ctrl-C"``), which the command turns into one line (:func:`interrupted`) and
exit code 130 (Ctrl-C) or 143 (SIGTERM). While the increments run, the job turns the handler's
signals into a decision of all ranks (parallel.Interrupts). Only the first signal raises; later
ones are recorded, so that the writers' closing and the output folder's last words (run.json,
io/folder.py) are not cut short.

Gmsh's Python module sets Ctrl-C to the system's default action when it is imported (the process
would die without a word): it is imported, when a mesh is built, with the signals held back
(geometry/gmsh_session.py). Dolfinx's compiled bindings abort the process if a signal's exception
is raised while they initialise: the command imports them with the signals held back
(:func:`signals_held`, :func:`import_bindings`) and installs its handler again after. Under Open
MPI's ``mpirun``, Ctrl-C reaches the ranks as SIGTERM, and ``mpirun`` itself ends with its own
exit code (1).

Nothing here imports dolfinx, mpi4py or numpy.
"""
from __future__ import annotations

import contextlib
import os
import pathlib
import signal
import sys
import threading

#: the signals (SIGINT, SIGTERM) the command has had, in order
SIGNALLED: list[int] = []
SIGNALS = (signal.SIGINT, signal.SIGTERM)


def on_signal(signum, frame):
    """The command's SIGINT and SIGTERM handler: the first signal raises KeyboardInterrupt
    ("SIGTERM" or "Ctrl-C") wherever the command is; later ones are recorded only."""
    SIGNALLED.append(signum)
    if len(SIGNALLED) == 1:
        raise KeyboardInterrupt("SIGTERM" if signum == signal.SIGTERM else "Ctrl-C")


def handle() -> dict:
    """Install :func:`on_signal` for SIGINT and SIGTERM (main thread only); the previous handlers."""
    if threading.current_thread() is not threading.main_thread():
        return {}
    return {sig: signal.signal(sig, on_signal) for sig in SIGNALS}


def restore(previous: dict, ignore: bool) -> None:
    """Put the ``previous`` handlers back, or with ``ignore`` ignore the signals from now on (the
    process is about to end: MPI's and PETSc's shutdown is not cut short by a late Ctrl-C, which
    Python's shutdown would let kill the process)."""
    for sig, handler in previous.items():
        signal.signal(sig, signal.SIG_IGN if ignore else handler)


@contextlib.contextmanager
def signals_held():
    """SIGINT and SIGTERM held back within the block (code that resets their handlers, as gmsh's
    import does, cannot let them kill the process without a word), then the command's handler
    installed again and the signals let through: one that came meanwhile is handled then."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    signal.pthread_sigmask(signal.SIG_BLOCK, set(SIGNALS))
    try:
        yield
    finally:
        handle()
        signal.pthread_sigmask(signal.SIG_UNBLOCK, set(SIGNALS))


def import_bindings() -> None:
    """Import dolfinx with the signals held back: a KeyboardInterrupt raised while its compiled
    bindings initialise aborts the process (nanobind's module set-up, dolfinx 0.10 and later:
    SIGSEGV or std::terminate). A signal that came meanwhile is handled once they are loaded. If
    dolfinx is missing, the platform check says so later. Gmsh is not imported here: a run whose
    mesh is in the cache never loads it, and its import, when a mesh is built, holds the signals
    itself (geometry/gmsh_session.py)."""
    import importlib
    with signals_held():
        try:
            importlib.import_module("dolfinx")
        except ImportError:
            pass


def writer():
    """A writer that installs the command's handlers when the run starts (after the problem is
    built): code of a problem file may have reset Ctrl-C to the system's default, as gmsh's Python
    API does (the package's own gmsh calls keep the handler: geometry/gmsh_session.py)."""
    from .io import Writer

    class Signals(Writer):
        def open(self, run):
            handle()
    return Signals()


def quiet_after_signal(unraisable) -> None:
    """Python's report of an exception it cannot raise (in a destructor), except once the command
    has had a signal: an object whose construction the signal cut short (a progress bar) then
    fails in its destructor, which is no news."""
    if not SIGNALLED:
        sys.__unraisablehook__(unraisable)


def own_signals() -> None:
    """The command ends cleanly on SIGTERM and Ctrl-C itself: PETSc must not install its own
    handlers (some builds do, and abort the process on SIGTERM). Before PETSc is loaded."""
    opts = os.environ.get("PETSC_OPTIONS", "")
    if "-no_signal_handler" not in opts:
        os.environ["PETSC_OPTIONS"] = f"{opts} -no_signal_handler".strip()


def interrupted(err: BaseException, args, rank: int) -> int:
    """Print (on rank 0) the one line of a command ended by Ctrl-C or SIGTERM (``err``; ``args``:
    the parsed arguments, None if it did not get that far); the exit code, 130 or 143."""
    why = "SIGTERM" if str(err) == "SIGTERM" or signal.SIGTERM in SIGNALLED[:1] else "Ctrl-C"
    out = getattr(args, "out", None) if getattr(args, "command", None) == "run" else None
    if out and (pathlib.Path(out) / "history.csv").exists():
        where = f"; every converged increment is in {out} (run.json says how far it got)"
    else:
        where = " while starting up, before any increment" if args is None or out else ""
    if rank == 0:
        print(f"comove: interrupted ({why}){where}", file=sys.stderr)
    # CPython notes a KeyboardInterrupt that escapes code run by exec() (dataclasses build their
    # methods so) as unhandled even when the command catches it later, and at exit kills the
    # process with SIGINT instead of returning its code; a string run by exec() clears the note.
    exec("None")
    return 143 if why == "SIGTERM" else 130


def end(err: BaseException, args, rank: int, ranks: int) -> int:
    """The exit code of a command ended by a signal, its one line printed (:func:`interrupted`).
    On several ranks, unless the ranks stopped together (a job's increments, parallel.Interrupts,
    which marks the exception ``all_ranks``), another rank may wait in a collective call that this
    one will never join, and a launcher that passes Ctrl-C on to the ranks and waits for them
    (MPICH's) would wait for ever: the ranks are ended by MPI_Abort, rank 0 at once (its run.json
    and line are written by then), the others a second later, so that rank 0 says its line first
    unless it is the one that waits."""
    code = interrupted(err, args, rank)
    mpi = sys.modules.get("mpi4py.MPI")
    if ranks > 1 and not getattr(err, "all_ranks", False) and mpi is not None and mpi.Is_initialized():
        import time
        sys.stderr.flush()
        sys.stdout.flush()
        if rank != 0:
            time.sleep(1.0)
        mpi.COMM_WORLD.Abort(code)
    return code

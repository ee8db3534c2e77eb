"""Collective decisions: a failure on one MPI rank becomes the same failure on every rank.

A rank that raises while the others go on to the next collective call (an assembly, a reduction, a
parallel file write) leaves them waiting for ever. Every piece of work that runs on some ranks only,
or that can fail on some ranks only (the return map at the rank's quadrature points, a file written
by rank 0, a user's callback), goes through :func:`collective` or :func:`on_root`: the outcome is
gathered, and if any rank failed, every rank raises the first failing rank's exception (the same type
and message; :class:`RankFailure` if it cannot be sent). A signal (Ctrl-C, SIGTERM) that reaches
the ranks at different moments is made one decision too: :class:`Interrupts`.
"""
from __future__ import annotations

import pickle
import signal
import threading
from typing import Any, Callable

from mpi4py import MPI


class RankFailure(RuntimeError):
    """An error raised on another rank that could not be re-created here."""


def _packed(err: BaseException | None):
    if err is None:
        return None
    try:
        blob = pickle.dumps(err)
        pickle.loads(blob)
    except Exception:
        blob = None
    return type(err).__name__, str(err), blob


def agree(comm: MPI.Comm, err: BaseException | None) -> None:
    """Raise on every rank if ``err`` is not None on any rank (the lowest failing rank's error)."""
    if comm.size == 1:
        if err is not None:
            raise err
        return
    outcomes = comm.allgather(_packed(err))
    failed = [(rank, o) for rank, o in enumerate(outcomes) if o is not None]
    if not failed:
        return
    rank, (name, text, blob) = failed[0]
    if err is not None and rank == comm.rank:
        raise err
    if blob is not None:
        raise pickle.loads(blob)
    raise RankFailure(f"rank {rank}: {name}: {text}")


def first_failure(comm: MPI.Comm, err: BaseException | None) -> str | None:
    """The message of the lowest failing rank's error (the same on every rank), or None."""
    if comm.size == 1:
        return None if err is None else f"{type(err).__name__}: {err}"
    outcomes = comm.allgather(None if err is None else f"{type(err).__name__}: {err}")
    failed = [(rank, o) for rank, o in enumerate(outcomes) if o is not None]
    return None if not failed else (failed[0][1] if len(failed) == comm.size
                                    else f"rank {failed[0][0]}: {failed[0][1]}")


def collective(comm: MPI.Comm, fn: Callable[..., Any], *args, **kwargs) -> Any:
    """Run ``fn`` on every rank; if it raises on any rank, raise on every rank."""
    result, err = None, None
    try:
        result = fn(*args, **kwargs)
    except Exception as e:          # noqa: BLE001 - handed to every rank
        err = e
    agree(comm, err)
    return result


def on_root(comm: MPI.Comm, fn: Callable[..., Any], *args, **kwargs) -> Any:
    """Run ``fn`` on rank 0 only (a file operation); its result is broadcast, its failure raised on
    every rank."""
    result, err = None, None
    if comm.rank == 0:
        try:
            result = fn(*args, **kwargs)
        except Exception as e:      # noqa: BLE001
            err = e
    agree(comm, err)
    return comm.bcast(result, root=0) if comm.size > 1 else result


class Interrupts:
    """Ctrl-C and SIGTERM while a job runs, as a decision of all ranks at the same point.

    Inside the ``with`` block a signal whose handler is Python's is recorded instead of raised
    where it lands (in one rank's collective call, or between two writers of an increment).
    :meth:`check`, called by every rank at the same points (each Newton iteration, after each
    increment's writers, and when the block ends), then calls the recorded signal's own handler
    (KeyboardInterrupt, or the command's) on every rank as soon as any rank has one. So the ranks
    stop together, and an increment goes to all its writers or to none. Signals whose handler is
    not Python's (SIG_DFL, SIG_IGN), and blocks outside the main thread, are left alone."""

    SIGNALS = (signal.SIGINT, signal.SIGTERM)

    def __init__(self, comm: MPI.Comm):
        self.comm, self.pending, self._saved = comm, 0, {}

    def _hold(self, signum, frame) -> None:
        self.pending = self.pending or int(signum)

    def __enter__(self) -> "Interrupts":
        self.pending = 0
        if threading.current_thread() is threading.main_thread():
            for sig in self.SIGNALS:
                if callable(signal.getsignal(sig)):
                    self._saved[sig] = signal.signal(sig, self._hold)
        return self

    def _restore(self) -> None:
        for sig, handler in self._saved.items():
            if signal.getsignal(sig) == self._hold:
                signal.signal(sig, handler)
        self._saved.clear()

    def check(self) -> None:
        """Collective: the recorded signal's handler on every rank once any rank has one (the
        larger number if two ranks got different ones: SIGTERM before Ctrl-C); a rank where that
        signal has no Python handler raises KeyboardInterrupt, so that no rank goes on alone. A
        handler that returns (one that only logs) lets the job go on, still recording."""
        signum = self.pending if self.comm.size == 1 else self.comm.allreduce(self.pending, op=MPI.MAX)
        if not signum:
            return
        self.pending = 0
        handler = self._saved.get(signum, signal.getsignal(signum))
        try:
            if not callable(handler):
                raise KeyboardInterrupt(signal.Signals(signum).name)
            handler(signum, None)
        except KeyboardInterrupt as err:
            err.all_ranks = True      # every rank raises it here (command_signals.end)
            raise

    def __exit__(self, exc_type, exc, tb) -> bool:
        try:
            if exc_type is None:
                self.check()          # every rank ends the block here: still one decision
        finally:
            self._restore()
        return False

"""Wall-clock time per named part of a run (assembly, solve, stress update, output, ...): the
run's timing print and Results.timing."""
from __future__ import annotations

import time
from collections import defaultdict


class Timer:
    """Time accumulated per category (assembly, solve, stress update, output, ...): wall time, or
    with ``clock=time.process_time`` the process's CPU time (the cost benchmarks)."""

    def __init__(self, clock=time.perf_counter):
        self.totals: dict[str, float] = defaultdict(float)
        self.clock = clock

    def __call__(self, name: str) -> "_Span":
        return _Span(self, name)

    def report(self) -> str:
        total = sum(self.totals.values())
        parts = [f"{k} {v:.2f} s ({100 * v / total:.0f} %)" for k, v in
                 sorted(self.totals.items(), key=lambda kv: -kv[1])] if total else []
        return "timing: " + ", ".join(parts)


class _Span:
    """One timed stretch of a :class:`Timer` (a plain context manager: several per iteration)."""

    __slots__ = ("timer", "name", "t0")

    def __init__(self, timer: Timer, name: str):
        self.timer, self.name = timer, name

    def __enter__(self) -> None:
        self.t0 = self.timer.clock()

    def __exit__(self, *exc) -> None:
        self.timer.totals[self.name] += self.timer.clock() - self.t0

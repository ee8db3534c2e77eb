"""slopes: why the line search spends trials.

In the ring's run (``--sizes``, default 0.058, about 18k dofs), at the first four corrections past
the load factor 0.2 (delta = 1.32) whose full step overshoots (``s(1) > 0.5 |s(0)|``,
``s(a) = du . R(u + a du)``), the secant slope ``(s(a) - s(0)) / (a |s(0)|)`` at steps a from 1e-5
to 1, and its internal force's part: 1 as a -> 0 for an exact tangent, and it stays near 1 where
the residual is smooth along du; with the quadrature points that yield at the iterate and unload at
the step, and those that start to yield there. The run goes on as without the probe.
"""
from __future__ import annotations

import pathlib

import numpy as np
from mpi4py import MPI

from .charts import lines
from .runs import say, short_run, write_csv

SLOPE_STEPS = (1e-5, 1e-4, 1e-3, 1e-2, 0.03, 0.1, 0.2, 0.5, 1.0)


def _plastic_points(model) -> np.ndarray | None:
    """Which of the rank's own quadrature points yield at the current iterate (p > p_n), or None
    for a body without plasticity."""
    st = model.state
    if st.p is None:
        return None
    n = model.rule.num_cells_local * model.rule.npts
    return st.p.x.array[:n] > st.p_n.x.array[:n]


class SlopeProbe:
    """A Newton monitor that looks along the corrections which overshoot: after load ``after``, at
    the first ``count`` corrections with s(0) < 0 and ``s(1) > overshoot |s(0)|`` (``s(a) = du . R(u +
    a du)``), the secant slopes ``(s(a) - s(0)) / (a |s(0)|)`` at ``steps``, whole and the internal
    force's part (Newton.along), and for a plastic body the quadrature points that yield at the
    iterate and unload at the step, and those that start to yield. ``cases``: one dict per
    correction (load, iteration, s0, the points yielding at the iterate, and rows of (a, slope,
    internal part, unloading points, newly yielding points); the counts are -1 without plasticity)."""

    def __init__(self, steps=SLOPE_STEPS, count: int = 4, after: float = 0.2, overshoot: float = 0.5):
        self.steps, self.count, self.after, self.overshoot = tuple(steps), count, after, overshoot
        self.cases: list[dict] = []

    def correction(self, newton, it: int) -> None:
        """Newton's call after the linear solve: record the correction if it is one to look at."""
        if len(self.cases) >= self.count or newton.model.load <= self.after:
            return
        (_, s0, f0, y0), (_, s1, _, _) = newton.along((0.0, 1.0), look=_plastic_points)
        if not (s0 < 0.0 and s1 > self.overshoot * abs(s0)):
            return
        comm = newton.model.comm

        def flips(y):
            if y0 is None or y is None:
                return -1, -1
            local = np.array([np.sum(y0 & ~y), np.sum(~y0 & y)], dtype=np.int64)
            comm.Allreduce(MPI.IN_PLACE, local, op=MPI.SUM)
            return int(local[0]), int(local[1])
        rows = [(a, (s - s0) / (a * abs(s0)), (f - f0) / (a * abs(s0)), *flips(y))
                for a, s, f, y in newton.along(self.steps, look=_plastic_points)]
        yielding = -1 if y0 is None else comm.allreduce(int(np.sum(y0)), op=MPI.SUM)
        self.cases.append({"load": newton.model.load, "iteration": it, "s0": s0,
                           "yielding": yielding, "rows": rows})


def _case_rows(size: float, dofs: int, case: dict) -> list[dict]:
    """slopes.csv's rows of one recorded correction, one per step."""
    return [{"size": size, "dofs": dofs, "load": case["load"], "iteration": case["iteration"],
             "s0": case["s0"], "step": a, "slope": slope, "internal_slope": internal,
             "items_slope": slope - internal, "yielding": case["yielding"], "unloading": unloading,
             "newly_yielding": loading}
            for a, slope, internal, unloading, loading in case["rows"]]


def slopes(out: pathlib.Path, sizes=(0.058,), increments: int = 36, count: int = 4,
           after: float = 0.2, overrides=()) -> list[dict]:
    """The ring's run with a :class:`SlopeProbe`: slopes.csv (one row per case and step) and
    slopes.png (the secant slope against the step, one line per case)."""
    rows, series = [], {}
    for size in sizes:
        probe = SlopeProbe(count=count, after=after)
        run = short_run("ring", size, increments, overrides=overrides, monitor=probe)
        for case in probe.cases:
            label = f"{run['dofs']} dofs, load {case['load']:.4f}, correction {case['iteration']}"
            series[label] = ([r[0] for r in case["rows"]], [r[1] for r in case["rows"]],
                             [0.0] * len(case["rows"]))
            rows += _case_rows(size, run["dofs"], case)
            say(f"{label} ({case['yielding']} points yielding): " +
                " ".join(f"{r[0]:g}:{r[1]:.3f} (-{r[3]} +{r[4]})" for r in case["rows"]))
        if not probe.cases:
            say(f"ring size {size}: no correction overshot after the load factor {after}")
    write_csv(out / "slopes.csv", rows)
    if series:
        lines(out / "slopes.png", series, "step a along the correction du",
              "(s(a) - s(0)) / (a |s(0)|)", "ring: the residual along Newton's correction "
              "(1: the tangent's slope)", logy=False)
    return rows

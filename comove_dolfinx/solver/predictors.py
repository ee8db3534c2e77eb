"""Where an increment starts: the predictors of the increment loop (increments.py).

The tangent predictor is the Euler step along the path's tangent; it is checked against the rate
that the last converged states give (:func:`agrees_with_path`, the slope of their quadratic,
:func:`path_rate`) and falls back on their linear extrapolation (:func:`extrapolate`, the chord).
docs/theory.md section 7.2.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from mpi4py import MPI


def extrapolate(points, t: float) -> np.ndarray:
    """Lagrange extrapolation of the converged states ``points`` = [(t_i, u_i)] to load t."""
    out = np.zeros_like(points[0][1])
    for i, (ti, ui) in enumerate(points):
        w = 1.0
        for j, (tj, _) in enumerate(points):
            if j != i:
                w *= (t - tj) / (ti - tj)
        out += w * ui
    return out


def path_rate(points) -> np.ndarray:
    """du/dt at the newest of the converged states ``points`` = [(t_i, u_i)] (two or three, oldest
    first): the chord through two; through three the slope of their quadratic, the last chord plus
    (t2 - t1) times the second divided difference (second-order accurate on a smooth path)."""
    (t1, u1), (t2, u2) = points[-2:]
    chord = (u2 - u1) / (t2 - t1)
    if len(points) < 3:
        return chord
    t0, u0 = points[-3]
    return chord + (t2 - t1) * (chord - (u1 - u0) / (t1 - t0)) / (t2 - t0)


def agrees_with_path(model, rate, past, chord_tol: float) -> bool:
    """Whether the path's tangent ``rate`` at the newest state lies within ``chord_tol`` of the
    rate that the last converged states give, ``|v - r| <= chord_tol |c|``: r the slope of the
    quadratic through the last three (second-order accurate on a smooth path, so a path that
    curves, as the elastica's does, is not taken for a spurious mode) or the chord c of the
    last increment while there are two. Near a mechanism (a ring of plastic hinges) the tangent
    is almost singular and its solution can carry a spurious part along it; the predictor then
    takes the chord (linear extrapolation) instead. Collective (``model.comm``)."""
    (t0, u0), (t1, u1) = past[-2:]
    chord = (u1 - u0) / (t1 - t0)
    ref = path_rate(past[-3:])
    imap = model.V.dofmap.index_map
    n = imap.size_local * model.V.dofmap.index_map_bs
    d = rate.x.array[:n] - ref[:n]
    sums = np.array([d @ d, chord[:n] @ chord[:n]])
    model.comm.Allreduce(MPI.IN_PLACE, sums, op=MPI.SUM)     # (a buffer: no pickling)
    diff2, chord2 = sums
    return bool(diff2 <= chord_tol ** 2 * chord2)


@dataclass
class Starts:
    """Where the increments of a step may start: ``tangent`` (the Euler step along the path's
    tangent), else the extrapolation of order ``alt`` (0: none) of the last converged states, of
    which ``keep`` are kept (the tangent keeps two for its check, agrees_with_path, and falls back
    on the linear extrapolation, the chord)."""

    tangent: bool
    alt: int
    keep: int

    @classmethod
    def of(cls, st) -> "Starts":
        """The starts of the step settings ``st`` (solver.StepSettings); ValueError for an unknown
        ``predictor``."""
        tangent = st.predictor == "tangent"
        if isinstance(st.predictor, str) and not tangent:
            raise ValueError(f"predictor = {st.predictor!r}: choose 0, 1, 2 or tangent")
        order = 1 if tangent else int(st.predictor)
        alt = 1 if (st.retry and order == 0) else order     # the extrapolation of a predictor start
        return cls(tangent, alt, 2 if tangent else alt)

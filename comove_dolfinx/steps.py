"""The stages of a job's loading: :class:`Step` (its increments, the items' targets, the increment
control and the supports it releases), and :class:`JobError`, the error of a step or job that cannot
run. The job (job.py) starts each step with :meth:`Step.start` and runs its increments with the
settings of :meth:`Step.settings`.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .choices import PREDICTORS, first_increment_error
from .solver import StepSettings


class JobError(ValueError):
    """A step or job that cannot run; the message names the value and the fix."""


@dataclass
class Step:
    """A stage of the loading: ``n`` nominal increments, the factors' targets, increment control.

    ``predictor``: where each increment starts, "tangent" (the default: Euler step along the path's
    tangent), "none" (the last converged state), "linear" or "quadratic" (extrapolation of the last
    converged states), docs/theory.md section 7.2. ``retry``: a failed increment is tried once more
    at the same size from the other start (a predictor if it started from the last state, the last
    state if it started from a predictor) before it is halved; a predictor that rescued an increment
    begun from the last state is kept for the rest of the step. ``max_cutbacks``: halvings of a
    failed increment.
    ``first``: the step's first increment as a fraction 1, 1/2, 1/4, ... of the nominal one (at most
    ``max_cutbacks`` halvings), doubled back to it after easy increments: a hard start (a first
    contact and its first yield) at a size that converges instead of failed attempts at the nominal.
    ``release``: supports (``Fixed``, ``Displacement``) taken away at the start of the step: the
    force each exerted there becomes a nodal force that the step ramps down to 0 (or to the target
    ``ramp`` gives it, as a fraction of that force), so the body is let go smoothly, e.g. a clamp
    opened after forming; a released support stays released.
    """

    n: int = 10
    ramp: dict | None = None
    predictor: str = "tangent"
    max_cutbacks: int = 6
    name: str = ""
    release: tuple = ()
    first: float = 1.0
    retry: bool = True

    def __post_init__(self):
        self.release = tuple(self.release) if isinstance(self.release, (list, tuple)) else (self.release,)
        if isinstance(self.n, bool) or not isinstance(self.n, (int, np.integer)) or not 1 <= self.n <= 10**6:
            raise JobError(f"step {self.name or ''} n = {self.n!r}: give a whole number of increments "
                           "from 1 to 1000000")
        if self.predictor not in PREDICTORS:
            raise JobError(f"predictor = {self.predictor!r} is unknown: choose one of {', '.join(PREDICTORS)}")
        if isinstance(self.max_cutbacks, bool) or not (isinstance(self.max_cutbacks, int) and
                                                       0 <= self.max_cutbacks <= 30):
            raise JobError(f"max_cutbacks = {self.max_cutbacks!r}: give a whole number from 0 to 30")
        why = first_increment_error(self.first, self.max_cutbacks)
        if why:
            raise JobError(why)
        if not isinstance(self.retry, (bool, np.bool_)):
            raise JobError(f"retry = {self.retry!r}: give True or False")

    def settings(self) -> StepSettings:
        return StepSettings(n_increments=int(self.n), max_cutbacks=self.max_cutbacks,
                            predictor=PREDICTORS[self.predictor], first=float(self.first),
                            retry=bool(self.retry))

    def check(self, items) -> None:
        """JobError if the step names an item that is not the job's, or releases what is not a
        support."""
        for k in list(self.ramp or {}) + list(self.release):
            if not any(k is item for item in items):
                verb = "ramps" if k in (self.ramp or {}) else "releases"
                raise JobError(f"step {self.name!r} {verb} {k!r}, which is not an item of the job")
        for k in self.release:
            if not callable(getattr(k, "release", None)):
                raise JobError(f"step {self.name!r} releases {k!r}: only supports (Fixed, Displacement) "
                               "can be released")

    def start(self, items, model=None) -> None:
        """Release the step's supports (with the model at its converged state), then set every
        item's ramp for this step."""
        self.check(items)
        ramp = self.ramp
        for item in self.release:
            if not item.released:
                model.release(item)
        for item in items:
            if ramp is not None and any(item is k for k in ramp):
                item.ramp(next(v for k, v in ramp.items() if k is item))
            elif any(item is k for k in self.release):
                item.ramp(0.0)
            elif ramp is None and not getattr(item, "released", False):
                item.ramp(1.0)
            else:
                item.hold()

"""Why an attempt at an increment failed, recorded where it fails, and what to change about it.

Every failed Newton solve leaves a :class:`Failure` on the solver (``Newton.failure``): its cause,
one of the named constants below, the reason as a sentence, and what the iterations showed (the
residual norms of the accepted iterates, the number of iterations in which the contact set changed).
The increment loop counts the failed attempts per cause (``StepOutcome.failures``, a job's
``Results.failures``, run.json's ``"failures"``) and, when a run stops, :func:`advice` turns the last
failure into one sentence naming what to change (whether the step was under loads alone,
:func:`force_controlled`, among what it weighs).

Causes (the counting keys, plain strings so that they go to JSON as they are):

* ``INADMISSIBLE``: an iterate with det F <= 0 at a quadrature point or a node, or a stress update
  that returned NaN (an S-R split beyond its range among them) or whose return map failed;
* ``MAX_IT``: ``max_it`` iterations without meeting the tolerance;
* ``DIVERGED``: ||R|| grew beyond ``divergence`` times the first residual of the increment, or
  became infinite;
* ``LINEAR``: the linear solver failed, or its correction was not finite (singular tangent);
* ``KRYLOV``: the iterative linear solver (``NewtonSettings.linear_solver`` "gamg" or "hypre", or a
  Krylov method of the PETSc options) stopped without reaching its tolerance.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

INADMISSIBLE = "inadmissible"
MAX_IT = "max_it"
DIVERGED = "diverged"
LINEAR = "linear_solver"
KRYLOV = "krylov"
CAUSES = (INADMISSIBLE, MAX_IT, DIVERGED, LINEAR, KRYLOV)

#: what a fall of ||R|| per iteration must stay below, over the last iterations, to count as steady
STEADY_RATIO = 0.9
#: iterations looked at for a steady fall and for a switching contact set
WINDOW = 6


@dataclass
class Failure:
    """One failed attempt at an increment.

    Attributes
    ----------
    cause : str
        One of :data:`CAUSES`.
    reason : str
        The failure as a sentence (what the log and the run's message show).
    residuals : list of float
        ||R|| of the first residual and of every accepted iterate of the attempt, in order.
    set_changes : int
        Iterations (among the last :data:`WINDOW`) after which the active contact set differed from
        the one before, on any rank; 0 without contact.
    max_it : int
        The iteration limit the attempt ran under.
    """

    cause: str
    reason: str
    residuals: list = field(default_factory=list)
    set_changes: int = 0
    max_it: int = 0

    @property
    def steady(self) -> bool:
        """Whether ||R|| fell in every one of the last iterations, each time by at least the factor
        :data:`STEADY_RATIO`: the iteration was converging, only slowly."""
        r = [v for v in self.residuals[-WINDOW:] if v > 0.0 and math.isfinite(v)]
        if len(r) < 3 or len(r) < len(self.residuals[-WINDOW:]):
            return False
        return all(b <= STEADY_RATIO * a for a, b in zip(r, r[1:]))

    def iterations_needed(self, target: float) -> int | None:
        """Further iterations at the mean rate of the last ones until ||R|| reaches ``target``
        (None if the residual is not falling steadily)."""
        if not self.steady:
            return None
        r = self.residuals[-WINDOW:]
        rate = (r[-1] / r[0]) ** (1.0 / (len(r) - 1))
        if r[-1] <= target:
            return 0
        return int(math.ceil(math.log(target / r[-1]) / math.log(rate)))


def advice(failure: Failure | None, *, contact: bool = False, friction: bool = False,
           predictor: bool = True, force_controlled: bool = False, target: float | None = None,
           n: int | None = None, line_search: bool = False) -> str:
    """What to change, as one sentence, after ``failure`` stopped a run at its smallest increment.

    Parameters
    ----------
    failure
        The last failed attempt (None: nothing to say).
    contact, friction
        Whether the model has contact items, and friction on any of them.
    predictor
        Whether the step started its increments from a predictor (else from the last state).
    force_controlled
        Whether every item that the step moves is a load (no prescribed displacement, no moving
        obstacle): the run may have reached a limit load, which a force-controlled step cannot pass.
    target
        The residual tolerance of the attempt (rtol times the scale plus atol), for the iterations
        a steadily falling residual still needed.
    n
        The step's nominal number of increments.
    line_search
        Whether Newton already scales its corrections by a line search (else one is suggested).
    """
    if failure is None:
        return ""
    more = f"more increments (Step n = {2 * n} instead of {n})" if n else "more increments"
    if failure.cause == INADMISSIBLE:
        start = "" if predictor else ", or predictor=\"tangent\" (a start on the path's tangent)"
        return (f"an iterate inverted an element or left the stress update's range: take {more}{start}; "
                "if it persists, refine the mesh where the body deforms most")
    if failure.cause == KRYLOV:
        return ("the iterative linear solver did not converge: raise its iteration limit "
                "(petsc_options ksp_max_it) or use the direct solver (NewtonSettings linear_solver=\"mumps\")")
    if failure.cause == LINEAR:
        return ("the tangent is singular or the linear solver failed: add a support if the body can "
                "move rigidly, or check the solver's options (NewtonSettings.petsc_options)")
    if failure.cause == MAX_IT and contact and failure.set_changes >= 2:
        law = ", or less friction (a smaller mu)" if friction else ""
        return (f"the contact set kept switching ({failure.set_changes} changes in the last "
                f"{min(WINDOW, max(len(failure.residuals) - 1, 0))} iterations): lower gamma0 (a softer "
                f"penalty), take {more}{law}")
    if failure.cause == MAX_IT and failure.steady:
        need = failure.iterations_needed(target) if target is not None else None
        raise_to = failure.max_it + need + 2 if need is not None else 2 * failure.max_it
        return (f"the residual was still falling steadily: raise NewtonSettings.max_it from "
                f"{failure.max_it} to about {raise_to}")
    limit = ("; the load may have reached the body's limit load, which a force-controlled step "
             "cannot pass: prescribe a displacement instead") if force_controlled else ""
    search = "" if line_search else ", or a line search (NewtonSettings line_search=\"residual\")"
    if failure.cause == DIVERGED:
        return f"Newton diverged: take {more}{search}{limit}"
    stick = " (with friction the stick/slip states may be switching: lower gamma0)" if friction else ""
    return f"the residual stalled{stick}: take {more}{search}{limit}"


def force_controlled(items) -> bool:
    """Whether every item that moves over the step is a load (a pressure, traction, body or point
    force, a released support's force), with no prescribed displacement and no moving obstacle: such
    a step cannot pass a maximum of the load (a limit load)."""
    loads = False
    for item in items:
        if all(item.factor_at(s) == item.factor_at(0.0) for s in (0.5, 1.0)):
            continue
        if item.kind == "load" or getattr(item, "released", False):
            loads = True
        elif item.kind == "contact":
            d = [np.asarray(item.obstacle.displacement(item.factor_at(s)), dtype=float) for s in (0.0, 0.5, 1.0)]
            if not all(np.array_equal(d[0], v) for v in d[1:]):
                return False
        elif getattr(item, "field", None) is not None or np.any(np.asarray(
                getattr(item, "value", None) if getattr(item, "value", None) is not None else 0.0) != 0.0):
            return False              # a prescribed displacement (Fixed prescribes none)
    return loads

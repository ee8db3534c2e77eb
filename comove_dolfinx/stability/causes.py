"""Why a run failed: the causes, the classifier of the increment loop's message, and the monitor
that watches Newton for what the message alone cannot tell.

The monitor (:class:`Recorder`) goes into the run's ``NewtonSettings.monitor`` (solver/newton.py):

* ``rejected``: when the stress update of an iterate returns NaN, that iterate (still in
  ``model.u``) is examined. The S-R split of an increment ``dF = F F_n^-1`` exists only while
  sin^2(theta) = omega^2 <= 1, omega = (dF21 - dF12)/2 (docs/theory.md 2.3), so omega^2 > 1
  somewhere means "S-R split beyond 90 degrees"; an in-plane det F <= 0 means an inverted element
  (the plane-stress thickness law takes a power of it and returns NaN before det F is checked);
  anything else stays "NaN in the stress update". The last such diagnosis of the run counts (the
  failing iterate of the last failed solve: its line search goes back to the iterate before, so
  the diagnosis is made at the trial itself, not after the solve).
* ``iteration``: at every convergence test of an accepted iterate (not the line search's trials)
  the active contact set is recorded: the contact boundary's nodes with a negative gap to the
  obstacle (for Nitsche the pressure also depends on the traction, so the gap is a proxy).
* ``solved``: a Newton solve that fails while this set keeps changing and comes back to a set it
  had left (a cycle, :func:`is_cycling`) is "contact chatter".
"""
from __future__ import annotations

SR_RANGE = "S-R split beyond 90 deg"
INVERTED = "inverted element"
NAN = "NaN in the stress update"
RETURN_MAP = "return map failed"
NO_CONVERGENCE = "Newton: no convergence"
DIVERGED = "Newton: diverged"
LINEAR = "linear solve failed"
CHATTER = "contact chatter"
OTHER = "other"
CAUSES = (SR_RANGE, INVERTED, NAN, RETURN_MAP, NO_CONVERGENCE, DIVERGED, LINEAR, CHATTER, OTHER)

SHORT = {SR_RANGE: "S-R > 90°", INVERTED: "det F ≤ 0", NAN: "NaN", RETURN_MAP: "return map",
         NO_CONVERGENCE: "no conv.", DIVERGED: "diverged", LINEAR: "lin. solve", CHATTER: "chatter",
         OTHER: "other"}


def classify(message: str, nan_diagnosis: str | None = None, chatter: bool = False) -> str:
    """The cause of a failed run from the increment loop's message (the reason of its last failed
    attempt is at the end of it). ``nan_diagnosis``: what the failing iterate showed when the update
    returned NaN (SR_RANGE, INVERTED or None); ``chatter``: whether the last failed Newton solve
    cycled through contact sets (then a Newton failure is put down to chatter)."""
    text = message.lower()
    if "returned nan" in text:
        return nan_diagnosis if nan_diagnosis in (SR_RANGE, INVERTED) else NAN
    if "det f" in text or "folds" in text:
        return INVERTED
    if "s-r" in text and ("90" in text or "range" in text):
        return SR_RANGE
    if "constitutive update failed" in text or "return map" in text or "return mapping" in text:
        return RETURN_MAP
    if "linear solve" in text or "not finite" in text or "linear solver" in text:
        return LINEAR
    if "no convergence" in text:
        return CHATTER if chatter else NO_CONVERGENCE
    if "diverged" in text:
        return CHATTER if chatter else DIVERGED
    return OTHER


def is_cycling(sets: list, window: int = 6) -> bool:
    """Whether a sequence of active contact sets (hashable, one per Newton iteration) chatters:
    within its last ``window`` entries the set changes at least three times and comes back to a
    set it had left (A -> B -> A)."""
    tail = sets[-window:]
    changes = sum(1 for a, b in zip(tail, tail[1:]) if a != b)
    revisit = any(tail[k] == tail[j] and any(tail[i] != tail[j] for i in range(j + 1, k))
                  for j in range(len(tail)) for k in range(j + 2, len(tail)))
    return changes >= 3 and revisit


class Recorder:
    """What Newton showed during one run: a monitor for ``NewtonSettings.monitor`` (one per run)."""

    def __init__(self):
        self.nan_diagnosis: str | None = None      # of the last NaN of the stress update
        self.max_omega2 = 0.0                     # sin^2 of the increment's S-R angle there
        self.sets: list = []                      # active contact sets of the current Newton solve
        self.last_failed_chatter = False
        self.last_failed_changes = 0              # active-set changes in the last failed solve
        self.chatter_solves = 0                   # failed Newton solves that cycled
        self.failed_solves = 0
        self.total_its = 0                        # Newton iterations of every solve, failed ones too
        self._exprs: tuple | None = None          # the diagnosis's compiled expressions, and
        self._exprs_model = None                  # the model they were compiled for

    # -- the monitor's methods (solver/newton.py) ---------------------------------------------------
    def rejected(self, newton, error) -> None:
        """The stress update of the iterate in ``newton.model.u`` raised ``error``: diagnose a NaN."""
        from ..mechanics.state import ReturnMapFailure
        if isinstance(error, ReturnMapFailure) and "nan" in str(error).lower():
            try:
                self._diagnose_nan(newton.model)
            except Exception:                  # noqa: BLE001 - a diagnosis must not change the run
                self.nan_diagnosis = None

    def iteration(self, newton, it: int, rnorm: float) -> None:
        """An accepted iterate: its active contact set (models with contact only)."""
        if it == 0:
            self.sets = []                     # a new solve
        if any(getattr(i, "kind", "") == "contact" for i in newton.model.items):
            self.sets.append(_active_set(newton.model))

    def solved(self, newton, ok: bool, its: int, reason: str) -> None:
        """A Newton solve returned: its iterations; if it failed, whether its contact sets cycled."""
        self.total_its += its
        if not ok:
            self.failed_solves += 1
            self.last_failed_chatter = is_cycling(self.sets)
            self.last_failed_changes = sum(1 for a, b in zip(self.sets, self.sets[1:]) if a != b)
            self.chatter_solves += int(self.last_failed_chatter)
        self.sets = []

    # ----------------------------------------------------------------------------------------------
    def _diagnose_nan(self, model) -> None:
        """At an iterate whose stress update returned NaN: the largest omega^2 of the increment and
        the smallest in-plane det F at the quadrature points."""
        import numpy as np
        import ufl
        from mpi4py import MPI

        from .. import compat
        if self._exprs is None or self._exprs_model is not model:
            F = ufl.Identity(2) + ufl.grad(model.u)
            Fn = ufl.Identity(2) + ufl.grad(model.u_n)
            dF = F * ufl.inv(Fn)
            omega = 0.5 * (dF[1, 0] - dF[0, 1])
            pts = model.rule.points
            self._exprs = (compat.expression(omega * omega, pts), compat.expression(ufl.det(F), pts))
            self._exprs_model = model
        w2 = compat.evaluate(self._exprs[0], model.mesh, model.rule.cells)
        det = compat.evaluate(self._exprs[1], model.mesh, model.rule.cells)
        w2 = w2[np.isfinite(w2)]                   # (an iterate that is NaN itself tells nothing)
        det = det[np.isfinite(det)]
        w2max = model.comm.allreduce(float(w2.max()) if w2.size else 0.0, op=MPI.MAX)
        detmin = model.comm.allreduce(float(det.min()) if det.size else 1.0, op=MPI.MIN)
        self.max_omega2 = w2max
        if w2max > 1.0 and model.body.update == "sr":
            self.nan_diagnosis = SR_RANGE
        elif detmin <= 0.0:
            self.nan_diagnosis = INVERTED
        else:
            self.nan_diagnosis = None


def _active_set(model):
    """The contact boundaries' nodes with a negative gap, as a hashable tuple (empty without contact)."""
    import numpy as np
    out = []
    X = None
    for item in model.items:
        if getattr(item, "kind", "") != "contact":
            continue
        dim = model.V.dofmap.index_map_bs
        if X is None:
            X = model.V.tabulate_dof_coordinates()[:, :dim]
        nodes = item.nodes
        x = X[nodes] + model.u.x.array.reshape(-1, dim)[nodes]
        g = item.obstacle.gap_np(x, item.obstacle.displacement(item.factor))
        out.append(tuple(np.flatnonzero(g < 0.0)))
    return tuple(out)

"""The increment loop: load factor t from 0 to t_end in increments, each solved by Newton.

An increment starts from the last converged state, or with ``predictor`` from the Lagrange
extrapolation (linear or quadratic in the load factor) of the last converged states, or ("tangent")
from the Euler step along the path's tangent at the last converged state: K du/dt = -dR/dt, with K
the tangent Newton factorised last (the algorithmic tangent of the increment just converged, so its
plastic points keep loading) and dR/dt a forward difference in the load factor; one
back-substitution, no new factorisation, so it is not counted as a Newton iteration. Unlike an
extrapolation it knows where the path is heading at t_n, not where it came from; the first
increment of a job, before any factorisation, starts from the unloaded state, the first of a later
step from the tangent at the state where the step before ended.
An iterate that stays inadmissible, ``max_it`` iterations, or a residual that grows by
``divergence`` over the increment's first fails the attempt; the loop restores the last converged
state (and the run's residual scale: a failed attempt is no measure of its forces). With ``retry``
the attempt is made once more at the same size from the other start: from the predictor (the
tangent, else the linear extrapolation) if it began at the last state, from the last state if a
predictor led it astray. Begun from the last state, the first iteration of an elastic-plastic
increment sees no strain increment, so every point that was yielding is elastic in its tangent
(the trial stress lies on the yield surface, not beyond it), and a body that flows plastically
can be sent far off: a predictor that rescues such an increment is kept for the rest of the step.
A predictor fails where the path changes its regime (a first contact, a first yield, an
unloading), which the past states cannot foresee; the last state that rescues such an increment
serves that increment only. Every failed attempt is counted by its cause (failures.py). Otherwise,
or if the retry fails too, the loop halves the increment, down to the smallest increment
dt_nom / 2^max_cutbacks;
when an increment of that size fails, the run stops cleanly (every converged increment has already
been handed out). A linear solver that fails for want of memory or of a feature of its build
(newton.py, ``hopeless``) stops the run at once: halving would fail the same way. The floor is
absolute, not a count of failures in a row: near a limit load, where increments converge only when
small and fail again once grown, a count would creep towards the limit for ever. After
``grow_after`` easy increments (at most ``easy_its`` iterations) the increment doubles again, never
beyond its nominal size, so the run comes back onto the nominal load levels.

Data flows one way: :meth:`IncrementalSolver.increments` yields each converged increment before
committing it (the consumer reads the converged state), and commits when the consumer asks for the
next one; nothing is called back. Its parts: where the loop starts (``_begin``), one attempt at an
increment (``_attempt``), what follows a failed one (``_failed``: the other start, half the size,
or the end, ``_stop``), a converged one (``_converged``) and its commit (``_commit``); the
predictors are in predictors.py.
"""
from __future__ import annotations

import logging
import time
from dataclasses import dataclass, field

import numpy as np
from dolfinx import fem

from ..deprecated import renamed_field, warn_renamed
from ..mechanics.model import Model
from ..choices import first_increment_error
from ..parallel import collective
from . import failures
from .newton import Newton, NewtonSettings, Timer
from .predictors import Starts, agrees_with_path, extrapolate

_extrapolate = extrapolate          # (the names this module had)

log = logging.getLogger("comove")


@renamed_field("n_steps", "n_increments")
@dataclass
class StepSettings:
    """Increment control: nominal number of equal increments over the load range, cut-back, growth.
    (``n_steps``, the old name of ``n_increments``, is still taken, with a DeprecationWarning.)"""

    n_increments: int = 20
    t_end: float = 1.0
    max_cutbacks: int = 6
    easy_its: int = 8
    grow_after: int = 1
    predictor: bool | int | str = False  # where an increment starts: False the last converged state;
                                   # True or 1, 2 its linear, quadratic extrapolation (hurts thin
                                   # rotating bodies); "tangent" the Euler step along the path
    first: float = 1.0             # the step's first increment as a fraction 1, 1/2, 1/4, ... of the
                                   # nominal one (then doubled back after easy increments, as after a
                                   # cut-back): a hard start (a first contact, a first yield) at a smaller
                                   # size instead of failed attempts at the nominal one
    retry: bool = False            # a failed increment is tried once more at the same size from the
                                   # other start (a predictor if it started from the last state, the
                                   # last state if it started from a predictor) before it is halved
    chord_tol: float = 0.1         # "tangent": take the last chord c instead when |v - r| > chord_tol |c|,
                                   # r the rate of the quadratic through the last three converged
                                   # states (the chord while there are two). Measured per node on
                                   # the ring (1.4k-45k dofs), as a fraction of the largest nodal
                                   # chord: 0.003-0.026 along the crush, 0.7 to 2.8 where the tangent
                                   # carried a spurious part (docs/performance.md)


@dataclass
class Increment:
    """What the loop reports of a converged increment (``step``, the old name of ``number``, is
    still read, with a DeprecationWarning)."""

    number: int                   # the increment's number in its step, from 1
    load: float
    newton_its: int               # iterations of the converged attempt
    wall_s: float                 # wall time since the previous increment, failed attempts included
    cutbacks: int = 0             # halvings of this increment before the attempt that converged
    failed_its: int = 0           # iterations spent in failed attempts of this increment
    retries: int = 0              # failed attempts tried again at the same size from the other start

    @property
    def step(self) -> int:
        warn_renamed("Increment.step", "Increment.number")
        return self.number


@dataclass
class StepOutcome:
    """How the increment loop of one step ended: its converged increments, whether it completed,
    its message, the failed attempts per cause and, if it stopped, what to change."""

    increments: list[Increment] = field(default_factory=list)
    completed: bool = False
    message: str = ""
    failures: dict = field(default_factory=dict)   # failed attempts per cause (failures.CAUSES)
    last_failure: failures.Failure | None = None
    advice: str = ""              # what to change, when the run stopped at its smallest increment

    @property
    def newton_its(self) -> list[int]:
        return [inc.newton_its for inc in self.increments]


def __getattr__(name: str):
    """``RunResult``, the old name of :class:`StepOutcome`, with a DeprecationWarning."""
    if name == "RunResult":
        warn_renamed("comove_dolfinx.solver.RunResult", "StepOutcome")
        return StepOutcome
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


@dataclass
class _Loop:
    """Where the increment loop of a step stands.

    Where an attempt starts: from a predictor (``pred_now``) or the last converged state. With
    ``retry`` a failed attempt is tried once more at the same size from the other start before the
    increment is halved. A predictor that rescues an increment begun from the last state is kept
    from then on (``use_pred``: that start fails for a lasting reason, its first tangent is elastic
    where the body flows plastically); the last state that rescues one a predictor led astray
    serves that increment only (a predictor fails at a change of regime the past states could not
    foresee: a first contact, a first yield, an unloading)."""

    t: float                      # load factor of the last converged state
    dt: float                     # size of the next attempt
    dt_nom: float                 # the nominal increment
    dt_min: float                 # the smallest increment: dt_nom / 2^max_cutbacks
    past: list                    # converged (load, u), newest last
    use_pred: bool                # the step's increments start from a predictor
    have_rate: bool               # the path's tangent at the last converged state is known (``rate``)
    from_start: bool              # ... only from the step's start: no chord to check it against
    count: int = 0                # increments converged in the step
    easy: int = 0                 # easy increments in a row
    cut: int = 0                  # halvings of the current increment
    failed_its: int = 0           # iterations of its failed attempts
    retried: bool = False         # it was tried again from the other start
    retries: int = 0              # its failed attempts tried again from the other start
    pred_now: bool = False        # the current attempt starts from a predictor
    t_mark: float = 0.0           # when the last increment converged (perf_counter)
    after: tuple = ()             # (past, easy, dt) once the increment yielded is committed


@dataclass
class _Attempt:
    """One Newton solve of an increment: converged (``ok``), iterations, reason, the failure, where
    it started and the residual scale before it."""

    ok: bool
    its: int
    reason: str
    failure: failures.Failure | None
    started: str
    scale: float


class IncrementalSolver:
    """Load factor t from 0 to t_end in increments, each solved by Newton, with cut-back."""

    def __init__(self, model: Model, steps: StepSettings | None = None,
                 newton: NewtonSettings | Newton | None = None, timer: Timer | None = None):
        """``newton``: settings, or a :class:`Newton` of the model to reuse (its matrix, factors
        and residual scale carry over from step to step of a job)."""
        self.model = model
        self.steps = steps or StepSettings()
        if self.steps.n_increments < 1:
            raise ValueError(f"n_increments = {self.steps.n_increments}: need at least one increment")
        why = first_increment_error(self.steps.first, self.steps.max_cutbacks)
        if why:
            raise ValueError(why)
        if isinstance(newton, Newton):
            self.newton, self.timer = newton, newton.timer
        else:
            self.timer = timer or Timer()
            self.newton = Newton(model, newton, self.timer)
        self.relaggers = [item for item in model.items if hasattr(item, "relag_pass")]
        self.max_passes = max([item.max_passes for item in self.relaggers] + [1])

    def _agrees_with_path(self, rate: fem.Function, past) -> bool:
        """Whether the path's tangent ``rate`` agrees with the last converged states ``past``
        (predictors.agrees_with_path, within ``chord_tol``)."""
        return agrees_with_path(self.model, rate, past, self.steps.chord_tol)

    def _friction(self) -> bool:
        """Whether a contact item of the model has friction."""
        return any(float(getattr(item, "mu", 0.0) or 0.0) > 0.0 for item in self.newton.contacts)

    def run(self, callbacks=(), progress=None) -> StepOutcome:
        """Run every increment; each callback(model, increment) is called after every converged one
        (a failure of a callback on one rank stops every rank). ``progress``: optional object with
        ``update(dt)`` (tqdm)."""
        result, last = StepOutcome(), 0.0
        for inc in self.increments(result):
            with self.timer("output"):            # before commit: the increment is still visible
                for cb in callbacks:
                    collective(self.model.comm, cb, self.model, inc)
            if progress is not None:
                progress.update(inc.load - last)
            last = inc.load
        return result

    def increments(self, result: StepOutcome | None = None, resume: dict | None = None):
        """Yield every converged increment while the model still holds its state (not yet
        committed); ``result`` (a StepOutcome) gathers the increments and says how the loop ended.
        ``self.resume_state`` then holds what the loop goes on from (load factor, increment size,
        counters, the predictor's past states): a checkpoint saves it, and ``resume`` (that dict,
        with the model, its items and the last tangent restored and committed) continues the loop
        where it stood, so that a restarted run repeats the uninterrupted one."""
        result = StepOutcome() if result is None else result
        st = self.steps
        loop = self._begin(resume)
        tol = 1e-12 * st.t_end
        while loop.t < st.t_end - tol:
            loop.dt = min(loop.dt, st.t_end - loop.t)
            t_try = loop.t + loop.dt
            attempt = self._attempt(loop, t_try)
            if not attempt.ok:
                if self._failed(loop, attempt, t_try, result):
                    return
                continue
            inc = self._converged(loop, attempt.its, t_try, result)
            yield inc
            self._commit(loop)
        result.completed = True
        result.message = f"completed {loop.count} increments"

    def _begin(self, resume: dict | None) -> _Loop:
        """Where the loop starts: the step's start, or ``resume`` (a checkpoint's resume dict);
        the path's tangent there for the tangent predictor, when Newton has a factorised tangent
        (a later step of a job: the tangent at the state where the last step ended, e.g. the
        elastic unloading when an obstacle starts to withdraw)."""
        m, st = self.model, self.steps
        dt_nom = st.t_end / st.n_increments
        dt, t, count, easy = dt_nom * st.first, 0.0, 0, 0
        dt_min = dt_nom / 2.0 ** st.max_cutbacks
        past = [(0.0, m.u.x.array.copy())]
        self._starts = starts = Starts.of(st)
        self._rate = rate = fem.Function(m.V) if starts.tangent else None
        have_rate = False
        if starts.tangent and self.newton.factorised:
            have_rate = self.newton.load_rate(0.0, rate, 1e-6 * st.t_end)
        from_start = have_rate          # no chord to check it against: dropped if it fails
        if resume is not None:
            t, dt, count, easy = resume["t"], resume["dt"], resume["increment"], resume["easy"]
            past = [(float(a), np.array(b)) for a, b in resume["past"]] or past
            from_start = have_rate = False
            if starts.tangent and self.newton.factorised:
                have_rate = (self.newton.load_rate(t, rate, 1e-6 * st.t_end)
                             and self._agrees_with_path(rate, past))
        use_pred = bool(st.predictor) if resume is None else bool(resume.get("use_pred", st.predictor))
        return _Loop(t=t, dt=dt, dt_nom=dt_nom, dt_min=dt_min, past=past, use_pred=use_pred,
                     have_rate=have_rate, from_start=from_start, count=count, easy=easy,
                     pred_now=use_pred, t_mark=time.perf_counter())

    def _attempt(self, loop: _Loop, t_try: float) -> _Attempt:
        """Solve the increment to load factor ``t_try`` from its start (the predictor's, or the last
        converged state), re-lagging the pressure of true Coulomb friction; an iterate that folds
        the mesh at a node fails it."""
        m, alt = self.model, self._starts.alt
        m.set_load(t_try)
        started = "last state"
        if loop.pred_now and loop.have_rate:
            m.u.x.array[:] = m.u_n.x.array + (t_try - loop.t) * self._rate.x.array
            started = "tangent"
        elif loop.pred_now and alt and len(loop.past) > 1:
            m.u.x.array[:] = extrapolate(loop.past[-(alt + 1):], t_try)
            started = "extrapolation"
        scale = self.newton.residual_scale
        ok, its, reason = self.newton.solve()
        failure = self.newton.failure
        passes = 1
        while ok and passes < self.max_passes and any([item.relag_pass() for item in self.relaggers]):
            ok, more, reason = self.newton.solve()     # true Coulomb: re-lag the pressure
            failure = self.newton.failure
            its += more
            passes += 1
        if ok:
            folded = m.folded_at_nodes()
            if folded is not None:
                ok, reason = False, folded
                failure = failures.Failure(failures.INADMISSIBLE, folded, max_it=self.newton.settings.max_it)
        return _Attempt(ok, its, reason, failure, started, scale)

    def _failed(self, loop: _Loop, attempt: _Attempt, t_try: float, result: StepOutcome) -> bool:
        """Undo the failed ``attempt`` and count it; then try again from the other start, or at half
        the size; True when the loop stops (the smallest increment failed, or the linear solver
        failed in a way no smaller increment cures)."""
        m = self.model
        m.restore()
        # a failed attempt is no measure of the run's forces: an extrapolation that led it
        # astray can start it at a residual many times the load increment's
        self.newton.residual_scale = attempt.scale
        if loop.from_start:
            loop.have_rate = loop.from_start = False
        loop.failed_its += attempt.its
        failure, reason = attempt.failure, attempt.reason
        cause = failure.cause if failure is not None else failures.MAX_IT
        result.failures[cause] = result.failures.get(cause, 0) + 1
        result.last_failure = failure
        log.info("  increment to t = %.6g from the %s failed (%s)", t_try, attempt.started, reason)
        if self.newton.hopeless:          # the linear solver's memory or build: no
            m.set_load(loop.t)            # smaller increment helps
            result.message = (f"stopped at load factor {loop.t:.6g}: an increment failed in a way "
                              f"no smaller increment cures: {reason}")
            return True
        # the other start, once per increment: a predictor if the attempt started from the
        # last state, the last state if a predictor led it astray
        last_state = attempt.started == "last state"
        other = (loop.have_rate or (self._starts.alt and len(loop.past) > 1)) if last_state else True
        if self.steps.retry and not loop.retried and other:
            loop.retried, loop.retries = True, loop.retries + 1
            loop.pred_now = last_state
            return False
        if loop.dt <= loop.dt_min * (1.0 + 1e-9):
            self._stop(loop, failure, reason, result)
            return True
        loop.dt *= 0.5
        loop.cut += 1
        loop.easy = 0
        loop.pred_now = loop.use_pred
        return False

    def _stop(self, loop: _Loop, failure, reason: str, result: StepOutcome) -> None:
        """Stop the loop after an increment of the smallest size failed: back at the last converged
        load, with a message and the advice that the failure suggests."""
        m, st = self.model, self.steps
        m.set_load(loop.t)
        result.advice = failures.advice(
            failure, contact=bool(self.newton.contacts), friction=self._friction(),
            predictor=loop.use_pred, force_controlled=failures.force_controlled(m.items),
            target=self.newton.tolerance, n=st.n_increments,
            line_search=self.newton.line_search is not None)
        result.message = (f"stopped at load factor {loop.t:.6g}: an increment of the "
                          f"smallest size ({loop.dt:.3g}, after {loop.cut} cut-backs in a row)"
                          f" failed: {reason}" + (f"; {result.advice}" if result.advice else ""))

    def _converged(self, loop: _Loop, its: int, t_try: float, result: StepOutcome) -> Increment:
        """The increment that converged at ``t_try`` in ``its`` iterations, recorded; and where the
        loop goes on from once it is committed (``self.resume_state``, computed before the consumer
        sees the increment, and ``loop.after``)."""
        st = self.steps
        if loop.retried and loop.pred_now and not loop.use_pred:
            log.info("  the increments start from the predictor from now on")
            loop.use_pred = True
        loop.t, loop.count = t_try, loop.count + 1
        t, dt = loop.t, loop.dt
        inc = Increment(loop.count, t, its, time.perf_counter() - loop.t_mark, loop.cut, loop.failed_its,
                        loop.retries)
        result.increments.append(inc)
        loop.cut, loop.failed_its, loop.retried, loop.retries = 0, 0, False, 0
        loop.pred_now = loop.use_pred
        keep = self._starts.keep
        past_next = loop.past[-keep:] + [(t, self.model.u.x.array.copy())] if keep else loop.past
        easy_next, dt_next = loop.easy + 1 if its <= st.easy_its else 0, dt
        # grow back towards the nominal increment, staying on the grid of the doubled step
        if easy_next >= st.grow_after and dt < loop.dt_nom and abs(t / (2 * dt) - round(t / (2 * dt))) < 1e-9:
            dt_next, easy_next = min(2 * dt, loop.dt_nom), 0
        self.resume_state = {"t": t, "dt": dt_next, "increment": loop.count, "easy": easy_next,
                             "past": past_next, "use_pred": loop.use_pred}
        loop.after = (past_next, easy_next, dt_next)
        return inc

    def _commit(self, loop: _Loop) -> None:
        """Commit the increment the consumer has seen and move the loop on: the predictor's past
        states, the path's tangent at the new state, the next increment's size."""
        st = self.steps
        self.model.commit()
        loop.past, easy_next, dt_next = loop.after
        if self._starts.tangent:
            loop.from_start = False
            loop.have_rate = (self.newton.load_rate(loop.t, self._rate, 1e-6 * st.t_end)
                              and self._agrees_with_path(self._rate, loop.past))
        loop.t_mark = time.perf_counter()
        loop.easy, loop.dt = easy_next, dt_next

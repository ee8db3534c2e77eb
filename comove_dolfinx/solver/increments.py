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
next one; nothing is called back.
"""
from __future__ import annotations

import logging
import time
from dataclasses import dataclass, field

import numpy as np
from dolfinx import fem
from mpi4py import MPI

from ..mechanics.model import Model
from ..choices import first_increment_error
from ..parallel import collective
from . import failures
from .newton import Newton, NewtonSettings, Timer

log = logging.getLogger("comove")


def _extrapolate(points, t: float) -> np.ndarray:
    """Lagrange extrapolation of the converged states ``points`` = [(t_i, u_i)] to load t."""
    out = np.zeros_like(points[0][1])
    for i, (ti, ui) in enumerate(points):
        w = 1.0
        for j, (tj, _) in enumerate(points):
            if j != i:
                w *= (t - tj) / (ti - tj)
        out += w * ui
    return out


def _path_rate(points) -> np.ndarray:
    """du/dt at the newest of the converged states ``points`` = [(t_i, u_i)] (two or three, oldest
    first): the chord through two; through three the slope of their quadratic, the last chord plus
    (t2 - t1) times the second divided difference (second-order accurate on a smooth path)."""
    (t1, u1), (t2, u2) = points[-2:]
    chord = (u2 - u1) / (t2 - t1)
    if len(points) < 3:
        return chord
    t0, u0 = points[-3]
    return chord + (t2 - t1) * (chord - (u1 - u0) / (t1 - t0)) / (t2 - t0)


def _force_controlled(items) -> bool:
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


@dataclass
class StepSettings:
    """Increment control: nominal number of equal increments over the load range, cut-back, growth."""

    n_steps: int = 20
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
    """What the loop reports of a converged increment."""

    step: int
    load: float
    newton_its: int               # iterations of the converged attempt
    wall_s: float                 # wall time since the previous increment, failed attempts included
    cutbacks: int = 0             # halvings of this increment before the attempt that converged
    failed_its: int = 0           # iterations spent in failed attempts of this increment
    retries: int = 0              # failed attempts tried again at the same size from the other start


@dataclass
class RunResult:
    increments: list[Increment] = field(default_factory=list)
    completed: bool = False
    message: str = ""
    failures: dict = field(default_factory=dict)   # failed attempts per cause (failures.CAUSES)
    last_failure: failures.Failure | None = None
    advice: str = ""              # what to change, when the run stopped at its smallest increment

    @property
    def newton_its(self) -> list[int]:
        return [inc.newton_its for inc in self.increments]


class IncrementalSolver:
    """Load factor t from 0 to t_end in increments, each solved by Newton, with cut-back."""

    def __init__(self, model: Model, steps: StepSettings | None = None,
                 newton: NewtonSettings | Newton | None = None, timer: Timer | None = None):
        """``newton``: settings, or a :class:`Newton` of the model to reuse (its matrix, factors
        and residual scale carry over from step to step of a job)."""
        self.model = model
        self.steps = steps or StepSettings()
        if self.steps.n_steps < 1:
            raise ValueError(f"n_steps = {self.steps.n_steps}: need at least one increment")
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
        """Whether the path's tangent ``rate`` at the newest state lies within ``chord_tol`` of the
        rate that the last converged states give, |v - r| <= chord_tol |c|: r the slope of the
        quadratic through the last three (second-order accurate on a smooth path, so a path that
        curves, as the elastica's does, is not taken for a spurious mode) or the chord c of the
        last increment while there are two. Near a mechanism (a ring of plastic hinges) the tangent
        is almost singular and its solution can carry a spurious part along it; the predictor then
        takes the chord (linear extrapolation) instead."""
        (t0, u0), (t1, u1) = past[-2:]
        chord = (u1 - u0) / (t1 - t0)
        ref = _path_rate(past[-3:])
        imap = self.model.V.dofmap.index_map
        n = imap.size_local * self.model.V.dofmap.index_map_bs
        d = rate.x.array[:n] - ref[:n]
        sums = np.array([d @ d, chord[:n] @ chord[:n]])
        self.model.comm.Allreduce(MPI.IN_PLACE, sums, op=MPI.SUM)     # (a buffer: no pickling)
        diff2, chord2 = sums
        return bool(diff2 <= self.steps.chord_tol ** 2 * chord2)

    def _friction(self) -> bool:
        """Whether a contact item of the model has friction."""
        return any(float(getattr(item, "mu", 0.0) or 0.0) > 0.0 for item in self.newton.contacts)

    def run(self, callbacks=(), progress=None) -> RunResult:
        """Run every increment; each callback(model, increment) is called after every converged one
        (a failure of a callback on one rank stops every rank). ``progress``: optional object with
        ``update(dt)`` (tqdm)."""
        result, last = RunResult(), 0.0
        for inc in self.increments(result):
            with self.timer("output"):            # before commit: the increment is still visible
                for cb in callbacks:
                    collective(self.model.comm, cb, self.model, inc)
            if progress is not None:
                progress.update(inc.load - last)
            last = inc.load
        return result

    def increments(self, result: RunResult | None = None, resume: dict | None = None):
        """Yield every converged increment while the model still holds its state (not yet
        committed); ``result`` (a RunResult) gathers the increments and says how the loop ended.
        ``self.resume_state`` then holds what the loop goes on from (load factor, increment size,
        counters, the predictor's past states): a checkpoint saves it, and ``resume`` (that dict,
        with the model, its items and the last tangent restored and committed) continues the loop
        where it stood, so that a restarted run repeats the uninterrupted one."""
        result = RunResult() if result is None else result
        m, st = self.model, self.steps
        dt_nom = st.t_end / st.n_steps
        dt, t, step, cut, easy = dt_nom * st.first, 0.0, 0, 0, 0
        dt_min = dt_nom / 2.0 ** st.max_cutbacks
        past = [(0.0, m.u.x.array.copy())]          # converged (load, u), newest last
        tangent = st.predictor == "tangent"
        if isinstance(st.predictor, str) and not tangent:
            raise ValueError(f"predictor = {st.predictor!r}: choose 0, 1, 2 or tangent")
        # the tangent's fallback is the linear extrapolation (the chord); it keeps the last three
        # states, which its check compares it with (_agrees_with_path)
        order = 1 if tangent else int(st.predictor)
        alt = 1 if (st.retry and order == 0) else order     # the extrapolation of a predictor start
        keep = 2 if tangent else alt
        rate, have_rate = fem.Function(m.V) if tangent else None, False
        if tangent and self.newton.factorised:
            # a later step of a job: the path's tangent at the state where the last step ended
            # (e.g. the elastic unloading when an obstacle starts to withdraw)
            have_rate = self.newton.load_rate(0.0, rate, 1e-6 * st.t_end)
        from_start = have_rate          # no chord to check it against: dropped if it fails
        if resume is not None:
            t, dt, step, easy = resume["t"], resume["dt"], resume["step"], resume["easy"]
            past = [(float(a), np.array(b)) for a, b in resume["past"]] or past
            from_start = have_rate = False
            if tangent and self.newton.factorised:
                have_rate = (self.newton.load_rate(t, rate, 1e-6 * st.t_end)
                             and self._agrees_with_path(rate, past))
        # where an attempt starts: from a predictor (``use_pred``) or the last converged state. With
        # ``retry`` a failed attempt is tried once more at the same size from the other start before
        # the increment is halved. A predictor that rescues an increment begun from the last state
        # is kept from then on (that start fails for a lasting reason: its first tangent is elastic
        # where the body flows plastically); the last state that rescues one a predictor led astray
        # serves that increment only (a predictor fails at a change of regime the past states could
        # not foresee: a first contact, a first yield, an unloading)
        use_pred = bool(st.predictor) if resume is None else bool(resume.get("use_pred", st.predictor))
        t_mark, failed_its, retried, retries = time.perf_counter(), 0, False, 0
        pred_now = use_pred
        tol = 1e-12 * st.t_end
        while t < st.t_end - tol:
            dt = min(dt, st.t_end - t)
            t_try = t + dt
            m.set_load(t_try)
            started = "last state"
            if pred_now and have_rate:
                m.u.x.array[:] = m.u_n.x.array + (t_try - t) * rate.x.array
                started = "tangent"
            elif pred_now and alt and len(past) > 1:
                m.u.x.array[:] = _extrapolate(past[-(alt + 1):], t_try)
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
            if not ok:
                m.restore()
                # a failed attempt is no measure of the run's forces: an extrapolation that led it
                # astray can start it at a residual many times the load increment's
                self.newton.residual_scale = scale
                if from_start:
                    have_rate = from_start = False
                failed_its += its
                cause = failure.cause if failure is not None else failures.MAX_IT
                result.failures[cause] = result.failures.get(cause, 0) + 1
                result.last_failure = failure
                log.info("  increment to t = %.6g from the %s failed (%s)", t_try, started, reason)
                if self.newton.hopeless:          # the linear solver's memory or build: no
                    m.set_load(t)                 # smaller increment helps
                    result.message = (f"stopped at load factor {t:.6g}: an increment failed in a way "
                                      f"no smaller increment cures: {reason}")
                    return
                # the other start, once per increment: a predictor if the attempt started from the
                # last state, the last state if a predictor led it astray
                other = (have_rate or (alt and len(past) > 1)) if started == "last state" else True
                if st.retry and not retried and other:
                    retried, retries = True, retries + 1
                    pred_now = started == "last state"
                    continue
                if dt <= dt_min * (1.0 + 1e-9):
                    m.set_load(t)
                    result.advice = failures.advice(
                        failure, contact=bool(self.newton.contacts), friction=self._friction(),
                        predictor=use_pred, force_controlled=_force_controlled(m.items),
                        target=self.newton.tolerance, n=st.n_steps,
                        line_search=self.newton.line_search is not None)
                    result.message = (f"stopped at load factor {t:.6g}: an increment of the "
                                      f"smallest size ({dt:.3g}, after {cut} cut-backs in a row)"
                                      f" failed: {reason}" + (f"; {result.advice}" if result.advice else ""))
                    return
                dt *= 0.5
                cut += 1
                easy = 0
                pred_now = use_pred
                continue
            if retried and pred_now and not use_pred:
                log.info("  the increments start from the predictor from now on")
                use_pred = True
            t, step = t_try, step + 1
            inc = Increment(step, t, its, time.perf_counter() - t_mark, cut, failed_its, retries)
            result.increments.append(inc)
            cut, failed_its, retried, retries = 0, 0, False, 0
            pred_now = use_pred
            # where the loop goes on from (computed before the consumer sees the increment)
            past_next = past[-keep:] + [(t, m.u.x.array.copy())] if keep else past
            easy_next, dt_next = easy + 1 if its <= st.easy_its else 0, dt
            # grow back towards the nominal increment, staying on the grid of the doubled step
            if easy_next >= st.grow_after and dt < dt_nom and abs(t / (2 * dt) - round(t / (2 * dt))) < 1e-9:
                dt_next, easy_next = min(2 * dt, dt_nom), 0
            self.resume_state = {"t": t, "dt": dt_next, "step": step, "easy": easy_next,
                                 "past": past_next, "use_pred": use_pred}
            yield inc
            m.commit()
            past = past_next
            if tangent:
                from_start = False
                have_rate = (self.newton.load_rate(t, rate, 1e-6 * st.t_end)
                             and self._agrees_with_path(rate, past))
            t_mark = time.perf_counter()
            easy, dt = easy_next, dt_next
        result.completed = True
        result.message = f"completed {step} increments"

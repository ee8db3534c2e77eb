"""Newton iterations and the increment loop with automatic cut-back.

Newton works on the total displacement u. Each iteration evaluates the stress update (and return
map) at the quadrature points, assembles the residual and the exact Jacobian and solves with MUMPS;
the matrix, vectors and KSP are created once and reused, so MUMPS's symbolic analysis is done once.

Convergence: ||R|| <= rtol * R_scale + atol, with R_scale (``scale``) either the largest initial
residual norm of the increments so far ("initial", a force scale of the run, which depends on the
increment size), or the norm of the internal force vector F_int = int P : Grad v at the iterate
("force": at equilibrium the applied loads, reactions and contact forces, so rtol bounds the
out-of-balance force as a fraction of the forces the body carries), or a Newton correction
||du|| <= stol * ||u|| (the residual of a stiff body stalls at a round-off floor set by its
internal forces, which can exceed rtol * R_scale when the load increments are small; only a full
step counts). Each Newton correction is halved (up to ``backtracks`` times) while it leads to an
inadmissible iterate (det F <= 0, or an increment the S-R split cannot represent). Line search (``line_search``): with contact terms by
default, corrections after the first ``free_its`` of an increment must also lower ||R|| (Armijo test
on the residual norm), which stops the active-set and stick/slip cycling; without contact it is off,
because ||R|| is not monotone along a converging Newton path of a rotating slender body (the first
corrections raise the axial residual by orders of magnitude). "energy" is Crisfield's search for the
root of du . R(u + a du) along the correction (regula falsi), for bodies whose corrections overshoot
(plastic hinges; Crisfield, Non-linear Finite Element Analysis of Solids and Structures, vol. 1, 9.3).
An increment starts from the last converged state, or with ``predictor`` from the Lagrange
extrapolation (linear or quadratic in the load factor) of the last converged states, or ("tangent")
from the Euler step along the path's tangent at the last converged state: K du/dt = -dR/dt, with K
the tangent Newton factorised last (the algorithmic tangent of the increment just converged, so its
plastic points keep loading) and dR/dt a forward difference in the load factor (the loads are linear
in it); one back-substitution, no new factorisation, so it is not counted as a Newton iteration.
Unlike an extrapolation it knows where the path is heading at t_n, not where it came from; the first
increment, before any factorisation, starts from the unloaded state.
An iterate that stays inadmissible, ``max_it`` iterations, or a residual that grows by
``divergence`` over the increment's first fails the increment; the loop
then restores the last converged state and halves the increment, down to the smallest increment
dt_nom / 2^max_cutbacks; when an increment of that size fails, the run stops cleanly (every converged
increment has already been handed to the callbacks). The floor is absolute, not a count of failures
in a row: near a limit load, where increments converge only when small and fail again once grown,
a count would creep towards the limit for ever.
After ``grow_after`` easy increments (at most ``easy_its`` iterations) the increment doubles again,
never beyond its nominal size, so the run comes back onto the nominal load levels.
"""
from __future__ import annotations

import logging
import time
from collections import defaultdict
from contextlib import contextmanager
from dataclasses import dataclass, field

import numpy as np
from dolfinx import fem
from mpi4py import MPI
from petsc4py import PETSc

from . import compat
from .model import InvertedElement, Model, ReturnMapFailure
from .parallel import collective, first_failure

log = logging.getLogger("comove")


class Timer:
    """Wall-time accumulated per category (assembly, solve, stress update, output, ...)."""

    def __init__(self):
        self.totals: dict[str, float] = defaultdict(float)

    @contextmanager
    def __call__(self, name: str):
        t0 = time.perf_counter()
        try:
            yield
        finally:
            self.totals[name] += time.perf_counter() - t0

    def report(self) -> str:
        total = sum(self.totals.values())
        parts = [f"{k} {v:.2f} s ({100 * v / total:.0f} %)" for k, v in
                 sorted(self.totals.items(), key=lambda kv: -kv[1])] if total else []
        return "timing: " + ", ".join(parts)


@dataclass
class NewtonSettings:
    rtol: float = 1e-8
    atol: float = 1e-12
    stol: float = 1e-10
    max_it: int = 25
    divergence: float = 1e12
    backtracks: int = 4
    free_its: int = 5              # corrections taken in full (unless inadmissible) before the Armijo test
    line_search: bool | str | None = None   # None: on when the model has contact (boundary) terms;
                                            # True/"residual": Armijo on ||R||; "energy": du.R(u + a du);
                                            # False/"none": off
    energy_eta: float = 0.8        # energy search: accept a step once |du.R| <= eta |du.R(u)|
    scale: str = "initial"         # what rtol is relative to: "initial", the largest initial
                                   # residual of the run; "force", ||F_int|| of the iterate


class Newton:
    """Newton-Raphson on ``model.u`` with an exact Jacobian and a direct solver (MUMPS)."""

    def __init__(self, model: Model, settings: NewtonSettings | None = None,
                 timer: Timer | None = None):
        self.model = model
        self.settings = settings or NewtonSettings()
        self.timer = timer or Timer()
        self.A = compat.create_matrix(model.jacobian_form)
        self.b = compat.create_vector(model.residual_form)
        self.ksp = PETSc.KSP().create(model.comm)
        self.ksp.setOperators(self.A)
        self.ksp.setType("preonly")
        pc = self.ksp.getPC()
        pc.setType("lu")
        pc.setFactorSolverType("mumps")
        ls = self.settings.line_search
        if ls is None:
            ls = bool(model.boundary_terms)
        self.line_search = {True: "residual", False: None, "none": None}.get(ls, ls)
        if self.line_search not in (None, "residual", "energy"):
            raise ValueError(f"line_search = {ls!r}: choose residual, energy or none")
        if self.settings.scale not in ("initial", "force"):
            raise ValueError(f"scale = {self.settings.scale!r}: choose initial or force")
        self._b_old = self.b.duplicate()
        self._f = self.b.duplicate()
        self.factorised = False            # the KSP holds the LU factors of a tangent
        self.residual_scale = 0.0
        self.history: list[tuple[float, float]] = []

    def residual(self) -> float:
        """Assemble -R (with the Dirichlet rows set to the constraint violation) into b; its norm."""
        m, b = self.model, self.b
        with self.timer("stress update"):
            m.evaluate_stress()
        with self.timer("assembly"):
            compat.assemble_vector(b, m.residual_form, m.jacobian_form, m.bcs, compat.petsc_vec(m.u))
            b.scale(-1.0)
        return b.norm()

    def _solve_linear(self) -> str | None:
        """Solve J du = -R into model.du; None, or why it failed (the same on every rank: an error
        raised on one rank's part of the solve becomes every rank's failure)."""
        err = None
        try:
            self.ksp.solve(self.b, compat.petsc_vec(self.model.du))
        except PETSc.Error as e:
            err = e
        failure = first_failure(self.model.comm, err)
        if failure is None:
            reason = self.ksp.getConvergedReason()
            if reason < 0:
                failure = f"the linear solver failed (PETSc KSP reason {reason})"
        if failure is not None:
            self.factorised = False
            return f"linear solve: {failure}"
        self.model.du.x.scatter_forward()
        return None

    def force_scale(self) -> float:
        """||F_int|| at the current iterate (stress of the last residual evaluation): the forces
        the body carries, reactions and contact forces included."""
        f = self._f
        compat.assemble_vector(f, self.model.internal_force_form)
        return f.norm()

    def _converged(self, rnorm: float) -> bool:
        """The residual test; with scale "force" against ||F_int|| of the current iterate."""
        s = self.settings
        if s.scale == "force":
            with self.timer("assembly"):
                self.residual_scale = self.force_scale()
        return rnorm <= s.rtol * self.residual_scale + s.atol

    def _trial(self, u0: np.ndarray, alpha: float):
        """u = u0 + alpha du and its ||R||; (None, error) if the iterate is inadmissible."""
        m = self.model
        m.u.x.array[:] = u0 + alpha * m.du.x.array
        try:
            return self.residual(), None
        except (InvertedElement, ReturnMapFailure) as e:
            return None, e

    def _settle(self, u0: np.ndarray, alpha: float | None, r_old: float, err):
        """End a search on the chosen step (or back at u0 when no trial was admissible)."""
        if alpha is None:
            self.model.u.x.array[:] = u0
            return r_old, 0.0, err
        r, _ = self._trial(u0, alpha)
        return r, alpha, None

    def _line_search(self, r_old: float, armijo: bool = True):
        """Move u along the Newton correction du: the full step if it is admissible and lowers
        ||R||; otherwise halve it (up to ``backtracks`` times) until ||R|| <= (1 - 1e-4 alpha) r_old,
        keeping the best admissible step when none does. Returns (||R||, alpha, error or None)."""
        u0 = self.model.u.x.array.copy()
        best, alpha, err = None, 1.0, None
        for _ in range(self.settings.backtracks + 1):
            r, e = self._trial(u0, alpha)
            if r is None:
                err, alpha = e, 0.5 * alpha
                continue
            if best is None or r < best[0]:
                best = (r, alpha)
            if not (self.line_search and armijo) or r <= (1.0 - 1e-4 * alpha) * r_old:
                return r, alpha, None
            alpha *= 0.5
        return self._settle(u0, best[1] if best else None, r_old, err)

    def _energy_search(self, r_old: float):
        """Crisfield's line search on s(a) = du . R(u + a du), s(0) < 0 along a descent direction:
        the full step if |s(1)| <= eta |s(0)| or s(1) still has the sign of s(0) (no extrapolation);
        otherwise regula falsi on the bracket of the sign change (at most ``backtracks`` more
        trials), keeping the trial of smallest |s|. An inadmissible trial is halved.
        Returns (||R||, alpha, error or None)."""
        m, st = self.model, self.settings
        u0 = m.u.x.array.copy()
        s0 = -self._b_old.dot(compat.petsc_vec(m.du))           # b = -R
        lo, hi = (0.0, s0), None
        alpha, err, best = 1.0, None, None
        for _ in range(st.backtracks + 1):
            r, e = self._trial(u0, alpha)
            if r is None:
                err, hi = e, None
                alpha = 0.5 * (lo[0] + alpha)
                continue
            s1 = -self.b.dot(compat.petsc_vec(m.du))
            if best is None or abs(s1) < best[0]:
                best = (abs(s1), alpha)
            if abs(s1) <= st.energy_eta * abs(s0) or (s1 * s0 > 0 and hi is None):
                return r, alpha, None
            if s1 * s0 > 0:
                lo = (alpha, s1)
            else:
                hi = (alpha, s1)
            a = lo[0] + (hi[0] - lo[0]) * lo[1] / (lo[1] - hi[1])
            width = hi[0] - lo[0]
            alpha = min(max(a, lo[0] + 0.1 * width), hi[0] - 0.1 * width)
        return self._settle(u0, best[1] if best else None, r_old, err)

    def solve(self) -> tuple[bool, int, str]:
        """Iterate from the current ``model.u``; returns (converged, iterations, reason)."""
        m, s = self.model, self.settings
        self.history = []
        try:
            r0 = rnorm = self.residual()
        except (InvertedElement, ReturnMapFailure) as err:
            return False, 0, str(err)
        if s.scale == "initial":
            self.residual_scale = max(self.residual_scale, r0)
        for it in range(1, s.max_it + 1):
            if self._converged(rnorm):
                return True, it - 1, "converged"
            with self.timer("assembly"):
                compat.assemble_matrix(self.A, m.jacobian_form, m.bcs)
            with self.timer("solve"):
                failure = self._solve_linear()
            if failure is not None:
                return False, it, failure
            self.factorised = True
            dnorm = compat.petsc_vec(m.du).norm()
            if not np.isfinite(dnorm):
                return False, it, "the Newton correction is not finite (singular tangent?)"
            if self.line_search == "energy":
                self.b.copy(self._b_old)
                rnorm, alpha, err = self._energy_search(rnorm)
            else:
                rnorm, alpha, err = self._line_search(rnorm, armijo=it > s.free_its)
            if err is not None:
                return False, it, str(err)
            if alpha < 1.0:
                log.info("    Newton %2d: step scaled by %g", it, alpha)
            self.history.append((rnorm, dnorm))
            log.info("    Newton %2d: |R| = %.3e (rel %.1e), |du| = %.3e", it, rnorm,
                     rnorm / max(self.residual_scale, 1e-300), dnorm)
            if not np.isfinite(rnorm) or rnorm > s.divergence * max(r0, s.atol):
                return False, it, f"diverged (|R| = {rnorm:.3e})"
            if alpha == 1.0 and dnorm <= s.stol * compat.petsc_vec(m.u).norm():
                return True, it, "converged"
        converged = self._converged(rnorm)
        return converged, s.max_it, "converged" if converged else f"no convergence in {s.max_it} iterations"

    def load_rate(self, t: float, rate: fem.Function, eps: float) -> bool:
        """The path's tangent at the current state and load factor t into ``rate``: K v = -dR/dt with
        the last factorised tangent K and dR/dt = (R(t + eps) - R(t)) / eps; False (rate untouched)
        before any factorisation or if the state cannot be evaluated."""
        if not self.factorised:
            return False
        m = self.model
        rhs = self._b_old
        try:
            with self.timer("predictor"):
                m.set_load(t + eps)
                self.residual()
                self.b.copy(rhs)
                m.set_load(t)
                self.residual()
                rhs.axpy(-1.0, self.b)          # b = -R: rhs = -(R(t + eps) - R(t))
                rhs.scale(1.0 / eps)
                err = None
                try:
                    self.ksp.solve(rhs, compat.petsc_vec(rate))
                except PETSc.Error as e:
                    err = e
                if first_failure(m.comm, err) is not None or self.ksp.getConvergedReason() < 0:
                    return False
                rate.x.scatter_forward()
        except (InvertedElement, ReturnMapFailure):
            m.set_load(t)
            return False
        return bool(m.comm.allreduce(bool(np.all(np.isfinite(rate.x.array))), op=MPI.LAND))


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
    chord_tol: float = 0.1         # "tangent": take the last chord instead when |v - c| > chord_tol |c|
                                   # (ring: 0.01-0.05 along the crush, 0.18 and 0.75 where the
                                   # tangent carried a spurious part and the next increment failed)


@dataclass
class Increment:
    """What a converged increment reports to the callbacks."""

    step: int
    load: float
    newton_its: int               # iterations of the converged attempt
    wall_s: float                 # wall time since the previous increment, failed attempts included
    cutbacks: int = 0
    failed_its: int = 0           # iterations spent in failed attempts of this increment


@dataclass
class RunResult:
    increments: list[Increment] = field(default_factory=list)
    completed: bool = False
    message: str = ""

    @property
    def newton_its(self) -> list[int]:
        return [inc.newton_its for inc in self.increments]


class IncrementalSolver:
    """Load factor t from 0 to t_end in increments, each solved by Newton, with cut-back."""

    def __init__(self, model: Model, steps: StepSettings | None = None,
                 newton: NewtonSettings | None = None, timer: Timer | None = None):
        self.model = model
        self.steps = steps or StepSettings()
        if self.steps.n_steps < 1:
            raise ValueError(f"n_steps = {self.steps.n_steps}: need at least one increment")
        self.timer = timer or Timer()
        self.newton = Newton(model, newton, self.timer)
        self.max_passes = max([getattr(t, "max_passes", 1) for t in model.boundary_terms] + [1])

    def _agrees_with_chord(self, rate: fem.Function, past) -> bool:
        """Whether the path's tangent ``rate`` at the newest state lies within ``chord_tol`` of the
        chord of the last increment, |v - c| <= chord_tol |c|. Near a mechanism (a ring of plastic
        hinges) the tangent is almost singular and its solution can carry a spurious part along it;
        the predictor then takes the chord (linear extrapolation) instead."""
        (t0, u0), (t1, u1) = past[-2:]
        chord = (u1 - u0) / (t1 - t0)
        imap = self.model.V.dofmap.index_map
        n = imap.size_local * self.model.V.dofmap.index_map_bs
        local = np.array([np.sum((rate.x.array[:n] - chord[:n]) ** 2), np.sum(chord[:n] ** 2)])
        diff2, chord2 = self.model.comm.allreduce(local, op=MPI.SUM)
        return bool(diff2 <= self.steps.chord_tol ** 2 * chord2)

    def run(self, callbacks=(), progress=None) -> RunResult:
        """Run the increments; each callback(model, increment) is called after every converged one.

        ``progress``: optional object with ``update(dt)`` and ``set_postfix_str(text)`` (tqdm).
        """
        m, st = self.model, self.steps
        dt_nom = st.t_end / st.n_steps
        dt, t, step, cut, easy = dt_nom, 0.0, 0, 0, 0
        dt_min = dt_nom / 2.0 ** st.max_cutbacks
        past = [(0.0, m.u.x.array.copy())]          # converged (load, u), newest last
        tangent = st.predictor == "tangent"
        if isinstance(st.predictor, str) and not tangent:
            raise ValueError(f"predictor = {st.predictor!r}: choose 0, 1, 2 or tangent")
        # the tangent keeps the last two states: its fallback is the linear extrapolation (the chord)
        order = 1 if tangent else int(st.predictor)
        rate, have_rate = fem.Function(m.V) if tangent else None, False
        result = RunResult()
        t_mark, failed_its = time.perf_counter(), 0
        tol = 1e-12 * st.t_end
        while t < st.t_end - tol:
            dt = min(dt, st.t_end - t)
            t_try = t + dt
            m.set_load(t_try)
            if have_rate:
                m.u.x.array[:] = m.u_n.x.array + (t_try - t) * rate.x.array
            elif order and len(past) > 1:
                m.u.x.array[:] = _extrapolate(past[-(order + 1):], t_try)
            ok, its, reason = self.newton.solve()
            passes = 1
            while ok and passes < self.max_passes and any([term.relag_pass(m) for term in
                                                           m.boundary_terms]):
                ok, more, reason = self.newton.solve()     # true Coulomb: re-lag the pressure
                its += more
                passes += 1
            if not ok:
                m.restore()
                cut += 1
                failed_its += its
                log.info("  increment to t = %.6g failed (%s)", t_try, reason)
                if dt <= dt_min * (1.0 + 1e-9):
                    m.set_load(t)
                    result.message = (f"stopped at load factor {t:.6g}: an increment of the "
                                      f"smallest size ({dt:.3g}, after {cut - 1} cut-backs in a row)"
                                      f" failed: {reason}")
                    return result
                dt *= 0.5
                easy = 0
                continue
            t, step = t_try, step + 1
            inc = Increment(step, t, its, time.perf_counter() - t_mark, cut, failed_its)
            result.increments.append(inc)
            cut, failed_its = 0, 0
            with self.timer("output"):            # before commit: the increment is still visible
                for cb in callbacks:               # a failure on one rank stops every rank
                    collective(m.comm, cb, m, inc)
            m.commit()
            past = past[-order:] + [(t, m.u_n.x.array.copy())] if order else past
            if tangent:
                have_rate = (self.newton.load_rate(t, rate, 1e-6 * st.t_end)
                             and self._agrees_with_chord(rate, past))
            if progress is not None:
                progress.update(dt)
            t_mark = time.perf_counter()
            easy = easy + 1 if its <= st.easy_its else 0
            # grow back towards the nominal increment, staying on the grid of the doubled step
            if easy >= st.grow_after and dt < dt_nom and abs(t / (2 * dt) - round(t / (2 * dt))) < 1e-9:
                dt = min(2 * dt, dt_nom)
                easy = 0
        result.completed = True
        result.message = f"completed {step} increments"
        return result

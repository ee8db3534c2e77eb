"""Newton iterations with the exact Jacobian and a direct solver.

Newton works on the total displacement u. Each iteration evaluates the stress update (and return
map) at the quadrature points, assembles the residual and the exact Jacobian and solves with MUMPS;
the matrix, vectors and KSP are created once and reused, so MUMPS's symbolic analysis is done once.
The linear solver reads PETSc options under the prefix ``comove_`` (linear.py): another direct
solver or ordering, or an iterative solver (GMRES with algebraic multigrid).

Convergence: ||R|| <= rtol * R_scale + min(atol, rtol * F_run), with R_scale (``scale``) either the
largest initial residual norm of the increments so far ("initial", a force scale of the run, which
depends on the increment size), or the norm of the internal force vector F_int = int P : Grad v at
the iterate ("force": at equilibrium the applied loads, reactions and contact forces, so rtol bounds
the out-of-balance force as a fraction of the forces the body carries; the residual is then
assembled as F_int plus the items' terms, so that F_int comes with it). The absolute tolerance atol
(in units of force) is capped at rtol times F_run, the largest force the run has met (its largest
initial residual of an increment, and with scale "force" its largest ||F_int||): a problem whose
forces are all of the order of atol or below (a Young's modulus of 1e-8, or units in which the
loads are 1e-13) is held to the relative test and never accepted at its unloaded state, while a
problem whose forces exceed atol / rtol is tested exactly as with the plain atol. A residual whose
norm is not finite (forces beyond the range of double precision) is never accepted: the solve
fails at once, and no smaller increment is tried. Or a Newton correction
||du|| <= stol * ||u|| (the residual of a stiff body stalls at a round-off floor set by its
internal forces, which can exceed rtol * R_scale when the load increments are small; only a full
step counts). Corrections are scaled by the line searches of linesearch.py. A failure of the
linear solve on any rank (an error, a negative PETSc reason, a correction that is not finite) is a
failed iteration on every rank. docs/theory.md section 7.

A failed solve leaves ``Newton.failure`` (failures.py): its cause (an inadmissible iterate,
``max_it``, divergence, the linear solver), the residual norms of its iterates and, with contact, in
how many of the last iterations the active contact set (the boundary nodes with a negative gap)
changed; the increment loop counts the causes and names a remedy from them.

Observation: ``NewtonSettings.monitor`` is an object with any of the methods

* ``iteration(newton, it, rnorm)``: at each residual test (rtol, atol) of an accepted iterate, after
  ``it`` corrections of this solve (``model.u`` holds the iterate, ``rnorm`` is its ||R||);
* ``rejected(newton, error)``: when the stress update of an iterate (a Newton iterate or a line
  search's trial) raises :class:`InvertedElement` or :class:`ReturnMapFailure`,
  before the solver handles it; ``model.u`` still holds that iterate (a line search then goes back);
* ``correction(newton, it)``: after the linear solve of correction ``it``, before the line search
  (``model.du`` holds the correction, ``b`` = -R at ``model.u``); it may look along du with
  :meth:`Newton.along`, which leaves the iteration as it was;
* ``solved(newton, ok, its, reason)``: when :meth:`Newton.solve` returns, with what it returns.

It watches and must not change the model. Without a monitor (the default) nothing is called.
"""
from __future__ import annotations

import logging

import numpy as np
from dolfinx import fem
from mpi4py import MPI
from petsc4py import PETSc

from .. import compat
from ..mechanics.model import InvertedElement, Model, ReturnMapFailure
from . import failures, krylov, linear
from .linesearch import LineSearches
from .settings import NewtonSettings
from .timer import Timer

__all__ = ["Newton", "NewtonSettings", "Timer"]

log = logging.getLogger("comove")


class Newton(LineSearches):
    """Newton-Raphson on ``model.u`` with an exact Jacobian and a direct solver (MUMPS unless the
    PETSc options under the prefix ``comove_`` choose another solver)."""

    def __init__(self, model: Model, settings: NewtonSettings | None = None,
                 timer: Timer | None = None):
        self.model = model
        self.settings = settings or NewtonSettings()
        self.settings.check()              # (its fields may have been changed since it was made)
        self.timer = timer or Timer()
        self.b = compat.create_vector(model.residual_form)
        self.linear_solver = krylov.chosen(self.settings.linear_solver, model.num_dofs(),
                                           model.V.dofmap.index_map_bs)
        self.ksp, self.A, self.petsc_options = linear.make_solver(
            model.comm, model.jacobian_form,
            krylov.options_for(self.linear_solver, self.settings.petsc_options or {}))
        self.iterative = not linear.is_direct(self.ksp)   # multigrid: the rigid motions at each tangent
        self.krylov_its: list[int] = []    # Krylov iterations of each linear solve of the last solve()
        self.linear_solves = self.krylov_total = 0     # over the Newton's life (benchmarks, summaries)
        self.inexact_solves = 0           # Krylov solves stopped at their limit, taken as inexact steps
        ls = self.settings.line_search
        if ls is None:       # friction: the energy search stops in the stick band (theory.md 7.1)
            contacts = [item for item in model.items if item.kind == "contact"]
            ls = ("energy" if any(getattr(c, "mu", 0.0) > 0 for c in contacts) else True) if contacts else False
        self.line_search = {True: "residual", False: None, "none": None}.get(ls, ls)
        if self.settings.scale == "force":     # every residual assembles these two: compiled here,
            _ = model.internal_force_form, model.items_form     # not in the first increment
        # the iterate, the correction and their PETSc vectors (views of the same memory, for the life
        # of the model's Functions)
        self._u, self._du = model.u.x.array, model.du.x.array
        self._u_vec, self._du_vec = compat.petsc_vec(model.u), compat.petsc_vec(model.du)
        self._b_old = self.b.duplicate()
        self._f = self.b.duplicate()
        self._w = self.b.duplicate()          # scratch: the constraint gap g - u
        self._last_trial = None               # (alpha, ||R||) of the line search's last trial
        self.factorised = False            # the KSP holds the LU factors of a tangent
        self.workspace = None              # ICNTL(14) (per cent) once MUMPS's workspace was raised
        self._linear_cause = failures.LINEAR   # of the last linear solve's failure
        self.hopeless = False              # the last linear solve failed in a way that no smaller
                                           # increment cures (linear.HOPELESS_CODES)
        self.residual_scale = 0.0
        self.force_level = 0.0             # the largest force the run has met (F_run: the cap of atol)
        self.history: list[tuple[float, float]] = []
        self.poll = None                   # called by every rank before each iteration (a job's
                                           # collective check for Ctrl-C and SIGTERM: parallel.py)
        self.failure: failures.Failure | None = None     # of the last solve, None if it converged
        self.contacts = [item for item in model.items if item.kind == "contact"]   # the model's contact items
        self._X = None                     # the dofs' reference coordinates (contact sets)
        self._residuals: list[float] = []
        self._sets: list = []

    def residual(self, again: bool = False) -> float:
        """Assemble -R (with the Dirichlet rows set to the constraint violation) into b; its norm.
        ``again``: the stress is evaluated without first comparing u with the iterate the state holds
        (for a caller that has just set a new iterate: Model.evaluate_stress)."""
        m, b = self.model, self.b
        with self.timer("stress update"):
            try:
                m.evaluate_stress(again)
            except (InvertedElement, ReturnMapFailure) as err:
                self._notify("rejected", err)
                raise
        with self.timer("assembly"):
            x = self._u_vec
            lift = compat.constraint_gap(self._w, m.bcs, x) > 0.0     # else the lifting adds 0
            if self.settings.scale == "force":    # F_int on its own, the items' terms added
                compat.assemble_vector(self._f, m.internal_force_form)
                compat.assemble_vector(b, m.items_form, m.jacobian_form, m.bcs, x,
                                       add=m.nodal_loads(), lift=lift, plus=self._f)
            else:
                compat.assemble_vector(b, m.residual_form, m.jacobian_form, m.bcs, x,
                                       add=m.nodal_loads(), lift=lift)
            b.scale(-1.0)
        return b.norm()

    def _solve(self, rhs: PETSc.Vec, x) -> str | None:
        """Solve K x = rhs with the KSP's operator into the Function x; None, or why it failed (the
        same on every rank: an error raised on one rank's part of the solve becomes every rank's
        failure). A MUMPS factorisation that ran out of workspace is done again with more
        (linear.grow_workspace), which then stays for the run (``workspace``)."""
        failure, grown = linear.solve(self.ksp, self.petsc_options, rhs, compat.petsc_vec(x),
                                      self.model.comm)
        for pct in grown:                     # MUMPS ran out of workspace and was given more
            log.info("    MUMPS's workspace was too small: ICNTL(14) raised to %d %%", pct)
        if grown:
            self.workspace = grown[-1]
        self.hopeless = False
        self.krylov_its.append(krylov.iterations(self.ksp))
        self.linear_solves += 1
        self.krylov_total += self.krylov_its[-1]
        self._linear_cause = failures.LINEAR
        if failure is None:
            reason = self.ksp.getConvergedReason()
            rel = krylov.inexact(self.ksp, rhs) if reason < 0 and self.iterative else None
            if rel is not None:
                self.inexact_solves += 1
                log.info("    the Krylov solve stopped at %d iterations with its residual down to %.1e: "
                         "taken as an inexact Newton step", self.krylov_its[-1], rel)
            elif reason < 0 and self.iterative:
                failure, self._linear_cause = krylov.not_converged(self.ksp, rhs), failures.KRYLOV
            elif reason < 0:
                why = linear.factor_error(self.ksp)
                failure = f"the linear solver failed (PETSc KSP reason {reason}{'; ' + why if why else ''})"
                self.hopeless = linear.mumps_code(self.ksp) in linear.HOPELESS_CODES
        if failure is None:
            x.x.scatter_forward()
        return failure

    def _solve_linear(self) -> str | None:
        """Solve J du = -R into model.du; None, or why it failed."""
        failure = self._solve(self.b, self.model.du)
        if failure is not None:
            self.factorised = False
            return f"linear solve: {failure}"
        return None

    def force_scale(self) -> float:
        """||F_int|| at the current iterate (stress of the last residual evaluation): the forces
        the body carries, reactions and contact forces included."""
        f = self._f
        compat.assemble_vector(f, self.model.internal_force_form)
        return f.norm()

    def _notify(self, event: str, *args) -> None:
        """Call the monitor's method ``event`` (if there is a monitor and it has one)."""
        method = getattr(self.settings.monitor, event, None)
        if method is not None:
            method(self, *args)

    def _converged(self, rnorm: float, it: int) -> bool:
        """The residual test of the iterate after ``it`` corrections; with scale "force" against
        ||F_int|| of the current iterate."""
        s = self.settings
        self._notify("iteration", it, rnorm)
        if s.scale == "force":                  # F_int of the residual just evaluated
            self.residual_scale = self._f.norm()
            self.force_level = max(self.force_level, self.residual_scale)
        return bool(np.isfinite(rnorm)) and rnorm <= self.tolerance

    def solve(self) -> tuple[bool, int, str]:
        """Iterate from the current ``model.u``; returns (converged, iterations, reason), also to
        the settings' monitor."""
        self.hopeless = False
        ok, its, reason = self._iterate()
        self._notify("solved", ok, its, reason)
        return ok, its, reason

    def _fail(self, cause: str, its: int, reason: str) -> tuple[bool, int, str]:
        """Record the failed attempt (``failure``: its cause, the residuals of its iterates, how
        often the contact set changed) and return what :meth:`solve` returns."""
        self.failure = failures.Failure(cause, reason, list(self._residuals), self._set_changes(),
                                        self.settings.max_it)
        return False, its, reason

    def _contact_set(self) -> bytes | None:
        """The contact boundaries' nodes with a negative gap at the current iterate (this rank's
        nodes, as bytes of a boolean mask), or None without contact. Local, no collective call."""
        if not self.contacts:
            return None
        dim = self.model.V.dofmap.index_map_bs
        if self._X is None:
            self._X = self.model.V.tabulate_dof_coordinates()[:, :dim]
        xu = self.model.u.x.array.reshape(-1, dim)
        parts = []
        for item in self.contacts:
            nodes = item.nodes
            g = item.obstacle.gap_np(self._X[nodes] + xu[nodes], item.obstacle.displacement(item.factor))
            parts.append(np.asarray(g) < 0.0)
        return np.concatenate(parts).tobytes() if parts else b""

    def _set_changes(self) -> int:
        """In how many of the last failures.WINDOW iterations the contact set changed on any rank
        (collective; 0 without contact)."""
        if not self.contacts:
            return 0
        sets = self._sets[-(failures.WINDOW + 1):]
        changed = np.array([int(a != b) for a, b in zip(sets, sets[1:])] +
                           [0] * (failures.WINDOW - max(len(sets) - 1, 0)), dtype=np.int32)
        self.model.comm.Allreduce(MPI.IN_PLACE, changed, op=MPI.MAX)
        return int(changed.sum())

    def _out_of_range(self, r0: float) -> tuple[str, int, str] | None:
        """(cause, iterations, reason) of a first residual whose norm overflows (or underflows to 0)
        from finite entries that are not all 0: forces beyond the range of double precision, which
        no smaller increment brings back (``hopeless``); else None. Entries that are not finite are
        an iterate led astray (a predictor's): the iteration fails as it always did (a correction
        that is not finite), and a retry or a smaller increment may cure it."""
        largest = self.b.norm(PETSc.NormType.NORM_INFINITY)
        if r0 == 0.0 and largest == 0.0:
            return None                        # in equilibrium as it stands
        if np.isfinite(largest):
            self.hopeless = True
            return (failures.DIVERGED, 0, f"the residual's norm is {r0:g} for a largest entry of {largest:.3g}: "
                    "the forces are beyond the range of double precision's squares (1e-154 to 1e154); "
                    "state the problem in other units (E and the loads nearer 1)")
        return None

    def _iterate(self) -> tuple[bool, int, str]:
        m, s = self.model, self.settings
        self.history = []
        self.failure = None
        self.krylov_its = []
        self._residuals, self._sets = [], []
        try:
            r0 = rnorm = self.residual()
        except (InvertedElement, ReturnMapFailure) as err:
            return self._fail(failures.INADMISSIBLE, 0, str(err))
        self._residuals.append(r0)
        if not np.isfinite(r0) or r0 == 0.0:          # (0: nothing to do, or an underflow)
            why = self._out_of_range(r0)
            if why is not None:
                return self._fail(*why)
        if self.contacts:
            self._sets.append(self._contact_set())
        self.force_level = max(self.force_level, r0)
        if s.scale == "initial":
            self.residual_scale = max(self.residual_scale, r0)
        for it in range(1, s.max_it + 1):
            if self.poll is not None:
                self.poll()
            if self._converged(rnorm, it - 1):
                return True, it - 1, "converged"
            with self.timer("jacobian"):
                m.assemble_jacobian(self.A)
                if self.iterative:
                    krylov.set_near_nullspace(m.V, self.A, self._u)
            self.u_factorised = self._u.copy()        # a checkpoint rebuilds this tangent
            with self.timer("solve"):
                failure = self._solve_linear()
            if failure is not None:
                return self._fail(self._linear_cause, it, failure)
            self.factorised = True
            dnorm = self._du_vec.norm()
            if not np.isfinite(dnorm):
                return self._fail(failures.LINEAR, it, "the Newton correction is not finite (singular tangent?)")
            self._notify("correction", it)
            if self.line_search == "energy":
                self.b.copy(self._b_old)
                rnorm, alpha, err = self._energy_search(rnorm)
            else:
                rnorm, alpha, err = self._line_search(rnorm, armijo=it > s.free_its)
            if err is not None:
                return self._fail(failures.INADMISSIBLE, it, str(err))
            if alpha < 1.0:
                log.info("    Newton %2d: step scaled by %g", it, alpha)
            self.history.append((rnorm, dnorm))
            self._residuals.append(rnorm)
            if self.contacts:
                self._sets.append(self._contact_set())
            log.info("    Newton %2d: |R| = %.3e (rel %.1e), |du| = %.3e", it, rnorm,
                     rnorm / max(self.residual_scale, 1e-300), dnorm)
            if not np.isfinite(rnorm) or rnorm > s.divergence * max(r0, s.atol):
                return self._fail(failures.DIVERGED, it, f"diverged (|R| = {rnorm:.3e})")
            if alpha == 1.0 and dnorm <= s.stol * self._u_vec.norm():
                return True, it, "converged"
        converged = self._converged(rnorm, s.max_it)
        if converged:
            return True, s.max_it, "converged"
        return self._fail(failures.MAX_IT, s.max_it, f"no convergence in {s.max_it} iterations")

    @property
    def tolerance(self) -> float:
        """The residual norm the last solve had to reach: rtol times its scale plus atol, atol at
        most rtol times the largest force the run has met (the module docstring)."""
        s = self.settings
        return s.rtol * self.residual_scale + min(s.atol, s.rtol * self.force_level)

    def along(self, steps, look=None) -> list[tuple]:
        """(a, s(a), f(a), seen) for each step a along the current correction du: s(a) = du . R(u +
        a du), the line searches' function, f(a) = du . F_int(u + a du), its internal force's part
        (the rest is the items' terms), and what ``look(model)`` returns there (None without it).
        A step whose stress update is inadmissible gives NaN and None (and the monitor hears of it
        as ``rejected``). Afterwards u, the state and b (= -R) are those of the iterate again,
        evaluated anew from the same data: the iteration goes on as it would have. Its evaluations
        count in the Timer (stress update, assembly). docs/performance.md, the line search's
        trials."""
        m = self.model
        u0 = m.u.x.array.copy()
        du = compat.petsc_vec(m.du)
        out = []
        try:
            for a in steps:
                m.u.x.array[:] = u0 + a * m.du.x.array
                try:
                    self.residual()
                except (InvertedElement, ReturnMapFailure):
                    out.append((float(a), np.nan, np.nan, None))
                    continue
                if self.settings.scale != "force":        # else the residual assembled F_int
                    compat.assemble_vector(self._f, m.internal_force_form)
                out.append((float(a), -self.b.dot(du), self._f.dot(du),
                            look(m) if look is not None else None))
        finally:
            m.u.x.array[:] = u0
            self.residual()
        return out

    def load_terms(self, out: PETSc.Vec) -> None:
        """-(R - F_int) at the current iterate and load factor into ``out``: the items' terms and
        nodal loads, with the constraint rows g - u and the lifting of g - u (with the Jacobian of
        the state last evaluated). The internal force depends on u alone, so differences of these
        in the load factor at a fixed u are those of the residual, without evaluating the stress
        or assembling F_int."""
        m = self.model
        x = compat.petsc_vec(m.u)
        lift = compat.constraint_gap(self._w, m.bcs, x) > 0.0
        compat.assemble_vector(out, m.items_form, m.jacobian_form, m.bcs, x,
                               add=m.nodal_loads(), lift=lift)
        out.scale(-1.0)

    def load_rate(self, t: float, rate: fem.Function, eps: float) -> bool:
        """The path's tangent at the current state and load factor t into ``rate``: K v = -dR/dt with
        the last factorised tangent K and dR/dt = (R(t + eps) - R(t)) / eps, of the load terms alone
        (:meth:`load_terms`: F_int cancels); False (rate untouched) before any factorisation or if
        the rate is not finite."""
        if not self.factorised:
            return False
        m = self.model
        rhs = self._b_old
        with self.timer("predictor"):
            m.set_load(t + eps)
            self.load_terms(rhs)
            m.set_load(t)
            self.load_terms(self.b)
            rhs.axpy(-1.0, self.b)          # -(R(t + eps) - R(t))
            rhs.scale(1.0 / eps)
            if self._solve(rhs, rate) is not None:
                return False
        return bool(m.comm.allreduce(bool(np.all(np.isfinite(rate.x.array))), op=MPI.LAND))

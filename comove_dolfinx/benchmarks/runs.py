"""What the benchmarks measure with: a scene's short run, the linear-elastic floor of an iteration, a
factorisation of the tangent with another linear solver, and the small helpers they share.

CPU times are ``time.process_time`` summed over the ranks; wall times the largest over the ranks.
"""
from __future__ import annotations

import dataclasses
import pathlib
import time

import numpy as np
from mpi4py import MPI

from .. import compat
from ..io.csv_tables import write_table
from ..mechanics.model import Model
from ..presets import get_scene
from ..solver import IncrementalSolver, Timer
from ..solver.linear import make_solver, pushed
from ..solver.newton import Newton

COMM = MPI.COMM_WORLD
RING_SIZES = (0.22, 0.115, 0.058, 0.0365)          # about 1.4k, 5k, 20k and 50k dofs


def cpu() -> float:
    """CPU seconds of this process, summed over the ranks by the caller."""
    return time.process_time()


def stats(values) -> tuple[float, float]:
    """(median, max - min)."""
    v = np.asarray(values, dtype=float)
    return float(np.median(v)), float(v.max() - v.min())


def write_csv(path: pathlib.Path, rows: list[dict], append: bool = False) -> None:
    """``rows`` as CSV, written by rank 0."""
    if COMM.rank == 0:
        write_table(path, rows, append=append)


def say(text: str) -> None:
    """A line on rank 0's standard output, flushed."""
    if COMM.rank == 0:
        print(text, flush=True)


def build(name: str, size: float, overrides=()) -> tuple:
    """(scene, finalized model) of a scene at a mesh size (and other parameters, "key=value")."""
    scene = get_scene(name, [f"size={size}", *overrides])
    body, items, _ = scene.build(scene.mesh_data(COMM))
    model = Model(body, items)
    model.finalize()
    return scene, model


def _count_residuals(newton: Newton, calls: dict) -> None:
    """Count Newton's residual evaluations in ``calls["residual"]``."""
    residual = newton.residual

    def counted(*args, **kwargs):
        calls["residual"] += 1
        return residual(*args, **kwargs)
    newton.residual = counted


def short_run(name: str, size: float, increments: int, options: dict | None = None,
              count: bool = False, between=None, overrides=(), monitor=None,
              linear_solver: str = "mumps") -> dict:
    """The scene's first ``increments`` nominal increments (its own predictor and Newton settings,
    the linear solver's ``options``): CPU and wall time of the run (max over ranks for wall, sum
    for CPU), iterations (failed ones included), residual evaluations, the Timer's split.
    ``between``: called after every converged increment, its CPU time taken out of the run's.
    ``overrides``: scene parameters, "key=value" (the predictor, ...); ``monitor``: Newton's
    (solver/newton.py); ``linear_solver``: NewtonSettings.linear_solver (the options come after it)."""
    scene, model = build(name, size, overrides)
    settings = dataclasses.replace(scene.newton_settings(), petsc_options=dict(options or {}),
                                   monitor=monitor, linear_solver=linear_solver)
    steps = dataclasses.replace(scene.steps()[0].settings(), n_increments=increments,
                                t_end=increments / scene.n_increments)
    return timed_run(model, settings, steps, count, between)


def timed_run(model: Model, settings, steps, count: bool = False, between=None) -> dict:
    """:func:`short_run`'s figures of a finalized ``model`` run with the Newton ``settings`` over
    the increments ``steps`` (a StepSettings)."""
    timer = Timer(time.process_time)
    newton = Newton(model, settings, timer)
    calls = {"residual": 0}
    if count:
        _count_residuals(newton, calls)
    solver = IncrementalSolver(model, steps, newton)
    aside = [0.0]

    def hook(model, inc):
        c = cpu()
        between(model)
        aside[0] += cpu() - c
    COMM.barrier()
    w0, c0 = time.perf_counter(), cpu()
    res = solver.run([hook] if between else ())
    run_cpu, wall = cpu() - c0 - aside[0], time.perf_counter() - w0
    its = sum(i.newton_its + i.failed_its for i in res.increments)
    return {"dofs": model.num_dofs(), "iterations": its, "increments": len(res.increments),
            "completed_to": res.increments[-1].load if res.increments else 0.0,
            "cpu": COMM.allreduce(run_cpu, op=MPI.SUM), "wall": COMM.allreduce(wall, op=MPI.MAX),
            "residuals": calls["residual"], "timer": dict(timer.totals), "model": model,
            "newton": newton}


class ElasticFloor:
    """One 'iteration' of linear elasticity on a model's mesh, space, quadrature and supports:
    stiffness matrix, residual (with the lifting Newton does) and a MUMPS factorisation and solve;
    the symbolic analysis done once at construction, as Newton does it once. ``sample()`` times
    one, the CPU seconds of (matrix, vector, factorisation + solve) summed over the ranks."""

    def __init__(self, model: Model):
        import ufl
        from dolfinx import fem
        self.model = model
        u, v = ufl.TrialFunction(model.V), ufl.TestFunction(model.V)
        self.w = fem.Function(model.V)
        E, nu = model.elastic.E, model.elastic.nu
        lam, mu = E * nu / ((1 + nu) * (1 - 2 * nu)), E / (2 * (1 + nu))

        def sigma(d):
            eps = ufl.sym(ufl.grad(d))
            return lam * ufl.tr(eps) * ufl.Identity(2) + 2 * mu * eps
        self.a = compat.form(ufl.inner(sigma(u), ufl.sym(ufl.grad(v))) * model.rule.dx)
        self.L = compat.form(ufl.inner(sigma(self.w), ufl.sym(ufl.grad(v))) * model.rule.dx)
        self.ksp, self.A, self.options = make_solver(model.comm, self.a, {})   # Newton's solver
        self.b = compat.create_vector(self.L)
        self.x = self.b.duplicate()
        self.rng = np.random.default_rng(0)
        self.sample()                                   # the symbolic analysis, not counted

    def sample(self) -> tuple[float, float, float]:
        """CPU seconds (summed over the ranks) of the matrix, the vector, and the factorisation and
        solve, for a new random field ``w``."""
        m = self.model
        self.w.x.array[:] = 1e-3 * self.rng.standard_normal(self.w.x.array.size)
        m.comm.barrier()
        c0 = cpu()
        compat.assemble_matrix(self.A, self.a, m.bcs)
        c1 = cpu()
        compat.assemble_vector(self.b, self.L, self.a, m.bcs, compat.petsc_vec(self.w))
        c2 = cpu()
        with pushed(self.options):
            self.ksp.solve(self.b, self.x)
        times = (c1 - c0, c2 - c1, cpu() - c2)
        return tuple(m.comm.allreduce(float(t), op=MPI.SUM) for t in times)

    def destroy(self) -> None:
        """Free the PETSc objects."""
        for obj in (self.ksp, self.A, self.b, self.x):
            obj.destroy()


def factor_solve(newton: Newton, options: dict, repeats: int) -> list[float]:
    """CPU seconds of one factorisation and solve of the Newton's current tangent with another
    linear solver (symbolic set-up at a first, untimed solve); one per repeat."""
    m = newton.model
    ksp, A, options = make_solver(m.comm, m.jacobian_form, options)   # the matrix type it takes
    x = newton.b.duplicate()
    out = []
    for k in range(repeats + 1):
        m.assemble_jacobian(A)   # a new state: a new factorisation
        m.comm.barrier()
        c0 = cpu()
        with pushed(options):
            ksp.solve(newton.b, x)
        reason = ksp.getConvergedReason()
        if k:
            out.append(cpu() - c0 if reason > 0 else np.nan)
    ksp.destroy()
    A.destroy()
    x.destroy()
    return [m.comm.allreduce(t, op=MPI.SUM) for t in out]

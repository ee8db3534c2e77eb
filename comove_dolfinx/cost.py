"""What a Newton iteration costs, against what it cannot cost less than; solvers; ranks. Writes CSV
files and charts, never asserts (docs/performance.md).

    python -m comove_dolfinx.cost floor   --out results/cost   # ring: iteration vs linear-elastic floor
    python -m comove_dolfinx.cost solvers --out results/cost   # ring: direct solvers, orderings, GAMG
    mpirun -n 2 python -m comove_dolfinx.cost scale --out results/cost   # ring, plate: 1 or 2 ranks
    python -m comove_dolfinx.cost slopes  --out results/cost   # ring: the residual along du
    python -m comove_dolfinx.cost parts   --out results/cost   # ring: each part, alone and in the loop

floor: per ring size, the CPU time of one Newton iteration of the real run (the scene's first
``--increments`` nominal increments, predictor, line searches, cut-backs and failed iterations
included: run time / all iterations) against the floor on the same mesh and degree: assembling a
linear-elastic stiffness matrix and residual (with the same lifting of the Dirichlet rows) and one
MUMPS factorisation and solve (symbolic analysis done once, as in Newton), sampled after every
increment of the run (its time taken out of the run's); the ratio is the median over the runs of
the run's time per iteration over the mean of its floor samples. Also the run's residual evaluations per iteration
and its Timer split; a cProfile listing of the largest size.
solvers: per ring size and solver configuration (PETSc options under ``comove_``), the CPU time of one
factorisation and solve of the real tangent, and of the short run.
scale: per scene, size and number of ranks (run once serial, once under mpirun, rows appended),
wall and CPU time (summed over ranks) per Newton iteration of a short run, MUMPS against GAMG.
slopes: why the line search spends trials. In the ring's run (``--sizes``, default 0.058, about 18k
dofs), at the first four corrections past the load factor 0.2 (delta = 1.32) whose full step
overshoots (``s(1) > 0.5 |s(0)|``, ``s(a) = du . R(u + a du)``), the secant slope ``(s(a) - s(0)) / (a |s(0)|)``
at steps a from 1e-5 to 1, and its internal force's part: 1 as a -> 0 for an exact tangent, and it
stays near 1 where the residual is smooth along du; with the quadrature points that yield at the
iterate and unload at the step, and those that start to yield there. The run goes on as without
the probe.

parts: the residual and its stress evaluation, the Jacobian and the floor's matrix and residual,
and two calls that do nearly nothing (a NumPy sum of 16 values, a PETSc vector norm), at the ring's
state after ``--increments`` (6) increments, each timed back to back, right after a factorisation
and solve of the tangent (where a Newton iteration meets them) and after 4 ms of the interpreter
alone: what a part costs in the loop beyond its own work (wall time, one rank).

CPU time is ``time.process_time`` (the process's, not the machine's); every figure is the median of
``--repeats`` runs with its spread (max - min) beside it. Other processes on the machine lengthen
wall times, and CPU times much less.
"""
from __future__ import annotations

import argparse
import cProfile
import dataclasses
import io
import logging
import pathlib
import pstats
import time

import numpy as np
from mpi4py import MPI

from . import compat
from .mechanics.model import Model
from .presets import SceneError, get_scene
from .solver import IncrementalSolver, Timer
from .solver import linear
from .solver.linear import make_solver, pushed
from .solver.newton import Newton
from .io.csv_tables import read_table, write_table

COMM = MPI.COMM_WORLD
RING_SIZES = (0.22, 0.115, 0.058, 0.0365)          # about 1.4k, 5k, 20k and 50k dofs
ITERATIVE = {"ksp_type": "gmres", "pc_type": "gamg", "ksp_rtol": 1e-10, "ksp_max_it": 1000,
             "ksp_gmres_restart": 100}
SOLVERS = {
    "mumps_auto": {},
    "mumps_amd": {"mat_mumps_icntl_7": 0},
    "mumps_amf": {"mat_mumps_icntl_7": 2},
    "mumps_scotch": {"mat_mumps_icntl_7": 3},
    "mumps_pord": {"mat_mumps_icntl_7": 4},
    "mumps_metis": {"mat_mumps_icntl_7": 5},
    "mumps_qamd": {"mat_mumps_icntl_7": 6},
    "mumps_scaled": {"mat_mumps_icntl_8": 77},        # MUMPS's own default: a scaling computed at
                                                      # every factorisation (linear.MUMPS_DEFAULTS)
    "petsc_nd": {"pc_factor_mat_solver_type": "petsc", "pc_factor_mat_ordering_type": "nd"},
    "umfpack": {"pc_factor_mat_solver_type": "umfpack"},
    "superlu_dist": {"pc_factor_mat_solver_type": "superlu_dist"},
    "gmres_gamg": ITERATIVE,
    "gmres_gamg_loose": {**ITERATIVE, "ksp_rtol": 1e-6},     # inexact Newton
}
SCALE = {"ring": (0.0365, 0.0175), "plate": (0.059, 0.029)}     # about 50k and 190k dofs


# ------------------------------------------------------------------------------------------------
# helpers
# ------------------------------------------------------------------------------------------------
def _cpu() -> float:
    """CPU seconds of this process, summed over the ranks by the caller."""
    return time.process_time()


def _stats(values) -> tuple[float, float]:
    """(median, max - min)."""
    v = np.asarray(values, dtype=float)
    return float(np.median(v)), float(v.max() - v.min())


def _write_csv(path: pathlib.Path, rows: list[dict], append: bool = False) -> None:
    if COMM.rank == 0:
        write_table(path, rows, append=append)


def build(name: str, size: float, overrides=()) -> tuple:
    """(scene, finalized model) of a scene at a mesh size (and other parameters, "key=value")."""
    scene = get_scene(name, [f"size={size}", *overrides])
    body, items, _ = scene.build(scene.mesh_data(COMM))
    model = Model(body, items)
    model.finalize()
    return scene, model


def short_run(name: str, size: float, increments: int, options: dict | None = None,
              count: bool = False, between=None, overrides=(), monitor=None) -> dict:
    """The scene's first ``increments`` nominal increments (its own predictor and Newton settings,
    the linear solver's ``options``): CPU and wall time of the run (max over ranks for wall, sum
    for CPU), iterations (failed ones included), residual evaluations, the Timer's split.
    ``between``: called after every converged increment, its CPU time taken out of the run's.
    ``overrides``: scene parameters, "key=value" (the predictor, ...); ``monitor``: Newton's
    (solver/newton.py)."""
    scene, model = build(name, size, overrides)
    settings = dataclasses.replace(scene.newton_settings(), petsc_options=dict(options or {}),
                                   monitor=monitor)
    steps = dataclasses.replace(scene.steps()[0].settings(), n_steps=increments,
                                t_end=increments / scene.n_steps)
    timer = Timer(time.process_time)
    newton = Newton(model, settings, timer)
    calls = {"residual": 0}
    if count:
        residual = newton.residual

        def counted(*args, **kwargs):
            calls["residual"] += 1
            return residual(*args, **kwargs)
        newton.residual = counted
    solver = IncrementalSolver(model, steps, newton)
    aside = [0.0]

    def hook(model, inc):
        c = _cpu()
        between(model)
        aside[0] += _cpu() - c
    COMM.barrier()
    w0, c0 = time.perf_counter(), _cpu()
    res = solver.run([hook] if between else ())
    cpu, wall = _cpu() - c0 - aside[0], time.perf_counter() - w0
    its = sum(i.newton_its + i.failed_its for i in res.increments)
    return {"dofs": model.num_dofs(), "iterations": its, "increments": len(res.increments),
            "completed_to": res.increments[-1].load if res.increments else 0.0,
            "cpu": COMM.allreduce(cpu, op=MPI.SUM), "wall": COMM.allreduce(wall, op=MPI.MAX),
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
        m = self.model
        self.w.x.array[:] = 1e-3 * self.rng.standard_normal(self.w.x.array.size)
        m.comm.barrier()
        c0 = _cpu()
        compat.assemble_matrix(self.A, self.a, m.bcs)
        c1 = _cpu()
        compat.assemble_vector(self.b, self.L, self.a, m.bcs, compat.petsc_vec(self.w))
        c2 = _cpu()
        with pushed(self.options):
            self.ksp.solve(self.b, self.x)
        times = (c1 - c0, c2 - c1, _cpu() - c2)
        return tuple(m.comm.allreduce(float(t), op=MPI.SUM) for t in times)

    def destroy(self) -> None:
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
        compat.assemble_matrix(A, m.jacobian_form, m.bcs)   # a new state: a new factorisation
        m.comm.barrier()
        c0 = _cpu()
        with pushed(options):
            ksp.solve(newton.b, x)
        reason = ksp.getConvergedReason()
        if k:
            out.append(_cpu() - c0 if reason > 0 else np.nan)
    ksp.destroy()
    A.destroy()
    x.destroy()
    return [m.comm.allreduce(t, op=MPI.SUM) for t in out]


def _chart(path, series: dict, xlabel: str, ylabel: str, title: str, logy=True) -> None:
    """One line per series: {label: (x, y, spread)}."""
    if COMM.rank != 0:
        return
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(6.4, 4.2))
    colours = plt.get_cmap("tab20").colors            # more series than the default ten colours
    for k, (label, (x, y, err)) in enumerate(series.items()):
        ax.errorbar(x, y, yerr=np.asarray(err) / 2, marker="osD^v<>"[k % 7], capsize=3, label=label,
                    color=colours[(2 * k) % 20 if k < 10 else (2 * k + 1) % 20])
    ax.set_xscale("log")
    if logy:
        ax.set_yscale("log")
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.set_title(title, fontsize=10)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def _say(text: str) -> None:
    if COMM.rank == 0:
        print(text, flush=True)


# ------------------------------------------------------------------------------------------------
# the studies
# ------------------------------------------------------------------------------------------------
def floor(out: pathlib.Path, sizes=RING_SIZES, repeats: int = 3, increments: int = 4,
          overrides=()) -> list[dict]:
    rows = []
    for size in sizes:
        # each run samples the floor on its own mesh after every increment, and its ratio is taken
        # against the mean of those samples: the floor is measured in the same minutes as the run,
        # so the machine's speed drifting (other virtual machines on the host: up to 2x within a
        # minute here) enters both alike
        runs, floors = [], []
        for _ in range(repeats):
            samples, holder = [], {}

            def sample(model):
                if "floor" not in holder:
                    holder["floor"] = ElasticFloor(model)
                samples.append(holder["floor"].sample())
            runs.append(short_run("ring", size, increments, count=True, between=sample,
                                  overrides=overrides))
            if not samples:                          # no increment converged: one after the run
                sample(runs[-1]["model"])
            holder["floor"].destroy()
            split = np.mean(samples, axis=0)
            floors.append((float(split.sum()), list(split)))
        per_it = [r["cpu"] / max(r["iterations"], 1) for r in runs]
        fl = [f[0] for f in floors]
        ratios = [a / b for a, b in zip(per_it, fl)]
        split = [float(np.median([f[1][k] for f in floors])) for k in range(3)]
        r = runs[-1]
        its = max(r["iterations"], 1)
        t = r["timer"]
        row = {"size": size, "dofs": r["dofs"], "iterations": r["iterations"],
               "increments": r["increments"], "residuals_per_it": round(r["residuals"] / its, 2)}
        row["iteration_cpu_s"], row["iteration_spread_s"] = _stats(per_it)
        row["floor_cpu_s"], row["floor_spread_s"] = _stats(fl)
        row["ratio"], row["ratio_spread"] = _stats(ratios)
        for k in ("solve", "jacobian", "assembly", "stress update", "force scale", "predictor"):
            row[f"{k.replace(' ', '_')}_s_per_it"] = t.get(k, 0.0) / its       # CPU, last run
        # the last run's CPU outside every timed part (its "output" is the floor's samples, which
        # its CPU leaves out): line searches, checks, commits, Python
        row["other_s_per_it"] = (r["cpu"] - sum(v for k, v in t.items() if k != "output")) / its
        for k, v in zip(("floor_matrix_s", "floor_vector_s", "floor_solve_s"), split):
            row[k] = v
        rows.append(row)
        _say(f"ring size {size}: {row['dofs']} dofs, {row['iterations']} its, iteration "
             f"{row['iteration_cpu_s'] * 1e3:.1f} ms (+-{row['iteration_spread_s'] * 5e2:.1f}), floor "
             f"{row['floor_cpu_s'] * 1e3:.1f} ms, ratio {row['ratio']:.2f} (+-{row['ratio_spread'] / 2:.2f}), "
             f"{row['residuals_per_it']} residuals/it")
    _write_csv(out / "floor.csv", rows)
    floor_chart(out / "floor.png", rows)
    if sizes:
        _profile(out, sizes[-1], increments, overrides)
    return rows


def floor_chart(path: pathlib.Path, rows: list[dict], goal: float = 1.3) -> None:
    """Two panels: CPU s per iteration and per floor iteration against dofs (absolute: they move
    with the host's speed between sizes), and their ratio (what the floor's pairing makes hold)
    with the goal."""
    if COMM.rank != 0:
        return
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    d = [int(r["dofs"]) for r in rows]

    def col(key):
        return np.array([float(r[key]) for r in rows])
    fig, (a, b) = plt.subplots(1, 2, figsize=(10, 4))
    a.errorbar(d, col("iteration_cpu_s"), yerr=col("iteration_spread_s") / 2, marker="o", capsize=3,
               label="Newton iteration (ring)")
    a.errorbar(d, col("floor_cpu_s"), yerr=col("floor_spread_s") / 2, marker="s", capsize=3,
               label="floor: elastic K, R, MUMPS")
    a.set_yscale("log")
    a.set_ylabel("CPU s per iteration")
    a.set_title("per iteration (moves with the host's speed)", fontsize=10)
    b.errorbar(d, col("ratio"), yerr=col("ratio_spread") / 2, marker="o", capsize=3, color="C3",
               label="iteration / floor (median of runs)")
    b.axhline(goal, color="0.3", ls="--", lw=1, label=f"goal {goal}")
    b.set_ylim(1.0, max(2.0, float(col("ratio").max()) + 0.2))
    b.set_ylabel("ratio")
    b.set_title("ratio, the floor sampled within each run", fontsize=10)
    for ax in (a, b):
        ax.set_xscale("log")
        ax.set_xlabel("dofs")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8)
    fig.suptitle("ring: one Newton iteration against the linear-elastic floor", fontsize=11)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def _profile(out: pathlib.Path, size: float, increments: int, overrides=()) -> None:
    """cProfile of the short ring run at one size, the 30 costliest functions (own time)."""
    prof = cProfile.Profile()
    prof.enable()
    short_run("ring", size, increments, overrides=overrides)
    prof.disable()
    if COMM.rank == 0:
        text = io.StringIO()
        pstats.Stats(prof, stream=text).sort_stats("tottime").print_stats(30)
        (out / f"profile_ring_{size}.txt").write_text(text.getvalue())


def solvers(out: pathlib.Path, sizes=RING_SIZES, repeats: int = 3, increments: int = 2,
            names=None, run_names=("mumps_auto", "mumps_metis", "mumps_amd", "mumps_scaled",
                                   "petsc_nd", "gmres_gamg")) -> list[dict]:
    """Factorisation + solve of the ring's tangent after ``increments`` increments, every solver;
    the short run itself with the solvers of ``run_names``."""
    names = list(names or SOLVERS)
    rows = []
    for size in sizes:
        base = short_run("ring", size, increments)
        for name in names:
            opts = SOLVERS[name]
            if COMM.size > 1 and name in ("petsc_nd", "umfpack"):
                continue                                     # sequential factorisations
            try:
                fs = factor_solve(base["newton"], opts, repeats)
            except Exception as err:                         # noqa: BLE001 - not in this PETSc
                _say(f"  {name}: not available ({str(err).splitlines()[0]})")
                continue
            row = {"size": size, "dofs": base["dofs"], "solver": name}
            row["factor_solve_cpu_s"], row["factor_solve_spread_s"] = _stats(fs)
            if name in run_names:
                runs = [short_run("ring", size, increments, opts) for _ in range(repeats)]
                row["run_cpu_s"], row["run_spread_s"] = _stats([r["cpu"] for r in runs])
                row["iterations"] = runs[-1]["iterations"]
            else:
                row.update(run_cpu_s=np.nan, run_spread_s=np.nan, iterations=np.nan)
            rows.append(row)
            _say(f"ring {row['dofs']} dofs, {name}: factor+solve {row['factor_solve_cpu_s'] * 1e3:.1f} ms"
                 f" (+-{row['factor_solve_spread_s'] * 5e2:.1f}), run {row['run_cpu_s']:.2f} s")
    _write_csv(out / "solvers.csv", rows)
    series = {}
    for name in names:
        sel = [r for r in rows if r["solver"] == name]
        if sel:
            series[name] = ([r["dofs"] for r in sel], [r["factor_solve_cpu_s"] for r in sel],
                            [r["factor_solve_spread_s"] for r in sel])
    _chart(out / "solvers.png", series, "dofs", "CPU s per factorisation + solve",
           "ring tangent: direct solvers and orderings, GMRES + GAMG")
    return rows


def scale(out: pathlib.Path, scenes=SCALE, repeats: int = 3, increments: int = 1,
          solver_names=("mumps_auto", "gmres_gamg")) -> list[dict]:
    """Short runs of each scene and size on the ranks this was started with; rows appended to
    scale.csv (run once serial, once under mpirun), the chart drawn from every row there."""
    rows = []
    for name, sizes in scenes.items():
        for size in sizes:
            for solver in solver_names:
                runs = [short_run(name, size, increments, SOLVERS[solver]) for _ in range(repeats)]
                its = [max(r["iterations"], 1) for r in runs]
                row = {"scene": name, "size": size, "dofs": runs[-1]["dofs"], "ranks": COMM.size,
                       "solver": solver, "iterations": runs[-1]["iterations"],
                       "completed_to": runs[-1]["completed_to"]}
                wall = [r["wall"] / i for r, i in zip(runs, its)]
                cpu = [r["cpu"] / i for r, i in zip(runs, its)]
                row["wall_per_it_s"], row["wall_spread_s"] = _stats(wall)
                row["cpu_per_it_s"], row["cpu_spread_s"] = _stats(cpu)
                rows.append(row)
                _say(f"{name} {row['dofs']} dofs, {COMM.size} rank(s), {solver}: {row['iterations']} its, "
                     f"wall {row['wall_per_it_s']:.3f} s/it (+-{row['wall_spread_s'] / 2:.3f}), "
                     f"CPU {row['cpu_per_it_s']:.3f} s/it")
    _write_csv(out / "scale.csv", rows, append=True)
    if COMM.rank == 0:
        every = read_table(out / "scale.csv")
        series = {}
        for r in every:
            key = f"{r['scene']} {r['solver']} {r['ranks']} rank(s)"
            x, y, e = series.setdefault(key, ([], [], []))
            x.append(int(r["dofs"]))
            y.append(float(r["wall_per_it_s"]))
            e.append(float(r["wall_spread_s"]))
        _chart(out / "scale.png", series, "dofs", "wall s per Newton iteration",
               "ring and plate: 1 and 2 ranks, MUMPS and GMRES + GAMG")
    return rows


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
            for a, slope, internal, unloading, loading in case["rows"]:
                rows.append({"size": size, "dofs": run["dofs"], "load": case["load"],
                             "iteration": case["iteration"], "s0": case["s0"], "step": a,
                             "slope": slope, "internal_slope": internal,
                             "items_slope": slope - internal, "yielding": case["yielding"],
                             "unloading": unloading, "newly_yielding": loading})
            _say(f"{label} ({case['yielding']} points yielding): " +
                 " ".join(f"{r[0]:g}:{r[1]:.3f} (-{r[3]} +{r[4]})" for r in case["rows"]))
        if not probe.cases:
            _say(f"ring size {size}: no correction overshot after the load factor {after}")
    _write_csv(out / "slopes.csv", rows)
    if series:
        _chart(out / "slopes.png", series, "step a along the correction du",
               "(s(a) - s(0)) / (a |s(0)|)", "ring: the residual along Newton's correction "
               "(1: the tangent's slope)", logy=False)
    return rows


def _idle(seconds: float) -> None:
    """The interpreter alone for ``seconds`` (a loop on the clock: no system call, no other code)."""
    end = time.perf_counter() + seconds
    while time.perf_counter() < end:
        pass


def parts(out: pathlib.Path, sizes=(0.22,), increments: int = 6, repeats: int = 40) -> list[dict]:
    """The parts of a Newton iteration, and the floor's, timed at the ring's state after
    ``increments`` increments in three conditions: back to back (the minimum over seven batches of
    ``repeats`` calls), each right after a Jacobian assembly, factorisation and solve (as a Newton
    iteration meets the residual) and each after 4 ms of the interpreter alone (medians of
    ``repeats``). Wall microseconds of one rank: parts.csv and parts.png."""
    rows = []
    for size in sizes:
        run = short_run("ring", size, increments)
        m, newton = run["model"], run["newton"]
        floor_it = ElasticFloor(m)
        du, w = compat.petsc_vec(m.du), compat.petsc_vec(floor_it.w)
        tiny = np.ones(16)
        cases = {
            "residual (stress evaluated again)": lambda: (m.evaluate_stress(again=True), newton.residual()),
            "stress evaluation": lambda: m.evaluate_stress(again=True),
            "residual without the stress": newton.residual,
            "Jacobian": lambda: compat.assemble_matrix(newton.A, m.jacobian_form, m.bcs),
            "floor: elastic matrix": lambda: compat.assemble_matrix(floor_it.A, floor_it.a, m.bcs),
            "floor: elastic residual": lambda: compat.assemble_vector(floor_it.b, floor_it.L, floor_it.a,
                                                                      m.bcs, w),
            "NumPy: sum of 16 values": tiny.sum,
            "PETSc: a vector's norm": newton.b.norm,
        }

        def factorise():
            compat.assemble_matrix(newton.A, m.jacobian_form, m.bcs)
            linear.solve(newton.ksp, newton.petsc_options, newton.b, du, m.comm)

        def timed(before, part):
            t = []
            for _ in range(repeats):
                before()
                t0 = time.perf_counter()
                part()
                t.append(time.perf_counter() - t0)
            return float(np.median(t))
        for name, part in cases.items():
            part()
            alone = []
            for _ in range(7):
                t0 = time.perf_counter()
                for _ in range(repeats):
                    part()
                alone.append((time.perf_counter() - t0) / repeats)
            row = {"size": size, "dofs": run["dofs"], "part": name, "alone_us": 1e6 * min(alone),
                   "after_factorisation_us": 1e6 * timed(factorise, part),
                   "after_idle_us": 1e6 * timed(lambda: _idle(4e-3), part)}
            rows.append(row)
            _say(f"ring size {size}, {name}: alone {row['alone_us']:.1f} us, after a factorisation "
                 f"{row['after_factorisation_us']:.1f} us, after 4 ms of the interpreter "
                 f"{row['after_idle_us']:.1f} us")
        floor_it.destroy()
    _write_csv(out / "parts.csv", rows)
    if COMM.rank == 0 and rows:
        _parts_chart(out / "parts.png", rows)
    return rows


def _parts_chart(path: pathlib.Path, rows: list[dict]) -> None:
    """Horizontal bars, one group per part of the first size: the three conditions."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    size = rows[0]["size"]
    rows = [r for r in rows if r["size"] == size]
    y = np.arange(len(rows))
    fig, ax = plt.subplots(figsize=(7.4, 4.4))
    for k, (key, label) in enumerate((("alone_us", "back to back"),
                                      ("after_factorisation_us", "after a factorisation and solve"),
                                      ("after_idle_us", "after 4 ms of the interpreter"))):
        ax.barh(y + (k - 1) * 0.27, [r[key] for r in rows], height=0.27, label=label)
    ax.set_yticks(y, [r["part"] for r in rows], fontsize=8)
    ax.invert_yaxis()
    ax.set_xscale("log")
    ax.set_xlabel("wall time of one call, microseconds")
    ax.set_title(f"ring, {rows[0]['dofs']} dofs: the parts of an iteration and when they run", fontsize=10)
    ax.grid(True, axis="x", which="both", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def main(argv=None) -> None:
    p = argparse.ArgumentParser(prog="python -m comove_dolfinx.cost", description=__doc__.split("\n")[0])
    p.add_argument("study", choices=("floor", "parts", "solvers", "scale", "slopes"))
    p.add_argument("--out", default="results/cost")
    p.add_argument("--repeats", type=int, default=None,
                   help="runs per figure (floor, solvers, scale: 3) or calls per timing (parts: 40)")
    p.add_argument("--increments", type=int, default=None, help="nominal increments of each short run")
    p.add_argument("--sizes", default=None, help="comma-separated mesh sizes (floor, solvers, slopes)")
    p.add_argument("--solvers", default=None, help="comma-separated configurations (solvers, scale)")
    p.add_argument("--scenes", default="ring,plate", help="comma-separated scenes (scale)")
    p.add_argument("--set", action="append", default=[], metavar="KEY=VALUE", dest="overrides",
                   help="a parameter of the ring scene for its runs (floor, slopes), e.g. predictor=linear")
    a = p.parse_args(argv)
    if a.overrides and a.study not in ("floor", "slopes"):
        p.error("--set applies to the floor and slopes studies only")
    if a.study == "parts" and COMM.size > 1:
        p.error("parts times one rank: run it without mpirun")
    try:
        get_scene("ring", a.overrides)
    except SceneError as err:
        p.error(str(err))
    logging.disable(logging.INFO)
    out = pathlib.Path(a.out)
    if COMM.rank == 0:
        out.mkdir(parents=True, exist_ok=True)
    COMM.barrier()
    kw = {"repeats": a.repeats} if a.repeats else {}
    if a.increments:
        kw["increments"] = a.increments
    if a.sizes and a.study != "scale":
        kw["sizes"] = tuple(float(s) for s in a.sizes.split(","))
    if a.study == "floor":
        floor(out, overrides=tuple(a.overrides), **kw)
    elif a.study == "parts":
        parts(out, **kw)
    elif a.study == "slopes":
        kw.pop("repeats", None)
        slopes(out, overrides=tuple(a.overrides), **kw)
    elif a.study == "solvers":
        solvers(out, names=a.solvers.split(",") if a.solvers else None, **kw)
    else:
        names = tuple(a.solvers.split(",")) if a.solvers else ("mumps_auto", "gmres_gamg")
        scale(out, scenes={k: SCALE[k] for k in a.scenes.split(",")}, solver_names=names, **kw)


if __name__ == "__main__":
    main()

"""solvers: the linear solver configurations on the ring's real tangent.

Per ring size and configuration (PETSc options under ``comove_``), the CPU time of one
factorisation and solve of the tangent after a few increments, and of the short run itself.
"""
from __future__ import annotations

import pathlib

import numpy as np

from .charts import lines
from .runs import COMM, RING_SIZES, factor_solve, say, short_run, stats, write_csv

ITERATIVE = {"ksp_type": "gmres", "pc_type": "gamg", "ksp_rtol": 1e-10, "ksp_max_it": 1000,
             "ksp_gmres_restart": 100}
#: the configurations by name: PETSc options of the Newton's linear solver (keys without the prefix)
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
RUN_NAMES = ("mumps_auto", "mumps_metis", "mumps_amd", "mumps_scaled", "petsc_nd", "gmres_gamg")


def _solver_row(size: float, base: dict, name: str, repeats: int, increments: int,
                run_names) -> dict | None:
    """The row of one configuration at one size (None where this PETSc lacks it): its
    factorisation and solve of ``base``'s tangent, and for ``run_names`` the short run with it."""
    opts = SOLVERS[name]
    try:
        fs = factor_solve(base["newton"], opts, repeats)
    except Exception as err:                         # noqa: BLE001 - not in this PETSc
        say(f"  {name}: not available ({str(err).splitlines()[0]})")
        return None
    row = {"size": size, "dofs": base["dofs"], "solver": name}
    row["factor_solve_cpu_s"], row["factor_solve_spread_s"] = stats(fs)
    if name in run_names:
        runs = [short_run("ring", size, increments, opts) for _ in range(repeats)]
        row["run_cpu_s"], row["run_spread_s"] = stats([r["cpu"] for r in runs])
        row["iterations"] = runs[-1]["iterations"]
    else:
        row.update(run_cpu_s=np.nan, run_spread_s=np.nan, iterations=np.nan)
    return row


def solvers(out: pathlib.Path, sizes=RING_SIZES, repeats: int = 3, increments: int = 2,
            names=None, run_names=RUN_NAMES) -> list[dict]:
    """Factorisation + solve of the ring's tangent after ``increments`` increments, every solver;
    the short run itself with the solvers of ``run_names``: solvers.csv and solvers.png."""
    names = list(names or SOLVERS)
    rows = []
    for size in sizes:
        base = short_run("ring", size, increments)
        for name in names:
            if COMM.size > 1 and name in ("petsc_nd", "umfpack"):
                continue                                     # sequential factorisations
            row = _solver_row(size, base, name, repeats, increments, run_names)
            if row is None:
                continue
            rows.append(row)
            say(f"ring {row['dofs']} dofs, {name}: factor+solve {row['factor_solve_cpu_s'] * 1e3:.1f} ms"
                f" (+-{row['factor_solve_spread_s'] * 5e2:.1f}), run {row['run_cpu_s']:.2f} s")
    write_csv(out / "solvers.csv", rows)
    series = {}
    for name in names:
        sel = [r for r in rows if r["solver"] == name]
        if sel:
            series[name] = ([r["dofs"] for r in sel], [r["factor_solve_cpu_s"] for r in sel],
                            [r["factor_solve_spread_s"] for r in sel])
    lines(out / "solvers.png", series, "dofs", "CPU s per factorisation + solve",
          "ring tangent: direct solvers and orderings, GMRES + GAMG")
    return rows

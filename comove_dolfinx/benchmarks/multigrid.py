"""krylov: MUMPS against the iterative path (GMRES + GAMG, GMRES + BoomerAMG) per Newton iteration.

Per scene, mesh size and linear solver (``NewtonSettings.linear_solver``), short runs on the ranks
this was started with, repeated: CPU time per Newton iteration (summed over the ranks; median and
spread), wall time per iteration (largest over the ranks), Newton iterations, Krylov iterations per
linear solve and the peak resident memory of the largest rank (``resource.getrusage``: the process's
peak so far, so each row runs in order of size and within a size MUMPS last, whose factors take the
most). Rows are appended to krylov.csv (run once serial, once under ``mpirun``). The scene is any
preset scene that takes ``size`` (a 3-D body's as well, once it has one).
"""
from __future__ import annotations

import pathlib
import resource

from mpi4py import MPI

from .runs import COMM, say, short_run, stats, write_csv

#: the plate at about 17k, 48k and 195k dofs
SIZES = {"plate": (0.1, 0.059, 0.029), "ring": (0.115, 0.058, 0.0365)}
NAMES = ("gamg", "hypre", "mumps")


def peak_mb() -> float:
    """The largest peak resident memory of the ranks so far, MB (Linux reports kB)."""
    return COMM.allreduce(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0, op=MPI.MAX)


def solver_row(runs: list[dict], **labels) -> dict:
    """The row of repeated runs (:func:`~.runs.short_run`'s figures) with one linear solver:
    ``labels`` first, then dofs, ranks, Newton iterations, Krylov iterations per solve, CPU and
    wall seconds per Newton iteration (median and spread) and the peak memory so far."""
    its = [max(r["iterations"], 1) for r in runs]
    newton = runs[-1]["newton"]
    row = {**labels, "dofs": runs[-1]["dofs"], "ranks": COMM.size, "newton_its": runs[-1]["iterations"],
           "completed_to": runs[-1]["completed_to"],
           "krylov_per_solve": newton.krylov_total / max(newton.linear_solves, 1)}
    row["cpu_per_it_s"], row["cpu_spread_s"] = stats([r["cpu"] / i for r, i in zip(runs, its)])
    row["wall_per_it_s"], row["wall_spread_s"] = stats([r["wall"] / i for r, i in zip(runs, its)])
    row["peak_mb"] = peak_mb()
    return row


def _row(scene: str, size: float, name: str, repeats: int, increments: int) -> dict:
    """The row of one scene, size and linear solver: ``repeats`` short runs of ``increments``."""
    runs = [short_run(scene, size, increments, linear_solver=name) for _ in range(repeats)]
    return solver_row(runs, scene=scene, size=size, solver=name)


def krylov(out: pathlib.Path, scene: str = "plate", sizes=None, names=NAMES, repeats: int = 3,
           increments: int = 1) -> list[dict]:
    """Short runs of ``scene`` at each size (ascending) with each linear solver of ``names``; rows
    appended to krylov.csv."""
    rows = []
    for size in sorted(sizes or SIZES[scene], reverse=True):        # coarse (large size) first
        for name in names:
            row = _row(scene, size, name, repeats, increments)
            rows.append(row)
            say(f"{scene} {row['dofs']} dofs, {COMM.size} rank(s), {name}: {row['newton_its']} Newton its, "
                f"{row['krylov_per_solve']:.1f} Krylov its/solve, CPU {row['cpu_per_it_s']:.3f} s/it "
                f"(+-{row['cpu_spread_s'] / 2:.3f}), wall {row['wall_per_it_s']:.3f} s/it, "
                f"peak {row['peak_mb']:.0f} MB")
    write_csv(out / "krylov.csv", rows, append=True)
    return rows

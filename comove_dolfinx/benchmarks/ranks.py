"""scale: the same short runs on one rank and under mpirun.

Per scene, size and number of ranks (run once serial, once under ``mpirun``, rows appended to
scale.csv), the wall and CPU time (summed over the ranks) per Newton iteration of a short run,
MUMPS against GMRES + GAMG.
"""
from __future__ import annotations

import pathlib

from ..io.csv_tables import read_table
from .charts import lines
from .linear_solvers import SOLVERS
from .runs import COMM, say, short_run, stats, write_csv

SCALE = {"ring": (0.0365, 0.0175), "plate": (0.059, 0.029)}     # about 50k and 190k dofs


def _scale_row(name: str, size: float, solver: str, repeats: int, increments: int) -> dict:
    """The row of one scene, size and solver on this run's ranks: time per iteration, median and
    spread of ``repeats`` short runs."""
    runs = [short_run(name, size, increments, SOLVERS[solver]) for _ in range(repeats)]
    its = [max(r["iterations"], 1) for r in runs]
    row = {"scene": name, "size": size, "dofs": runs[-1]["dofs"], "ranks": COMM.size,
           "solver": solver, "iterations": runs[-1]["iterations"],
           "completed_to": runs[-1]["completed_to"]}
    wall = [r["wall"] / i for r, i in zip(runs, its)]
    cpu = [r["cpu"] / i for r, i in zip(runs, its)]
    row["wall_per_it_s"], row["wall_spread_s"] = stats(wall)
    row["cpu_per_it_s"], row["cpu_spread_s"] = stats(cpu)
    return row


def _scale_chart(out: pathlib.Path) -> None:
    """scale.png from every row of scale.csv (this run's and the earlier ones')."""
    series = {}
    for r in read_table(out / "scale.csv"):
        key = f"{r['scene']} {r['solver']} {r['ranks']} rank(s)"
        x, y, e = series.setdefault(key, ([], [], []))
        x.append(int(r["dofs"]))
        y.append(float(r["wall_per_it_s"]))
        e.append(float(r["wall_spread_s"]))
    lines(out / "scale.png", series, "dofs", "wall s per Newton iteration",
          "ring and plate: 1 and 2 ranks, MUMPS and GMRES + GAMG")


def scale(out: pathlib.Path, scenes=SCALE, repeats: int = 3, increments: int = 1,
          solver_names=("mumps_auto", "gmres_gamg")) -> list[dict]:
    """Short runs of each scene and size on the ranks this was started with; rows appended to
    scale.csv (run once serial, once under mpirun), the chart drawn from every row there."""
    rows = []
    for name, sizes in scenes.items():
        for size in sizes:
            for solver in solver_names:
                row = _scale_row(name, size, solver, repeats, increments)
                rows.append(row)
                say(f"{name} {row['dofs']} dofs, {COMM.size} rank(s), {solver}: {row['iterations']} its, "
                    f"wall {row['wall_per_it_s']:.3f} s/it (+-{row['wall_spread_s'] / 2:.3f}), "
                    f"CPU {row['cpu_per_it_s']:.3f} s/it")
    write_csv(out / "scale.csv", rows, append=True)
    if COMM.rank == 0:
        _scale_chart(out)
    return rows

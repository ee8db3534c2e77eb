"""floor: what a Newton iteration costs against what it cannot cost less than.

Per ring size, the CPU time of one Newton iteration of the real run (the scene's first
``--increments`` nominal increments, predictor, line searches, cut-backs and failed iterations
included: run time / all iterations) against the floor on the same mesh and degree: assembling a
linear-elastic stiffness matrix and residual (with the same lifting of the Dirichlet rows) and one
MUMPS factorisation and solve (symbolic analysis done once, as in Newton), sampled after every
increment of the run (its time taken out of the run's); the ratio is the median over the runs of the
run's time per iteration over the mean of its floor samples. Also the run's residual evaluations per
iteration and its Timer split; a cProfile listing of the largest size.
"""
from __future__ import annotations

import cProfile
import io
import pathlib
import pstats

import numpy as np

from .charts import floor_chart
from .runs import COMM, RING_SIZES, ElasticFloor, say, short_run, stats, write_csv

#: the Timer's parts booked per iteration in floor.csv
TIMED_PARTS = ("solve", "jacobian", "assembly", "stress update", "force scale", "predictor")


def _sampled_run(size: float, increments: int, overrides) -> tuple[dict, tuple[float, list]]:
    """One short run of the ring with the floor sampled after every increment: (the run, (the
    floor's mean CPU seconds, its mean split into matrix, vector and solve))."""
    samples, holder = [], {}

    def sample(model):
        if "floor" not in holder:
            holder["floor"] = ElasticFloor(model)
        samples.append(holder["floor"].sample())
    run = short_run("ring", size, increments, count=True, between=sample, overrides=overrides)
    if not samples:                          # no increment converged: one after the run
        sample(run["model"])
    holder["floor"].destroy()
    split = np.mean(samples, axis=0)
    return run, (float(split.sum()), list(split))


def _floor_row(size: float, runs: list[dict], floors: list[tuple]) -> dict:
    """The table's row of one size: the iteration, the floor and their ratio (medians and spreads
    over the runs), the last run's Timer split per iteration and the floor's split."""
    per_it = [r["cpu"] / max(r["iterations"], 1) for r in runs]
    fl = [f[0] for f in floors]
    ratios = [a / b for a, b in zip(per_it, fl)]
    split = [float(np.median([f[1][k] for f in floors])) for k in range(3)]
    r = runs[-1]
    its = max(r["iterations"], 1)
    t = r["timer"]
    row = {"size": size, "dofs": r["dofs"], "iterations": r["iterations"],
           "increments": r["increments"], "residuals_per_it": round(r["residuals"] / its, 2)}
    row["iteration_cpu_s"], row["iteration_spread_s"] = stats(per_it)
    row["floor_cpu_s"], row["floor_spread_s"] = stats(fl)
    row["ratio"], row["ratio_spread"] = stats(ratios)
    for k in TIMED_PARTS:
        row[f"{k.replace(' ', '_')}_s_per_it"] = t.get(k, 0.0) / its       # CPU, last run
    # the last run's CPU outside every timed part (its "output" is the floor's samples, which
    # its CPU leaves out): line searches, checks, commits, Python
    row["other_s_per_it"] = (r["cpu"] - sum(v for k, v in t.items() if k != "output")) / its
    for k, v in zip(("floor_matrix_s", "floor_vector_s", "floor_solve_s"), split):
        row[k] = v
    return row


def floor(out: pathlib.Path, sizes=RING_SIZES, repeats: int = 3, increments: int = 4,
          overrides=()) -> list[dict]:
    """The ring's iteration against the floor at each size, ``repeats`` runs of ``increments``
    increments each (scene parameters ``overrides``, "key=value"): floor.csv, floor.png and the
    profile of the last size."""
    rows = []
    for size in sizes:
        # each run samples the floor on its own mesh after every increment, and its ratio is taken
        # against the mean of those samples: the floor is measured in the same minutes as the run,
        # so the machine's speed drifting (other virtual machines on the host: up to 2x within a
        # minute here) enters both alike
        runs, floors = zip(*(_sampled_run(size, increments, overrides) for _ in range(repeats)))
        row = _floor_row(size, list(runs), list(floors))
        rows.append(row)
        say(f"ring size {size}: {row['dofs']} dofs, {row['iterations']} its, iteration "
            f"{row['iteration_cpu_s'] * 1e3:.1f} ms (+-{row['iteration_spread_s'] * 5e2:.1f}), floor "
            f"{row['floor_cpu_s'] * 1e3:.1f} ms, ratio {row['ratio']:.2f} (+-{row['ratio_spread'] / 2:.2f}), "
            f"{row['residuals_per_it']} residuals/it")
    write_csv(out / "floor.csv", rows)
    floor_chart(out / "floor.png", rows)
    if sizes:
        _profile(out, sizes[-1], increments, overrides)
    return rows


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

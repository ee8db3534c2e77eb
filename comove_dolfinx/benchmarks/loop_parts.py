"""parts: what each part of a Newton iteration costs inside the loop beyond its own work.

The residual and its stress evaluation, the Jacobian and the floor's matrix and residual, and two
calls that do nearly nothing (a NumPy sum of 16 values, a PETSc vector norm), at the ring's state
after ``--increments`` (6) increments, each timed back to back, right after a factorisation and
solve of the tangent (where a Newton iteration meets them) and after 4 ms of the interpreter alone
(wall time, one rank).
"""
from __future__ import annotations

import pathlib
import time

import numpy as np

from .. import compat
from ..solver import linear
from .charts import parts_chart
from .runs import COMM, ElasticFloor, say, short_run, write_csv


def _idle(seconds: float) -> None:
    """The interpreter alone for ``seconds`` (a loop on the clock: no system call, no other code)."""
    end = time.perf_counter() + seconds
    while time.perf_counter() < end:
        pass


def _cases(run: dict, floor_it: ElasticFloor) -> dict:
    """The parts to time, by name: calls on the run's model and Newton and on the floor."""
    m, newton = run["model"], run["newton"]
    w = compat.petsc_vec(floor_it.w)
    tiny = np.ones(16)
    return {
        "residual (stress evaluated again)": lambda: (m.evaluate_stress(again=True), newton.residual()),
        "stress evaluation": lambda: m.evaluate_stress(again=True),
        "residual without the stress": newton.residual,
        "Jacobian": lambda: m.assemble_jacobian(newton.A),
        "floor: elastic matrix": lambda: compat.assemble_matrix(floor_it.A, floor_it.a, m.bcs),
        "floor: elastic residual": lambda: compat.assemble_vector(floor_it.b, floor_it.L, floor_it.a,
                                                                  m.bcs, w),
        "NumPy: sum of 16 values": tiny.sum,
        "PETSc: a vector's norm": newton.b.norm,
    }


def _back_to_back(part, repeats: int) -> float:
    """Seconds per call of ``part`` called ``repeats`` times in a row, the least of seven batches."""
    part()
    alone = []
    for _ in range(7):
        t0 = time.perf_counter()
        for _ in range(repeats):
            part()
        alone.append((time.perf_counter() - t0) / repeats)
    return min(alone)


def _after(before, part, repeats: int) -> float:
    """Median seconds of ``part`` called right after ``before``, over ``repeats`` calls."""
    t = []
    for _ in range(repeats):
        before()
        t0 = time.perf_counter()
        part()
        t.append(time.perf_counter() - t0)
    return float(np.median(t))


def _size_rows(size: float, increments: int, repeats: int) -> list[dict]:
    """parts.csv's rows of one ring size: each part's three timings, in microseconds."""
    run = short_run("ring", size, increments)
    m, newton = run["model"], run["newton"]
    floor_it = ElasticFloor(m)
    du = compat.petsc_vec(m.du)

    def factorise():
        m.assemble_jacobian(newton.A)
        linear.solve(newton.ksp, newton.petsc_options, newton.b, du, m.comm)
    rows = []
    for name, part in _cases(run, floor_it).items():
        row = {"size": size, "dofs": run["dofs"], "part": name,
               "alone_us": 1e6 * _back_to_back(part, repeats),
               "after_factorisation_us": 1e6 * _after(factorise, part, repeats),
               "after_idle_us": 1e6 * _after(lambda: _idle(4e-3), part, repeats)}
        rows.append(row)
        say(f"ring size {size}, {name}: alone {row['alone_us']:.1f} us, after a factorisation "
            f"{row['after_factorisation_us']:.1f} us, after 4 ms of the interpreter "
            f"{row['after_idle_us']:.1f} us")
    floor_it.destroy()
    return rows


def parts(out: pathlib.Path, sizes=(0.22,), increments: int = 6, repeats: int = 40) -> list[dict]:
    """The parts of a Newton iteration, and the floor's, timed at the ring's state after
    ``increments`` increments in three conditions: back to back (the minimum over seven batches of
    ``repeats`` calls), each right after a Jacobian assembly, factorisation and solve (as a Newton
    iteration meets the residual) and each after 4 ms of the interpreter alone (medians of
    ``repeats``). Wall microseconds of one rank: parts.csv and parts.png."""
    rows = [row for size in sizes for row in _size_rows(size, increments, repeats)]
    write_csv(out / "parts.csv", rows)
    if COMM.rank == 0 and rows:
        parts_chart(out / "parts.png", rows)
    return rows

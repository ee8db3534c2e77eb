"""solid: the linear solvers of a 3D body's Newton iterations, from 50k to a million dofs.

A block of 4 x 1 x 1 (``cm.box``, P2 tetrahedra), clamped at x = 0 and bent by a prescribed
deflection of its end x = 4 (along -z) well into plasticity (J2 with linear hardening, the first
yield at about a quarter of the final deflection), in a few increments. Per mesh size and linear
solver (``NewtonSettings.linear_solver``: MUMPS, GMRES + GAMG or BoomerAMG with the rigid-body
modes of the current configuration), on the ranks it was started with: Newton iterations, Krylov
iterations per linear solve, CPU seconds per Newton iteration (summed over the ranks; median and
spread of the repeats), wall seconds per iteration (largest over the ranks) and the peak resident
memory of the largest rank (the process's peak so far: the rows run from coarse to fine and, at a
size, MUMPS last). Rows are appended to solid.csv (run once serial, once under ``mpirun``).
"""
from __future__ import annotations

import pathlib

from ..geometry import box
from ..loads import Displacement, Fixed
from ..mechanics.body import Body
from ..mechanics.materials import J2, Hardening
from ..mechanics.model import Model
from ..solver import NewtonSettings, StepSettings
from .multigrid import solver_row
from .runs import COMM, say, timed_run, write_csv

#: mesh sizes of about 50k, 200k and 1M dofs (P2 tetrahedra: about 96 / size^3 dofs)
SIZES = (0.125, 0.078, 0.046)
NAMES = ("gamg", "hypre", "mumps")
DEFLECTION = 0.04        # the end's deflection: the surface yields at about 0.011 (E = 1000, sigma0 = 1)


def block(size: float) -> Model:
    """The bent block at mesh ``size``, finalized."""
    mesh = box(4.0, 1.0, 1.0, size, comm=COMM)
    body = Body(mesh, "solid", J2(1000.0, 0.3, Hardening.linear(1.0, 10.0)))
    model = Model(body, [Fixed("left"), Displacement("right", -DEFLECTION, component=2)])
    model.finalize()
    return model


def _row(size: float, name: str, repeats: int, increments: int) -> dict:
    """The row of one size and linear solver: ``repeats`` runs of ``increments`` increments."""
    runs = [timed_run(block(size), NewtonSettings(linear_solver=name), StepSettings(n_increments=increments))
            for _ in range(repeats)]
    return solver_row(runs, size=size, solver=name)


def solid(out: pathlib.Path, sizes=None, names=NAMES, repeats: int = 2, increments: int = 3) -> list[dict]:
    """The bent block at each size (coarse first) with each linear solver of ``names`` (MUMPS
    last at a size, for the memory column); rows appended to solid.csv."""
    rows = []
    order = sorted(names, key=lambda n: n == "mumps")
    for size in sorted(sizes or SIZES, reverse=True):
        for name in order:
            row = _row(size, name, repeats, increments)
            rows.append(row)
            say(f"solid {row['dofs']} dofs, {COMM.size} rank(s), {name}: {row['newton_its']} Newton its, "
                f"{row['krylov_per_solve']:.1f} Krylov its/solve, CPU {row['cpu_per_it_s']:.3f} s/it "
                f"(+-{row['cpu_spread_s'] / 2:.3f}), wall {row['wall_per_it_s']:.3f} s/it, "
                f"peak {row['peak_mb']:.0f} MB")
            write_csv(out / "solid.csv", [row], append=True)
    return rows

"""CalculiX's reference for the necking case: our deck of the bar, its run, and its printed history.

:func:`calculix_deck` writes the input (CAX8R on the grid of cm.necking_bar_grid, NLGEOM, fixed
increments; docs/verification/necking_calculix.inp is its output at the defaults),
:func:`run_calculix` runs ccx on it and :func:`read_calculix` reads the end's force and the neck's
radius of each increment from the .dat file. ``python -m comove_dolfinx.verify.necking --calculix
DIR`` does all three.
"""
from __future__ import annotations

import pathlib

import numpy as np

from .necking_law import (DELTA, DSIGMA, GRADING, LENGTH, N_R, N_INCREMENTS, N_Z, NU, PULL, REDUCTION, SIGMA0,
                          E, H, R, plastic_table)

def _deck_mesh(n_r: int, n_z: int, grading: float) -> tuple[list[str], list[str], dict]:
    """The deck's ``*NODE`` lines, its ``*ELEMENT`` connectivities (CAX8R: four corners
    counter-clockwise in (r, z), then four mid-sides) and the node numbers by (j, i) on the doubled
    grid; node 1 is the outer node of the neck."""
    from ..geometry.builders import necking_bar_grid
    z, r = necking_bar_grid(R, LENGTH, REDUCTION, n_r, n_z, grading)
    # nodes on the doubled grid (2 n_z + 1) x (2 n_r + 1): corners at even indices, mid-sides
    # where one index is odd; the centres (both odd) are not used by eight-node elements
    zz = np.empty(2 * n_z + 1)
    zz[0::2], zz[1::2] = z, 0.5 * (z[:-1] + z[1:])
    frac = np.arange(2 * n_r + 1) / (2 * n_r)
    radius = R * (1.0 - REDUCTION * (1.0 - zz / (0.5 * LENGTH)))
    ids, nodes, number = {}, [], 1
    order = [(0, 2 * n_r)] + [(j, i) for j in range(2 * n_z + 1) for i in range(2 * n_r + 1)
                               if not (j % 2 and i % 2) and (j, i) != (0, 2 * n_r)]
    for j, i in order:
        ids[j, i] = number
        nodes.append(f"{number}, {radius[j] * frac[i]:.12g}, {zz[j]:.12g}")
        number += 1
    elems = []
    for j in range(n_z):
        for i in range(n_r):
            a, b = 2 * j, 2 * i
            corners = [(a, b), (a, b + 2), (a + 2, b + 2), (a + 2, b)]       # counter-clockwise in (r, z)
            mids = [(a, b + 1), (a + 1, b + 2), (a + 2, b + 1), (a + 1, b)]
            elems.append(", ".join(str(ids[k]) for k in corners + mids))
    return nodes, elems, ids


def calculix_deck(n_r: int = N_R, n_z: int = N_Z, grading: float = GRADING, n_increments: int = N_INCREMENTS,
                  tol: float = 1e-5) -> str:
    """Our CalculiX input of the bar: CAX8R on the grid of cm.necking_bar_grid (eight-node
    quadrilaterals with straight edges), NLGEOM, ``n_increments`` fixed increments. Node 1 is the outer
    node of the neck; the set NEND is the end, whose total reaction is printed each increment."""
    nodes, elems, ids = _deck_mesh(n_r, n_z, grading)
    pieces = lambda rows: "\n".join(", ".join(str(v) for v in rows[k:k + 8])  # noqa: E731
                                    for k in range(0, len(rows), 8))
    axis = [ids[j, 0] for j in range(2 * n_z + 1)]
    neck = [ids[0, i] for i in range(2 * n_r + 1)]
    end = [ids[2 * n_z, i] for i in range(2 * n_r + 1)]
    p, s = plastic_table(tol)
    plastic = "\n".join(f"{sv:.10g}, {pv:.10g}" for pv, sv in zip(p, s))
    return "\n".join([
        "** Necking of a circular bar (Simo 1988), quarter of the axial section, mm and GPa (forces kN).",
        f"** Written by comove_dolfinx.verify.necking.calculix_deck(n_r={n_r}, n_z={n_z}, "
        f"grading={grading}, n_increments={n_increments}, tol={tol}).",
        "*NODE, NSET=NALL", *nodes,
        "*ELEMENT, TYPE=CAX8R, ELSET=EALL",
        *(f"{k + 1}, {e}" for k, e in enumerate(elems)),
        "*NSET, NSET=NAXIS", pieces(axis),
        "*NSET, NSET=NNECK", pieces(neck),
        "*NSET, NSET=NEND", pieces(end),
        "*NSET, NSET=NOUT", "1",
        "*MATERIAL, NAME=STEEL",
        "*ELASTIC", f"{E}, {NU}",
        f"** sigma_y = {SIGMA0} + {H} p + {DSIGMA} (1 - exp(-{DELTA} p)) sampled within {tol} GPa",
        "*PLASTIC", plastic,
        "*SOLID SECTION, ELSET=EALL, MATERIAL=STEEL",
        "*BOUNDARY", "NAXIS, 1, 1, 0.0", "NNECK, 2, 2, 0.0",
        "*STEP, NLGEOM, INC=100000",
        "*STATIC, DIRECT", f"{1.0 / n_increments:.15g}, 1.0",
        "*BOUNDARY", f"NEND, 2, 2, {PULL}",
        "*NODE PRINT, NSET=NEND, TOTALS=ONLY", "RF",
        "*NODE PRINT, NSET=NOUT", "U",
        "*END STEP", ""])


def read_calculix(dat: str | pathlib.Path, scale: float = 1.0) -> np.ndarray:
    """(time, u, force, neck radius) of each increment from a .dat file of :func:`calculix_deck`;
    ``scale`` turns the printed reaction into the total over the circumference."""
    rows, block, t = [], None, None
    for line in pathlib.Path(dat).read_text().splitlines():
        words = line.split()
        if "total force" in line and "time" in line:
            block, t = "force", float(words[-1])
        elif line.strip().startswith("displacements") and "time" in line:
            block, t = "u", float(words[-1])
        elif block and len(words) == 3 and block == "force":
            rows.append([t, scale * float(words[1])])
            block = None
        elif block == "u" and len(words) == 4 and words[0] == "1":
            rows[-1] += [float(words[1]), float(words[2])]
            block = None
    return np.array([[t, PULL * t, f, R * (1.0 - REDUCTION) + u_r] for t, f, u_r, _ in rows])


CCX_SCALE = 180.0
"""ccx expands an axisymmetric model into a 2-degree segment and prints its forces for that segment:
the total over the circumference is 180 times the printed one (checked: the first, elastic increment
gives E A eps to 0.1 %)."""


def run_calculix(folder: pathlib.Path, **grid) -> tuple[np.ndarray, float]:
    """Write the deck into ``folder`` (bar.inp), run ccx there (one thread) and return its history
    (time, u, force, neck radius) and its CPU seconds (user + system of the child, os.times)."""
    import os
    import subprocess
    folder = pathlib.Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "bar.inp").write_text(calculix_deck(**grid))
    env = dict(os.environ, OMP_NUM_THREADS="1", CCX_NPROC_EQUATION_SOLVER="1")
    before = os.times()
    subprocess.run(["ccx", "-i", "bar"], cwd=folder, env=env, check=True, stdout=subprocess.DEVNULL)
    after = os.times()
    cpu = (after.children_user - before.children_user) + (after.children_system - before.children_system)
    return read_calculix(folder / "bar.dat", CCX_SCALE), cpu


def write_history(path: pathlib.Path, hist: np.ndarray) -> None:
    np.savetxt(path, hist, delimiter=",", fmt="%.9g", header="time,u_mm,force_kN,neck_radius_mm", comments="")

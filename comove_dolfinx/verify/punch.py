"""Prandtl's flat punch: volumetric locking in plastic flow (plane strain and a 3D slab).

A smooth rigid flat punch of half-width b = 1 is pressed into a perfectly plastic half-space (J2,
E = 1000, nu = 0.3, shear yield stress k = 1, i.e. sigma0 = sqrt(3)); plane strain, small strains
(``update="small_strain"``: the classical problem). The limit pressure is (2 + pi) k [Prandtl 1920;
Hill 1950, ch. VIII]. The half model [0, 5] x [-5, 0] (5 half-widths wide and deep: the plastic zone
of the mechanism reaches 2 b sideways and about 1.4 b deep) has u_x = 0 on its axis and right side and
u = 0 at its base; the punch is a prescribed settlement u_y = -0.05 (25 increments; the pressure
levels off after about 0.02) of the facets under it, u_x free (a smooth punch). The mesh is n x n
squares cut into triangles (``crossed``: four per square; ``right``: two), graded towards the
punch's edge; the slab is the same squares, one layer of cubes (six tetrahedra each), held by
u_z = 0 on both faces.

Plastic flow keeps the volume, and an element whose displacements cannot follow such a flow locks:
the limit pressure comes out too high and falls slowly as the mesh is refined. Measured here:

* P2 triangles (the default element) reach the limit pressure as the mesh is refined, the error
  falling about as h^1.7; checked at the finest mesh (n = 32, crossed) within 1 %.
* P2 tetrahedra (the slab, n = 16) are within 3.5 %, as P2 triangles with one diagonal are
  (the same vertices): no locking in 3D either.
* P1 triangles (and tetrahedra) overshoot by 10-40 % on these meshes and converge about as h: they
  lock. So do Q1 quadrilaterals (the squares themselves) and hexahedra. A job with P1 displacements
  that yields in plane strain, axisymmetry or 3D says so (guards.py) and advises degree=2 (or, on
  quadrilaterals and hexahedra, fbar=True).
* Q1 with ``fbar=True`` (B-bar here, under linear kinematics: mechanics/volume.py) converges as P2
  does: checked at n = 32 within 2 %, and the slab of Q1 hexahedra at n = 16 within 5 %.

With ``small`` the meshes are n = 8 and 16 (P2 checked at n = 16 within 2.5 %, Q1 with B-bar
within 5 %), the slab n = 8 (P2 within 10 %, Q1 with B-bar within 15 %).
"""
from __future__ import annotations

import math
import pathlib

import numpy as np
from mpi4py import MPI

from . import Check
from .common import run_job, save_figure

NAME = "punch"
TITLE = "Prandtl's flat punch"
SOURCE = "Prandtl 1920; Hill 1950, ch. VIII"

PRANDTL = 2.0 + math.pi          # the limit pressure over the shear yield stress k
WIDTH = DEPTH = 5.0              # the half model; the punch's half-width is 1
SETTLEMENT, INCREMENTS = 0.05, 25
FBAR = {False: "", True: " with B-bar"}     # the label of fbar=True (B-bar under linear kinematics)


def _graded(s, power: float = 1.8):
    """[0, 1] onto [0, 1], denser towards 0."""
    return np.clip(s, 0.0, 1.0) ** power


def mesh(n: int, diagonal: str = "crossed", slab: bool = False, comm=MPI.COMM_WORLD):
    """The half model in n x n squares graded towards the punch's edge (1, 0), a MeshData with the
    facets 'punch' (y = 0, x <= 1), 'top' (the rest of y = 0), 'sym' (x = 0), 'bottom' and
    'right'; with ``slab`` a layer of n x n x 1 cubes of tetrahedra, 2 WIDTH / n thick, whose faces
    z = const are 'faces'. ``diagonal`` "none": the squares (and cubes) themselves, quadrilaterals
    (hexahedra)."""
    import dolfinx.mesh

    from ..geometry import from_dolfinx
    lower, upper = np.array([0.0, -DEPTH]), np.array([WIDTH, 0.0])
    thick = 2.0 * WIDTH / n
    CellType = dolfinx.mesh.CellType
    if slab:
        msh = dolfinx.mesh.create_box(comm, [np.append(lower, 0.0), np.append(upper, thick)], [n, n, 1],
                                      CellType.hexahedron if diagonal == "none" else CellType.tetrahedron)
    elif diagonal == "none":
        msh = dolfinx.mesh.create_rectangle(comm, [lower, upper], [n, n], CellType.quadrilateral)
    else:
        msh = dolfinx.mesh.create_rectangle(comm, [lower, upper], [n, n], dolfinx.mesh.CellType.triangle,
                                            diagonal=getattr(dolfinx.mesh.DiagonalType, diagonal))
    x = msh.geometry.x
    xs, ys, half = x[:, 0].copy(), x[:, 1].copy(), WIDTH / 2
    x[:, 0] = np.where(xs <= half, 1.0 - _graded((half - xs) / half),
                       1.0 + (WIDTH - 1.0) * _graded((xs - half) / half))
    x[:, 1] = -DEPTH * _graded(-ys / DEPTH)
    groups = {"punch": lambda p: np.isclose(p[1], 0.0) & (p[0] <= 1.0 + 1e-9),
              "top": lambda p: np.isclose(p[1], 0.0) & (p[0] >= 1.0 - 1e-9),
              "sym": lambda p: np.isclose(p[0], 0.0),
              "bottom": lambda p: np.isclose(p[1], -DEPTH),
              "right": lambda p: np.isclose(p[0], WIDTH)}
    if slab:
        groups["faces"] = lambda p: np.isclose(p[2], 0.0) | np.isclose(p[2], thick)
    fdim = msh.topology.dim - 1
    facets, values = [], []
    for tag, where in enumerate(groups.values(), start=1):
        found = dolfinx.mesh.locate_entities_boundary(msh, fdim, where)
        facets.append(found)
        values.append(np.full(found.size, tag, dtype=np.int32))
    facets, values = np.concatenate(facets), np.concatenate(values)
    order = np.argsort(facets, kind="stable")
    tags = dolfinx.mesh.meshtags(msh, fdim, facets[order], values[order])
    return from_dolfinx(msh, tags, {name: tag for tag, name in enumerate(groups, start=1)})


def press(n: int, degree: int, diagonal: str = "crossed", slab: bool = False, comm=MPI.COMM_WORLD,
          fbar: bool = False):
    """The punch pressed: (settlements, pressures / k, the job's Results, Newton iterations, CPU s);
    ``fbar``: B-bar (the body's option)."""
    import comove_dolfinx as cm
    body = cm.Body(mesh(n, diagonal, slab, comm), "solid" if slab else "plane_strain",
                   cm.J2(1000.0, 0.3, cm.Hardening.perfect(math.sqrt(3.0))), degree=degree,
                   update="small_strain", fbar=fbar)
    items = [cm.Fixed("sym", 0), cm.Fixed("bottom"), cm.Fixed("right", 0),
             cm.Displacement("punch", -SETTLEMENT, component=1)]
    if slab:
        items.append(cm.Fixed("faces", 2))
    probe = cm.Reaction("punch", "P", dim=3 if slab else 2)
    res, its, cpu = run_job(cm.Job(body, items, [cm.Step(INCREMENTS)], probes=[probe], writers=[]), comm)
    thickness = 2.0 * WIDTH / n if slab else 1.0
    return SETTLEMENT * res["load"], np.abs(res["P_fy"]) / thickness, res, its, cpu


def run(out: pathlib.Path, small: bool = False) -> list[Check]:
    comm = MPI.COMM_WORLD
    out = pathlib.Path(out)
    sizes = (8, 16) if small else (8, 16, 32)
    curves, checks = {}, []
    for degree in (1, 2):
        for n in sizes:
            curves[f"P{degree} triangles, n = {n}"] = press(n, degree, comm=comm)
    for fbar in (False, True):
        for n in sizes:
            curves[f"Q1 quadrilaterals{FBAR[fbar]}, n = {n}"] = press(n, 1, "none", comm=comm, fbar=fbar)
    n_slab = 8 if small else 16
    curves[f"P2 tetrahedra (slab), n = {n_slab}"] = press(n_slab, 2, slab=True, comm=comm)
    curves[f"Q1 hexahedra{FBAR[True]} (slab), n = {n_slab}"] = press(n_slab, 1, "none", slab=True, comm=comm,
                                                                       fbar=True)
    checked = [(f"P2 triangles, n = {sizes[-1]}", 0.025 if small else 0.01),
               (f"P2 tetrahedra (slab), n = {n_slab}", 0.10 if small else 0.035),
               (f"Q1 quadrilaterals{FBAR[True]}, n = {sizes[-1]}", 0.05 if small else 0.02),
               (f"Q1 hexahedra{FBAR[True]} (slab), n = {n_slab}", 0.15 if small else 0.05)]
    for label, tol in checked:
        _, p, res, its, cpu = curves[label]
        checks.append(Check(TITLE, SOURCE, f"{label} ({res.dofs} dofs): limit pressure / k against 2 + pi",
                            PRANDTL, p[-1], tol, its, cpu))
    if comm.rank == 0:
        from ..io.csv_tables import write_table
        write_table(out / f"{NAME}_limits.csv",
                    [{"mesh": label, "dofs": res.dofs, "limit_pressure/k": p[-1],
                      "error": p[-1] / PRANDTL - 1.0, "newton_its": its, "cpu_s": cpu}
                     for label, (_, p, res, its, cpu) in curves.items()])
    _plot(out, curves, comm)
    return checks


def _plot(out, curves: dict, comm) -> None:
    """Left: the pressure against the settlement on the middle meshes (n = 16, or the slab's);
    right: the limit pressure's error against the dofs for each element."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, (left, right) = plt.subplots(1, 2, figsize=(10.5, 4.4))
    families = {}
    for label, (d, p, res, *_) in curves.items():
        family, n = label.rsplit(", n = ", 1)
        families.setdefault(family, []).append((res.dofs, p[-1] / PRANDTL - 1.0))
        if n == "16" or "slab" in family and n == "8":
            style = "-." if "B-bar" in label else "--" if label[:2] in ("P1", "Q1") else (
                "-" if "triangles" in label else ":")
            left.plot(np.append(0.0, d), np.append(0.0, p), style, lw=1.4, label=label)
    left.axhline(PRANDTL, color="k", lw=1, label="2 + pi (Prandtl)")
    left.set_xlabel("settlement of the punch / its half-width")
    left.set_ylabel("mean pressure / k")
    left.set_ylim(0, 1.4 * PRANDTL)
    left.legend(fontsize=7, loc="lower right")
    for family, points in families.items():
        dofs, err = np.array(points).T
        right.loglog(dofs, err, "s--" if "slab" in family else "o-", label=family)
    right.set_xlabel("displacement dofs")
    right.set_ylabel("limit pressure / (2 + pi) k - 1")
    right.grid(True, which="both", lw=0.3)
    right.legend(fontsize=7)
    fig.suptitle("smooth flat punch on a perfectly plastic half-space (plane strain): locking and B-bar",
                 fontsize=9)
    fig.tight_layout()
    save_figure(fig, out, NAME, comm)

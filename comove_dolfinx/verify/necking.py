"""Necking of a circular bar (Simo 1988): finite-strain J2 plasticity with saturation hardening.

The bar (length 53.334 mm, radius 6.413 mm, radius 1.8 % smaller at its centre, tapering linearly
to the ends) is pulled 7 mm on each half, i.e. 14 mm in all; the quarter of its axial section is
modelled (axisymmetric, r = x, z = y): the neck z = 0 a plane of symmetry, the end z = 26.667 mm moved
axially and free radially, the axis r = 0 held radially. Material: E = 206.9 GPa, nu = 0.29,
sigma_y(p) = 0.45 + 0.12924 p + 0.265 (1 - exp(-16.93 p)) GPa (Simo 1988; Simo and Hughes 1998,
Computational Inelasticity, sec. 9.x).

Units: mm, GPa, so forces are in kN (totals over the circumference). The history is the force on
the end (the supports' reaction, positive in tension) and the radius at the neck (r at the outer
node of z = 0) against the elongation of the half bar (the end's displacement u).

References compared with:

* CalculiX (ccx 2.20, Debian 12): our own deck of the same structured grid with CAX8R elements
  (eight nodes, reduced integration), NLGEOM, the law as a *PLASTIC table sampled within 1e-5 GPa
  (below), 140 fixed increments (*STATIC, DIRECT). The deck and its history are committed in
  docs/verification/ (necking_calculix.inp, necking_calculix.csv); :func:`main` writes and runs
  them again (``python -m comove_dolfinx.verify.necking --calculix DIR``).
* The bar's homogeneous response before the neck forms, in closed form (:func:`homogeneous`).

The CSV tables and the picture necking.png go to ``out``.
"""
from __future__ import annotations

import math
import pathlib
import time

import numpy as np

from . import Check

NAME = "necking"
TITLE = "Necking of a circular bar (finite-strain J2, saturation hardening)"
SOURCE = ("J. C. Simo, Comput. Methods Appl. Mech. Engrg. 66 (1988) 199-219 and 68 (1988) 1-31; "
          "J. C. Simo and T. J. R. Hughes, Computational Inelasticity (Springer, 1998); "
          "reference curve: CalculiX ccx 2.20, CAX8R, the same grid (docs/verification/necking_calculix.*)")

# the benchmark, mm and GPa
R, LENGTH, REDUCTION = 6.413, 53.334, 0.018
E, NU = 206.9, 0.29
SIGMA0, H, DSIGMA, DELTA = 0.45, 0.12924, 0.265, 16.93
PULL = 7.0
COMPARE_UP_TO = 6.0              # mm of elongation over which the curves are compared
N_R, N_Z, GRADING = 5, 40, 3.0   # the default mesh (P2 triangles on this grid)
N_STEPS = 140

DATA = pathlib.Path(__file__).resolve().parents[2] / "docs" / "verification"


def yield_stress(p):
    """sigma_y(p) of the benchmark, GPa."""
    p = np.asarray(p, dtype=float)
    return SIGMA0 + H * p + DSIGMA * (1.0 - np.exp(-DELTA * p))


def plastic_table(tol: float = 1e-5, p_max: float = 3.0) -> tuple[np.ndarray, np.ndarray]:
    """The law sampled for a code that takes a piecewise-linear table: points p_k with
    (p_k+1 - p_k)^2 / 8 max|sigma_y''| <= tol on each interval (the bound of linear interpolation;
    sigma_y'' = -dsigma delta^2 exp(-delta p), largest at the interval's start), so that the table is
    within ``tol`` (GPa) of the law up to ``p_max``."""
    p = [0.0]
    while p[-1] < p_max:
        curvature = DSIGMA * DELTA ** 2 * math.exp(-DELTA * p[-1])
        p.append(min(p[-1] + math.sqrt(8.0 * tol / curvature), p_max))
    p = np.array(p)
    return p, yield_stress(p)


def homogeneous(u: np.ndarray, radius: float = R, half_length: float = 0.5 * LENGTH):
    """Force and radius of a straight bar (no imperfection) stretched homogeneously by u on its half
    length: uniaxial stress in logarithmic strains, eps_z = ln(1 + u / half_length) = sigma / E + p,
    sigma = sigma_y(p) (once yielding), eps_r = -nu sigma / E - p / 2; force sigma pi r^2. This is what
    a rate formulation with the logarithmic elastic strain (and the exact return of the law)
    integrates along a proportional path; it holds until the neck forms."""
    eps = np.log1p(np.asarray(u, dtype=float) / half_length)
    sig = np.minimum(E * eps, SIGMA0)
    p = np.zeros_like(eps)
    plastic = E * eps > SIGMA0
    for _ in range(60):                    # Newton on eps - sigma_y(p) / E - p = 0 (p increasing)
        r = eps - yield_stress(p) / E - p
        slope = H + DSIGMA * DELTA * np.exp(-DELTA * p)
        p = np.where(plastic, p + r / (1.0 + slope / E), 0.0)
    sig = np.where(plastic, yield_stress(p), E * eps)
    r_now = radius * np.exp(-NU * sig / E - 0.5 * p)
    return sig * math.pi * r_now ** 2, r_now


# ------------------------------------------------------------------------------------- CalculiX
def calculix_deck(n_r: int = N_R, n_z: int = N_Z, grading: float = GRADING, n_steps: int = N_STEPS,
                  tol: float = 1e-5) -> str:
    """Our CalculiX input of the bar: CAX8R on the grid of cm.necking_bar_grid (eight-node
    quadrilaterals with straight edges), NLGEOM, ``n_steps`` fixed increments. Node 1 is the outer
    node of the neck; the set NEND is the end, whose total reaction is printed each increment."""
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
        f"grading={grading}, n_steps={n_steps}, tol={tol}).",
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
        "*STATIC, DIRECT", f"{1.0 / n_steps:.15g}, 1.0",
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


# ------------------------------------------------------------------------------------- our run
def simulate(n_r: int = N_R, n_z: int = N_Z, n_steps: int = N_STEPS, predictor: str | None = None,
             grading: float = GRADING, pull: float = PULL, cache_dir: str | pathlib.Path = "meshes",
             degree: int = 2) -> dict:
    """Run the bar with the public API: P``degree`` triangles on the grid n_r x n_z, ``n_steps``
    nominal increments to the end's displacement ``pull`` (the Step's defaults, or its ``predictor``).
    Returns the columns u, force, radius (the converged increments, the unloaded state first) and
    the run's figures: newton_its, cutbacks, cpu_s (process time of the job's run, compilation
    included, the sum over ranks / ranks), completed, message."""
    from mpi4py import MPI

    import comove_dolfinx as cm
    mesh = cm.necking_bar(R, LENGTH, REDUCTION, n_r, n_z, grading, order=2, cache_dir=str(cache_dir))
    law = cm.J2(E, NU, cm.Hardening.saturation(SIGMA0, H, DSIGMA, DELTA))
    body = cm.Body(mesh, "axisymmetric", law, degree=degree)
    items = [cm.Fixed("axis", component=0), cm.Fixed("neck", component=1),
             cm.Displacement("end", pull, component=1)]
    step = cm.Step(n_steps) if predictor is None else cm.Step(n_steps, predictor=predictor)
    probes = [cm.Reaction("end", "end"), cm.NodeDisplacement("neck", (R * (1.0 - REDUCTION), 0.0), component=0,
                                                             column="neck_ur")]
    job = cm.Job(body, items, [step], probes=probes)
    cpu = time.process_time()
    res = job.run()
    cpu = MPI.COMM_WORLD.allreduce(time.process_time() - cpu, op=MPI.SUM) / MPI.COMM_WORLD.size
    return dict(u=np.r_[0.0, pull * res["load"]], force=np.r_[0.0, res["end_fy"]],
                radius=R * (1.0 - REDUCTION) + np.r_[0.0, res["neck_ur"]],
                newton_its=int(sum(res.newton_its) + res.failed_its),
                cutbacks=int(sum(inc.cutbacks for inc in res.increments)),
                increments=len(res.rows), cpu_s=cpu, completed=res.completed, message=res.message)

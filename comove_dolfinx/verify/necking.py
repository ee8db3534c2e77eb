"""Necking of a circular bar (Simo 1988): finite-strain J2 plasticity with saturation hardening.

The bar (length 53.334 mm, radius 6.413 mm, the radius 1.8 % smaller at its centre and tapering
linearly to the ends) is pulled 7 mm at each end, 14 mm in all. The quarter of its axial section is
modelled (axisymmetric, r = x, z = y, cm.necking_bar): the neck z = 0 a plane of symmetry (u_z = 0),
the axis r = 0 held radially, the end z = 26.667 mm moved 7 mm along z and free radially (a
shear-free end). Material: E = 206.9 GPa, nu = 0.29, sigma_y(p) = 0.45 + 0.12924 p + 0.265
(1 - exp(-16.93 p)) GPa [Simo 1988; Simo and Hughes 1998], cm.Hardening.saturation.

Units: mm and GPa, so forces are in kN (totals over the circumference). The history is the force on
the end (the supports' reaction, tension positive) and the radius at the neck (of the outer node of
z = 0) against the end's displacement u, the elongation of the half bar.

References:

* CalculiX (ccx 2.20, Debian 12), our own deck of the same structured grid (cm.necking_bar_grid,
  5 x 40 cells) with CAX8R elements (eight nodes, reduced integration), NLGEOM, the law as a
  ``*PLASTIC`` table within 1e-5 GPa of it (:func:`plastic_table`), fixed increments (``*STATIC, DIRECT``);
  docs/verification/necking_calculix.inp (140 increments) and the histories at 140 and 560
  increments (necking_calculix.csv, necking_calculix_560.csv; the 560 deck differs in the ``*STATIC``
  line only). ``python -m comove_dolfinx.verify.necking --calculix DIR`` writes and runs the deck again.
* The straight bar's homogeneous response in closed form (:func:`homogeneous`), until the neck forms.

Both codes' histories depend on the increment at first order once the neck forms (from 140 to 560
increments CalculiX's force at 6 mm moves by 0.7 %, ours by 1.1 % with the default update sr_log and
2.1 % with sr, docs/theory.md 3.2). The case compares the two at 140 increments, where ours lies 1.4 %
and CalculiX's 0.9 % below their limits of vanishing increments, which on this grid lie 0.4 % apart
(0.16 % with ours on 10 x 80 cells): docs/verification/necking.md, the study.
:func:`run` writes necking.csv and necking.png to ``out``.
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


def uniaxial_state(eps):
    """Stress and plastic strain of monotonic uniaxial stress at the axial strain ``eps`` (the sum of
    the increments' strains): sigma = E eps while elastic, else sigma = sigma_y(p) with
    sigma / E + p = eps (Newton's iteration on p, monotone from p = 0)."""
    eps = np.asarray(eps, dtype=float)
    plastic = E * eps > SIGMA0
    p = np.zeros_like(eps)
    for _ in range(60):
        r = eps - yield_stress(p) / E - p
        p = np.where(plastic, p + r / (1.0 + (H + DSIGMA * DELTA * np.exp(-DELTA * p)) / E), 0.0)
    return np.where(plastic, yield_stress(p), E * eps), p


def homogeneous(u, radius: float = R, half_length: float = 0.5 * LENGTH, n_steps: int | None = None,
                update: str = "sr_log"):
    """Force and radius of a straight bar (no imperfection) stretched homogeneously by u on its half
    length, in uniaxial stress, as long as it stays homogeneous (until the neck forms).

    ``n_steps`` None: the limit of vanishing increments, logarithmic strains, eps_z = ln(1 + u / half_length)
    = sigma / E + p with sigma = sigma_y(p) once yielding, eps_r = -nu sigma / E - p / 2 and the force
    sigma pi r^2. A whole number: what the S-R update ``update`` gives exactly in ``n_steps`` equal
    increments of u (docs/theory.md 3.2: in coaxial stretching an increment's strain is e = r - 1 with
    "sr" and e = 2 (r - 1) / (r + 1) with "sr_log", r = lambda_k+1 / lambda_k its stretch ratio), with
    the same law; the return is radial (the stress stays uniaxial), so it is exact along the path, and
    the lateral strain of increment k is e_r = -nu dsigma_k / E - dp_k / 2, from which its radial
    stretch ratio follows by inverting that map. ``u`` then is the displacement at the increments (a
    multiple of the increment)."""
    if update not in ("sr", "sr_log"):
        raise ValueError(f"update = {update!r}: the discrete solution is written for sr and sr_log")
    u = np.asarray(u, dtype=float)
    if n_steps is None:
        sig, p = uniaxial_state(np.log1p(u / half_length))
        return sig * math.pi * (radius * np.exp(-NU * sig / E - 0.5 * p)) ** 2, radius * np.exp(-NU * sig / E - 0.5 * p)
    du = u.max() / n_steps if u.size else 0.0
    k = np.arange(n_steps + 1)
    lam = 1.0 + k * du / half_length
    r = lam[1:] / lam[:-1]
    eps = np.r_[0.0, np.cumsum(r - 1.0 if update == "sr" else 2.0 * (r - 1.0) / (r + 1.0))]
    sig, p = uniaxial_state(eps)
    e_r = -NU * np.diff(sig) / E - 0.5 * np.diff(p)
    ratio = 1.0 + e_r if update == "sr" else (1.0 + 0.5 * e_r) / (1.0 - 0.5 * e_r)
    lam_r = np.cumprod(np.r_[1.0, ratio])
    at = np.rint(u / du).astype(int) if du > 0 else np.zeros(u.shape, dtype=int)
    r_now = radius * lam_r[at]
    return sig[at] * math.pi * r_now ** 2, r_now


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


# ------------------------------------------------------------------------------------- the case
# The case runs the bar as a user would write it, at the library's defaults (the update sr_log, each
# increment started from the path's tangent, a failed one retried from the last state before it is
# halved) in the benchmark's 140 increments, against CalculiX in the same 140 increments on the same
# grid. From the last converged state with the elastic tangent instead, Newton heads for the
# homogeneous, still-loading branch once the force has passed its maximum, and increments are cut
# back (249 of them at 140 nominal increments, docs/verification/necking.md).
# the test suite's run: the default mesh itself (1650 dofs, about 2 s of CPU); the coarser 3 x 16
# grid is 2.2 % off CalculiX's force at 6 mm, a mesh error that says nothing about the code
SMALL = dict(n_r=N_R, n_z=N_Z, n_steps=N_STEPS)
SMALL_TOLERANCE = 0.005
TOLERANCE = 0.005                         # the default mesh against CalculiX on the same grid
MAX_CUTBACKS = 5                          # halved increments the defaults may take


CASE_STEPS = N_STEPS                      # the case's increments, ours and CalculiX's (see run)


def reference(n_steps: int = N_STEPS) -> np.ndarray:
    """CalculiX's history (time, u, force, neck radius) in ``n_steps`` increments (140 or 560),
    docs/verification/necking_calculix[_560].csv, with the unloaded state as its first row."""
    name = "necking_calculix.csv" if n_steps == N_STEPS else f"necking_calculix_{n_steps}.csv"
    hist = np.loadtxt(DATA / name, delimiter=",", skiprows=1)
    return np.vstack([[0.0, 0.0, 0.0, R * (1.0 - REDUCTION)], hist])


def compare(ours: dict, ref: np.ndarray, upto: float = COMPARE_UP_TO) -> dict:
    """Relative differences of our force and neck radius from the reference's, at our increments
    with 0 < u <= upto (the reference interpolated linearly between its increments)."""
    u = ours["u"]
    keep = (u > 0.0) & (u <= upto + 1e-9)
    f_ref = np.interp(u[keep], ref[:, 1], ref[:, 2])
    r_ref = np.interp(u[keep], ref[:, 1], ref[:, 3])
    return dict(u=u[keep], force=ours["force"][keep] / f_ref - 1.0, radius=ours["radius"][keep] / r_ref - 1.0)


def run(out: pathlib.Path, small: bool = False) -> list[Check]:
    """The bar at the default mesh and increments (or the test suite's coarse one) and the library's
    defaults against CalculiX's history on the default grid in as many increments: force and neck
    radius at 3 and 6 mm, the force's maximum, the largest differences up to 6 mm, and the number of
    cut-backs. Writes necking.csv and necking.png to ``out``."""
    from mpi4py import MPI
    out = pathlib.Path(out)
    if MPI.COMM_WORLD.rank == 0:
        out.mkdir(parents=True, exist_ok=True)
    ref = reference(CASE_STEPS)
    args = SMALL if small else dict(n_steps=CASE_STEPS)
    ours = simulate(cache_dir=out / "meshes", **args)
    tol = SMALL_TOLERANCE if small else TOLERANCE
    its, cpu = ours["newton_its"], ours["cpu_s"]
    bench, source = "necking bar", "CalculiX ccx, CAX8R, the same grid (docs/verification)"
    checks = []
    for u in (3.0, COMPARE_UP_TO):
        checks.append(Check(bench, source, f"end force at u = {u:g} mm [kN]", float(np.interp(u, ref[:, 1], ref[:, 2])),
                            float(np.interp(u, ours["u"], ours["force"])), tol, its, cpu))
        checks.append(Check(bench, source, f"neck radius at u = {u:g} mm [mm]",
                            float(np.interp(u, ref[:, 1], ref[:, 3])),
                            float(np.interp(u, ours["u"], ours["radius"])), tol, its, cpu))
    checks.append(Check(bench, source, "largest end force [kN]", float(ref[:, 2].max()), float(ours["force"].max()),
                        tol, its, cpu))
    diff = compare(ours, ref)
    for name in ("force", "radius"):
        checks.append(Check(bench, source, f"largest relative {name} difference, 0 < u <= {COMPARE_UP_TO:g} mm",
                            0.0, float(np.abs(diff[name]).max()), tol, its, cpu))
    checks.append(Check(bench, "the library's defaults", "increments halved (cut-backs)", 0.0,
                        float(ours["cutbacks"]), MAX_CUTBACKS, its, cpu))
    if not ours["completed"]:
        checks.append(Check(bench, source, "increments completed", 1.0, 0.0, 0.0, its, cpu))
    if MPI.COMM_WORLD.rank == 0:
        np.savetxt(out / "necking.csv", np.c_[ours["u"], ours["force"], ours["radius"]], delimiter=",",
                   header="u_mm,force_kN,neck_radius_mm", comments="")
        mesh = "{n_r}x{n_z}".format(**{**dict(n_r=N_R, n_z=N_Z), **args})
        _picture(out / f"{NAME}.png", {f"this code (P2, {mesh}, {args['n_steps']} incr.)": ours}, ref,
                 f"CalculiX (CAX8R, {N_R}x{N_Z}, {CASE_STEPS} incr.)")
    return checks


def _picture(path: pathlib.Path, runs: dict, ref: np.ndarray, ref_label: str) -> None:
    """Force and neck radius against the elongation: our runs, CalculiX, the homogeneous bar."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, (a, b) = plt.subplots(1, 2, figsize=(11, 4.2))
    u = np.linspace(0.0, PULL, 300)
    f_h, r_h = homogeneous(u)
    a.plot(u, f_h, ":", color="0.5", label="straight bar, homogeneous (closed form)")
    b.plot(u, r_h / R, ":", color="0.5", label="straight bar, homogeneous (closed form)")
    a.plot(ref[:, 1], ref[:, 2], "k-", lw=2.5, alpha=0.35, label=ref_label)
    b.plot(ref[:, 1], ref[:, 3] / (R * (1.0 - REDUCTION)), "k-", lw=2.5, alpha=0.35, label=ref_label)
    for label, run_ in runs.items():
        a.plot(run_["u"], run_["force"], "-", lw=1, label=label)
        b.plot(run_["u"], run_["radius"] / (R * (1.0 - REDUCTION)), "-", lw=1, label=label)
    a.set_xlabel("elongation of the half bar u [mm]")
    a.set_ylabel("force on the end [kN]")
    b.set_xlabel("elongation of the half bar u [mm]")
    b.set_ylabel("neck radius / its initial value")
    for ax in (a, b):
        ax.axvline(COMPARE_UP_TO, color="0.8", lw=0.8)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
    fig.suptitle("Necking of a circular bar (Simo 1988): J2, sigma_y = 0.45 + 0.12924 p + 0.265 (1 - exp(-16.93 p)) GPa",
                 fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


# ------------------------------------------------------------------------------------- reproduce
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


STUDY_MESHES = ((3, 24), (5, 40), (8, 64), (10, 80))
STUDY_STEPS = (140, 280, 560)
STUDY_CALCULIX = ((3, 24, 140), (5, 40, 140), (5, 40, 280), (5, 40, 560), (8, 64, 140), (10, 80, 140))


def study(out: pathlib.Path, calculix: bool = True) -> list[dict]:
    """Meshes x increments (the library's defaults), and CalculiX on each mesh at 140 increments and on
    the default mesh at 280 and 560: force and neck radius at 3 and 6 mm, the force's maximum,
    Newton iterations, cut-backs, CPU seconds. Writes necking_study.csv and necking_study.png to
    ``out``. Serial."""
    out = pathlib.Path(out)
    out.mkdir(parents=True, exist_ok=True)
    rows = []
    for n_r, n_z in STUDY_MESHES:
        for n in STUDY_STEPS:
            r = simulate(n_r=n_r, n_z=n_z, n_steps=n, cache_dir=out / "meshes")
            rows.append(_study_row("this code (P2 triangles)", n_r, n_z, n, r))
    for n_r, n_z, n in STUDY_CALCULIX if calculix else ():
        hist, cpu = run_calculix(out / f"ccx_{n_r}x{n_z}_{n}", n_r=n_r, n_z=n_z, n_steps=n)
        r = dict(u=np.r_[0.0, hist[:, 1]], force=np.r_[0.0, hist[:, 2]], radius=np.r_[R * (1 - REDUCTION), hist[:, 3]],
                 newton_its=0, cutbacks=0, cpu_s=cpu, completed=True)
        rows.append(_study_row("CalculiX (CAX8R)", n_r, n_z, n, r))
    keys = list(rows[0])
    with open(out / "necking_study.csv", "w") as f:
        f.write(",".join(keys) + "\n")
        for row in rows:
            f.write(",".join(f"{row[k]:.6g}" if isinstance(row[k], float) else str(row[k]) for k in keys) + "\n")
    study_picture(out / "necking_study.csv", out / "necking_study.png")
    return rows


def _study_row(code, n_r, n_z, n, r) -> dict:
    at = lambda col, u: float(np.interp(u, r["u"], r[col]))  # noqa: E731
    return dict(code=code, n_r=n_r, n_z=n_z, increments=n, force_3mm=at("force", 3.0), force_6mm=at("force", 6.0),
                radius_3mm=at("radius", 3.0), radius_6mm=at("radius", 6.0), force_max=float(np.max(r["force"])),
                newton_its=r["newton_its"], cutbacks=r["cutbacks"], cpu_s=float(r["cpu_s"]),
                completed=bool(r["completed"]))


def study_picture(csv: pathlib.Path, png: pathlib.Path) -> None:
    """The study's table as a picture: force and neck radius at 6 mm against the increment of u, one
    line per mesh and code (straight lines through 0: first order in the increment)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    rows = np.genfromtxt(csv, delimiter=",", names=True, dtype=None, encoding=None)
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2))
    colours = {m: f"C{k}" for k, m in enumerate(STUDY_MESHES)}
    for code, style in (("this code (P2 triangles)", "o-"), ("CalculiX (CAX8R)", "s--")):
        for mesh in STUDY_MESHES:
            sel = (rows["code"] == code) & (rows["n_r"] == mesh[0]) & (rows["n_z"] == mesh[1])
            if not sel.any():
                continue
            du = PULL / rows["increments"][sel]
            order = np.argsort(du)
            label = f"{'ours' if code.startswith('this') else 'CalculiX'} {mesh[0]}x{mesh[1]}"
            for ax, col in zip(axes, ("force_6mm", "radius_6mm")):
                ax.plot(du[order], rows[col][sel][order], style, color=colours[mesh], ms=4, lw=1,
                        mfc="none" if code.startswith("Calc") else None, label=label)
    for ax, what in zip(axes, ("force on the end at u = 6 mm [kN]", "neck radius at u = 6 mm [mm]")):
        ax.set_xlabel("increment of u [mm] (7 mm / increments)")
        ax.set_ylabel(what)
        ax.set_xlim(left=0.0)
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=7, ncol=2)
    fig.suptitle("Necking bar: mesh (cells n_r x n_z) and increment study, P2 triangles against CalculiX CAX8R",
                 fontsize=9)
    fig.tight_layout()
    fig.savefig(png, dpi=110)
    plt.close(fig)


def main(argv=None) -> None:
    """``python -m comove_dolfinx.verify.necking --calculix DIR``: CalculiX's reference again (the deck,
    its run, the CSV, into DIR); ``--study DIR``: the mesh and increment study; ``--case DIR``: the
    case (run) itself."""
    import argparse
    ap = argparse.ArgumentParser(prog="python -m comove_dolfinx.verify.necking")
    ap.add_argument("--calculix", metavar="DIR")
    ap.add_argument("--study", metavar="DIR")
    ap.add_argument("--case", metavar="DIR")
    args = ap.parse_args(argv)
    if args.calculix:
        hist, cpu = run_calculix(pathlib.Path(args.calculix))
        write_history(pathlib.Path(args.calculix) / "necking_calculix.csv", hist)
        print(f"CalculiX: {len(hist)} increments, {cpu:.2f} s CPU, largest force {hist[:, 2].max():.4f} kN")
    if args.study:
        for row in study(pathlib.Path(args.study)):
            print(row)
    if args.case:
        for c in run(pathlib.Path(args.case)):
            print(f"{'ok  ' if c.ok else 'FAIL'} {c.quantity}: {c.result:.6g} against {c.reference:.6g} "
                  f"(error {c.error:.2e}, tolerance {c.tolerance:g}; {c.newton_its} Newton its, {c.cpu_s:.2f} s CPU)")


if __name__ == "__main__":
    main()

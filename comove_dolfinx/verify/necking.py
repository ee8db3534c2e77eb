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
  ``*PLASTIC`` table within 1e-5 GPa of it (:func:`.necking_law.plastic_table`), fixed increments
  (``*STATIC, DIRECT``);
  docs/verification/necking_calculix.inp (140 increments) and the histories at 140 and 560
  increments (necking_calculix.csv, necking_calculix_560.csv; the 560 deck differs in the ``*STATIC``
  line only). ``python -m comove_dolfinx.verify.necking --calculix DIR`` writes and runs the deck again.
* The straight bar's homogeneous response in closed form (:func:`.necking_law.homogeneous`), until the
  neck forms.

Both codes' histories depend on the increment at first order once the neck forms (from 140 to 560
increments CalculiX's force at 6 mm moves by 0.7 %, ours by 1.1 % with the default update sr_log and
2.1 % with sr, docs/theory.md 3.2). The case compares the two at 140 increments, where ours lies 1.4 %
and CalculiX's 0.9 % below their limits of vanishing increments, which on this grid lie 0.4 % apart
(0.16 % with ours on 10 x 80 cells): docs/verification/necking.md, the study.
:func:`run` writes necking.csv and necking.png to ``out``.

The bar, the law and the closed forms are in :mod:`.necking_law`, CalculiX's deck, run and output in
:mod:`.necking_calculix`, the mesh and increment study in :mod:`.necking_study`; their names used by
the case and its tests are importable from here too.
"""
from __future__ import annotations

import pathlib
import time

import numpy as np

from . import Check
from .necking_calculix import calculix_deck  # noqa: F401 - the deck's writer (its header names it here)
from .necking_law import (DELTA, DSIGMA, GRADING, LENGTH, N_R, N_INCREMENTS, N_Z, NU, PULL, REDUCTION,  # noqa: F401
                          SIGMA0, E, H, R, homogeneous, plastic_table, yield_stress)

NAME = "necking"
TITLE = "Necking of a circular bar (finite-strain J2, saturation hardening)"
SOURCE = ("J. C. Simo, Comput. Methods Appl. Mech. Engrg. 66 (1988) 199-219 and 68 (1988) 1-31; "
          "J. C. Simo and T. J. R. Hughes, Computational Inelasticity (Springer, 1998); "
          "reference curve: CalculiX ccx 2.20, CAX8R, the same grid (docs/verification/necking_calculix.*)")

COMPARE_UP_TO = 6.0              # mm of elongation over which the curves are compared

DATA = pathlib.Path(__file__).resolve().parents[2] / "docs" / "verification"


# ------------------------------------------------------------------------------------- our run
def simulate(n_r: int = N_R, n_z: int = N_Z, n_increments: int = N_INCREMENTS, predictor: str | None = None,
             grading: float = GRADING, pull: float = PULL, cache_dir: str | pathlib.Path = "meshes",
             degree: int = 2) -> dict:
    """Run the bar with the public API: P``degree`` triangles on the grid n_r x n_z, ``n_increments``
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
    step = cm.Step(n_increments) if predictor is None else cm.Step(n_increments, predictor=predictor)
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
SMALL = dict(n_r=N_R, n_z=N_Z, n_increments=N_INCREMENTS)
SMALL_TOLERANCE = 0.005
TOLERANCE = 0.005                         # the default mesh against CalculiX on the same grid
MAX_CUTBACKS = 5                          # halved increments the defaults may take


CASE_STEPS = N_INCREMENTS                      # the case's increments, ours and CalculiX's (see run)


def reference(n_increments: int = N_INCREMENTS) -> np.ndarray:
    """CalculiX's history (time, u, force, neck radius) in ``n_increments`` increments (140 or 560),
    docs/verification/necking_calculix[_560].csv, with the unloaded state as its first row."""
    name = "necking_calculix.csv" if n_increments == N_INCREMENTS else f"necking_calculix_{n_increments}.csv"
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
    args = SMALL if small else dict(n_increments=CASE_STEPS)
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
        _picture(out / f"{NAME}.png", {f"this code (P2, {mesh}, {args['n_increments']} incr.)": ours}, ref,
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
        from .necking_calculix import run_calculix, write_history
        hist, cpu = run_calculix(pathlib.Path(args.calculix))
        write_history(pathlib.Path(args.calculix) / "necking_calculix.csv", hist)
        print(f"CalculiX: {len(hist)} increments, {cpu:.2f} s CPU, largest force {hist[:, 2].max():.4f} kN")
    if args.study:
        from .necking_study import study
        for row in study(pathlib.Path(args.study)):
            print(row)
    if args.case:
        for c in run(pathlib.Path(args.case)):
            print(f"{'ok  ' if c.ok else 'FAIL'} {c.quantity}: {c.result:.6g} against {c.reference:.6g} "
                  f"(error {c.error:.2e}, tolerance {c.tolerance:g}; {c.newton_its} Newton its, {c.cpu_s:.2f} s CPU)")


if __name__ == "__main__":
    main()

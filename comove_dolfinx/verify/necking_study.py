"""The necking case's mesh and increment study: our runs and CalculiX's on several grids.

``python -m comove_dolfinx.verify.necking --study DIR`` (docs/verification/necking.md): the
library's defaults on meshes x increments, CalculiX on each mesh at 140 increments and on the default
mesh at 280 and 560; necking_study.csv and necking_study.png.
"""
from __future__ import annotations

import pathlib

import numpy as np

from .necking import simulate
from .necking_calculix import run_calculix
from .necking_law import PULL, REDUCTION, R

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
            r = simulate(n_r=n_r, n_z=n_z, n_increments=n, cache_dir=out / "meshes")
            rows.append(_study_row("this code (P2 triangles)", n_r, n_z, n, r))
    for n_r, n_z, n in STUDY_CALCULIX if calculix else ():
        hist, cpu = run_calculix(out / f"ccx_{n_r}x{n_z}_{n}", n_r=n_r, n_z=n_z, n_increments=n)
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

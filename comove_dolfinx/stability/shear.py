"""Jaumann's oscillation in simple shear, through the public API: each stress update sheared to
gamma = 10 at several increment sizes, against the closed forms of its rate (Dienes 1979)."""
from __future__ import annotations

import csv
import pathlib
import re
import time

from .causes import Recorder, classify
from .report import Panel, heatmap, write_csv

SHEAR_ROWS = (("hughes_winget", "hughes_winget", 6), ("sr", "sr", 6), ("sr, no cut-backs", "sr", 0),
              ("polar", "polar", 6), ("neo_hooke", "neo_hooke", 6), ("svk", "svk", 6))
SHEAR_DGAMMA = (0.02, 0.1, 0.5, 1.0, 2.5)
SHEAR_GAMMA = 10.0
_MESHES: dict = {}


def jaumann_shear(gamma):
    """sigma_12 / G of the hypoelastic Jaumann law in simple shear (Dienes 1979)."""
    import numpy as np
    return np.sin(gamma)


def green_naghdi_shear(gamma):
    """sigma_12 / G of the hypoelastic Green-Naghdi law in simple shear: with beta = atan(gamma/2)
    (the polar rotation angle), 2 cos 2b (2b - 2 tan 2b ln cos b - tan b) (Dienes 1979; docs/theory.md 3.4)."""
    import numpy as np
    b = np.arctan(np.asarray(gamma, dtype=float) / 2.0)
    return 2.0 * np.cos(2 * b) * (2 * b - 2 * np.tan(2 * b) * np.log(np.cos(b)) - np.tan(b))


def simple_shear(update: str, gamma: float, n: int, max_cutbacks: int = 6, G: float = 1.0,
                 nu: float = 0.3, size: float = 1.0, monitor=None):
    """A unit square in homogeneous simple shear x = X + gamma t Y (every boundary node prescribed)
    in n equal increments; returns the Results (columns gamma, s12, s11 = stresses / G, the mean
    over the quadrature points). ``monitor``: Newton's monitor (NewtonSettings.monitor), e.g. a
    :class:`Recorder`."""
    from mpi4py import MPI

    import comove_dolfinx as cm
    E = 2.0 * G * (1.0 + nu)
    md = _MESHES.get(size)
    if md is None:
        md = _MESHES[size] = cm.rectangle(1.0, 1.0, size, order=1, comm=MPI.COMM_WORLD)

    def field(x, f):
        import numpy as np
        return np.vstack([f * gamma * x[1], np.zeros_like(x[1])])

    def mean(col):
        def fn(model):
            s = model.cauchy_stress()[:, col]
            return model.comm.allreduce(float(s.sum()), op=MPI.SUM) / \
                model.comm.allreduce(len(s), op=MPI.SUM) / G
        return fn
    body = cm.Body(md, "plane_strain", cm.Elastic(E, nu), update=update, degree=1)
    items = [cm.Displacement(b, field=field) for b in ("left", "right", "bottom", "top")]
    probes = [cm.Value("s12", mean(3)), cm.Value("s11", mean(0))]
    job = cm.Job(body, items, [cm.Step(n, max_cutbacks=max_cutbacks, predictor="none", retry=False)], probes,
                 newton=cm.NewtonSettings(monitor=monitor), load=lambda t: gamma * t)
    return job.run()


def first_decrease(gam, s12, tol: float = 1e-9) -> float | None:
    """The shear strain at the first converged level where sigma_12 falls (None: monotone)."""
    for k in range(1, len(s12)):
        if s12[k] < s12[k - 1] - tol:
            return float(gam[k - 1])
    return None


def run_shear(out: pathlib.Path) -> list[dict]:
    """Each update to gamma = 10 at each increment size dgamma: monotone or not, where it peaks,
    and its distance from the closed form of its rate (Jaumann or Green-Naghdi)."""
    import numpy as np
    rows = []
    for label, u, max_cut in SHEAR_ROWS:
        for dg in SHEAR_DGAMMA:
            n = int(round(SHEAR_GAMMA / dg))
            rec = Recorder()
            cpu0 = time.process_time()
            res = simple_shear(u, SHEAR_GAMMA, n, max_cutbacks=max_cut, monitor=rec)
            cpu = time.process_time() - cpu0
            gam, s12 = np.array([0.0, *res["load"]]), np.array([0.0, *res["s12"]])
            peak = first_decrease(gam, s12)
            cut = sum(i.cutbacks for i in res.increments)
            m = re.search(r"after (\d+) cut-backs in a row", res.message)
            cut += int(m.group(1)) if (m and not res.completed) else 0
            exact = {"hughes_winget": jaumann_shear, "sr": jaumann_shear, "polar": green_naghdi_shear}.get(u)
            err = float(np.max(np.abs(s12[gam <= 3.0] - exact(gam[gam <= 3.0])))) if exact else float("nan")
            if not res.completed:
                status, cause = "failed", classify(res.message, rec.nan_diagnosis)
            elif peak is not None:
                status, cause = "failed", f"non-monotone: s12 falls after gamma = {peak:.3g}"
            else:
                status, cause = ("cutbacks" if cut else "converged"), ""
            rows.append({"scene": "shear", "panel": 0, "method": label, "column": f"{dg:g}",
                         "sets": f"update={u} dgamma={dg:g}", "n_increments": n, "gamma0": "",
                         "max_cutbacks": max_cut, "status": status, "cutbacks": cut,
                         "load_reached": float(gam[-1]), "load_max": SHEAR_GAMMA, "cause": cause,
                         "newton_its": rec.total_its, "failed_its": rec.total_its - sum(res.newton_its),
                         "increments": len(res.increments), "cpu_s": round(cpu, 2), "wall_s": "",
                         "result": float(s12[-1]), "max_penetration": "",
                         "penetration_per_h": "",
                         "chatter_solves": 0, "max_omega2": rec.max_omega2,
                         "message": "" if res.completed else res.message,
                         "err_to_gamma3": err, "peak_gamma": peak, "curve": (gam, s12)})
            print(f"shear {label:16s} dgamma {dg:5g} {status:9s} cut {cut} {cause} s12(10) = {s12[-1]:.4g} "
                  f"err(<=3) {err:.3g}", flush=True)
    write_csv(out / "shear.csv", rows)
    _write_shear_extra(out, rows)
    heatmap(out / "shear.png", rows, shear_panels())
    _plot_shear_curves(out / "shear_curves.png", rows)
    return rows


def shear_panels() -> list[Panel]:
    return [Panel(f"simple shear to gamma = {SHEAR_GAMMA:g}: update x increment size dgamma "
                  "(red: the shear stress is not monotone, or the run failed)",
                  [(label, []) for label, _, _ in SHEAR_ROWS],
                  [(f"{d:g}", []) for d in SHEAR_DGAMMA], "dgamma")]


def _write_shear_extra(out, rows):
    with open(out / "shear_detail.csv", "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["update", "dgamma", "status", "cutbacks", "peak_gamma", "peak_s12_over_G",
                    "s12_over_G_at_10", "max_err_to_closed_form_gamma_le_3"])
        for r in rows:
            gam, s12 = r["curve"]
            w.writerow([r["method"], r["column"], r["status"], r["cutbacks"],
                        "" if r["peak_gamma"] is None else f"{r['peak_gamma']:.4g}", f"{s12.max():.5g}",
                        f"{s12[-1]:.5g}", f"{r['err_to_gamma3']:.3g}"])


def _plot_shear_curves(path, rows):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np
    fig, ax = plt.subplots(figsize=(7.5, 4.8))
    g = np.linspace(0, SHEAR_GAMMA, 400)
    ax.plot(g, jaumann_shear(g), color="0.6", lw=5, alpha=0.6, label="Jaumann closed form: sin γ")
    ax.plot(g, green_naghdi_shear(g), color="#90caf9", lw=5, alpha=0.8,
            label="Green-Naghdi closed form (Dienes 1979)")
    styles = {"hughes_winget": "-", "sr": "--", "polar": "-", "neo_hooke": "-", "svk": "-"}
    for r in rows:
        if r["column"] == "0.1" and r["method"] in styles:
            gam, s12 = r["curve"]
            ax.plot(gam, s12, styles[r["method"]], lw=1.4, label=f"{r['method']} (dγ = 0.1)")
    ax.set(xlabel="shear γ", ylabel="σ12 / G", title="simple shear of a hypoelastic / hyperelastic block",
           ylim=(-1.5, 8))
    ax.axhline(0, color="grey", lw=0.5)
    ax.legend(fontsize=8, loc="upper left")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)

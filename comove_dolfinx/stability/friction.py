"""Frictional Hertz contact on the stability map: a half-cylinder pressed onto a rigid flat, then the
flat slides under it, through the public API, for each contact method and friction law at several
contact weights and increment counts (docs/stability.md).

The problem: the lower half of an elastic cylinder (R = 1, E = 1000, nu = 0.3, plane strain, P2,
element size 0.02 at the contact, 0.2 away from it) has its flat cut face held; the flat rises by
0.02 in 10 increments, then slides sideways by 0.05 in ``n_slide`` increments, mu = 0.3; everything
else at the defaults (the tangential weight gamma0_t = min(gamma0, 10), the line search). Each run
records the Newton iterations of the pressing and of the sliding increments, and Q / (mu P) at the
end (the friction force over mu times the normal force: 1 once the whole contact slides).
"""
from __future__ import annotations

import re
import time

from .causes import Recorder, classify
from .report import Panel, heatmap, write_csv

E, NU, R, MU = 1000.0, 0.3, 1.0, 0.3
DEPTH, DRAG, N_PRESS = 0.02, 0.05, 10
# (label, Contact's arguments, Newton's line search): the defaults but for what the label names;
# "γ0_t = γ0, Armijo" is the tangential weight and the line search that friction had before they
# became its defaults (docs/theory.md 6.3)
_OLD = {"gamma0_t": "gamma0"}
FRICTION_ROWS = (("penalty, frictionless", dict(method="penalty", mu=0.0), None),
                 ("penalty, lagged", dict(method="penalty"), None),
                 ("penalty, lagged + relag", dict(method="penalty", relag=True), None),
                 ("penalty, coulomb", dict(method="penalty", friction="coulomb"), None),
                 ("penalty, lagged, γ0_t = γ0, Armijo", dict(method="penalty", **_OLD), "residual"),
                 ("nitsche θ=0, frictionless", dict(method="nitsche", mu=0.0), None),
                 ("nitsche θ=0, lagged", dict(method="nitsche"), None),
                 ("nitsche θ=0, coulomb", dict(method="nitsche", friction="coulomb"), None),
                 ("nitsche θ=0, lagged, γ0_t = γ0, Armijo", dict(method="nitsche", **_OLD), "residual"),
                 ("nitsche θ=1, lagged", dict(method="nitsche", theta=1), None),
                 ("nitsche θ=1, coulomb", dict(method="nitsche", theta=1, friction="coulomb"), None),
                 ("nitsche θ=-1, lagged", dict(method="nitsche", theta=-1), None),
                 ("nitsche θ=-1, coulomb", dict(method="nitsche", theta=-1, friction="coulomb"), None))
FRICTION_GAMMA0 = (1.0, 10.0, 100.0, 1000.0)
FRICTION_SLIDES = (5, 10, 20, 40)
_MESHES: dict = {}


def hertz_slide(gamma0: float, n_slide: int, size_contact: float = 0.02, monitor=None,
                line_search=None, **contact):
    """The half-cylinder pressed by DEPTH in N_PRESS increments, then slid by DRAG in ``n_slide``;
    returns the Results (columns Q, P: the obstacle's force on the body along x and y).
    ``contact``: the Contact's arguments (method, theta, mu (default MU), friction, relag,
    gamma0_t; gamma0_t = "gamma0" takes gamma0); ``line_search``: Newton's (None: its default)."""
    from mpi4py import MPI

    import comove_dolfinx as cm
    md = _MESHES.get(size_contact)
    if md is None:
        md = _MESHES[size_contact] = cm.quarter_disc(R, 0.2, size_contact, 0.3, order=2, half=True,
                                                     comm=MPI.COMM_WORLD)
    flat = cm.Plane((0.0, 0.0), (0.0, 1.0),
                    motion=lambda f: (DRAG * max(f - 1.0, 0.0), DEPTH * min(f, 1.0)))
    contact = {"mu": MU, **contact}
    if contact.get("gamma0_t") == "gamma0":
        contact["gamma0_t"] = gamma0
    c = cm.Contact("contact", flat, gamma0=gamma0, **contact)
    probes = [cm.ContactForce(c, "Q", component=0), cm.ContactForce(c, "P", component=1)]
    job = cm.Job(cm.Body(md, "plane_strain", cm.Elastic(E, NU)), [cm.Fixed("top"), c],
                 [cm.Step(N_PRESS, ramp={c: 1.0}), cm.Step(n_slide, ramp={c: 2.0})], probes,
                 newton=cm.NewtonSettings(monitor=monitor, line_search=line_search))
    return job.run()


def friction_panels() -> list[Panel]:
    rows = [(label, []) for label, *_ in FRICTION_ROWS]
    return [Panel(f"Hertz slide (μ = {MU:g}): method and law x gamma0 (10 + 20 increments)",
                  rows, [(f"{g:g}", []) for g in FRICTION_GAMMA0], "gamma0"),
            Panel("Hertz slide: method and friction law x sliding increments (gamma0 = 100)",
                  rows, [(f"{n}", []) for n in FRICTION_SLIDES], "n_slide")]


def run_friction(out) -> list[dict]:
    """Every run of the two panels; friction.csv, friction.png and friction_detail.csv into ``out``."""
    import numpy as np
    rows = []
    cases = [(0, f"{g:g}", g, 20) for g in FRICTION_GAMMA0] + [(1, f"{n}", 100.0, n) for n in FRICTION_SLIDES]
    for panel, col, gamma0, n_slide in cases:
        for label, contact, line_search in FRICTION_ROWS:
            mu = contact.get("mu", MU)
            rec = Recorder()
            cpu0 = time.process_time()
            res = hertz_slide(gamma0, n_slide, monitor=rec, line_search=line_search, **contact)
            cpu = time.process_time() - cpu0
            cut = sum(i.cutbacks for i in res.increments)
            m = re.search(r"after (\d+) cut-backs in a row", res.message)
            cut += int(m.group(1)) if (m and not res.completed) else 0
            status = "failed" if not res.completed else ("cutbacks" if cut else "converged")
            its = np.array(res.newton_its, dtype=float)
            t = np.array([row["time"] for row in res.rows])       # 0 to 1 pressing, 1 to 2 sliding
            press, slide = its[t <= 1.0 + 1e-12], its[t > 1.0 + 1e-12]
            last = res.last
            ratio = abs(last["Q"]) / (mu * last["P"]) if (mu and res.completed) else float("nan")
            rows.append({"scene": "friction", "panel": panel, "method": label, "column": col,
                         "sets": " ".join(f"{k}={v}" for k, v in contact.items()) +
                                 f" gamma0={gamma0:g} n_slide={n_slide} line_search={line_search}",
                         "n_increments": N_PRESS + n_slide, "gamma0": gamma0, "max_cutbacks": 6,
                         "status": status, "cutbacks": cut,
                         "load_reached": float(last.get("load", 0.0)) if last else 0.0, "load_max": 2.0,
                         "cause": "" if res.completed else classify(res.message, rec.nan_diagnosis,
                                                                    rec.last_failed_chatter),
                         "newton_its": rec.total_its, "failed_its": rec.total_its - sum(res.newton_its),
                         "increments": len(res.increments), "cpu_s": round(cpu, 2), "wall_s": "",
                         "result": ratio, "max_penetration": "", "penetration_per_h": "",
                         "chatter_solves": rec.chatter_solves, "max_omega2": "",
                         "message": "" if res.completed else res.message,
                         "press_its": float(press.mean()) if press.size else float("nan"),
                         "slide_its": float(slide.mean()) if slide.size else float("nan")})
            r = rows[-1]
            print(f"friction {label:40s} {col:>6s} {status:9s} cut {cut:2d} its {rec.total_its:4d} "
                  f"press {r['press_its']:.2f} slide {r['slide_its']:.2f} Q/muP {ratio:.6f} "
                  f"{r['cause']} cpu {cpu:.1f} s", flush=True)
    write_csv(out / "friction.csv", rows)
    _write_detail(out, rows)
    heatmap(out / "friction.png", rows, friction_panels())
    return rows


def _write_detail(out, rows):
    """Per run: Newton iterations per increment while pressing and while sliding, and Q / (mu P)."""
    from ..io.csv_tables import write_table
    fields = ["panel", "method", "column", "status", "cutbacks", "press_its", "slide_its", "newton_its",
              "Q_over_muP", "cpu_s"]
    write_table(out / "friction_detail.csv",
                [{"panel": r["panel"], "method": r["method"], "column": r["column"], "status": r["status"],
                  "cutbacks": r["cutbacks"], "press_its": f"{r['press_its']:.2f}",
                  "slide_its": f"{r['slide_its']:.2f}", "newton_its": r["newton_its"],
                  "Q_over_muP": f"{r['result']:.6g}", "cpu_s": r["cpu_s"]} for r in rows], fields)

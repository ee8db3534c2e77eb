"""The stability map: where each scene's methods converge, need cut-backs, or fail, and why.

    python -m comove_dolfinx.stability elastica --out results/stability   # one scene
    python -m comove_dolfinx.stability shear --out results/stability      # Jaumann simple shear
    python -m comove_dolfinx.stability all --out results/stability        # everything, 2 at a time

For each scene the grid runs the scene with one parameter changed per row (stress update, contact
method and Nitsche variant, plasticity law) and one per column (nominal increments ``n_steps`` or the
contact weight ``gamma0``), with the scene's cut-backs allowed unless the row says otherwise, and
classifies each run:

* ``converged``: every increment converged at its nominal size;
* ``cutbacks``: the run reached the end, but some increments had to be halved (column ``cutbacks``);
* ``failed``: an increment of the smallest size failed; ``load_reached`` is the load level of the last
  converged increment and ``cause`` the class of the last failure (:func:`classify`).

Causes come from the increment loop's failure message (solver/increments.py, newton.py,
mechanics/state.py), sharpened by two instruments this module attaches to the running solver for
the duration of a run (it wraps methods of the Newton and Model classes and restores them after):

* when the stress update returns NaN, the failing iterate is examined: the S-R split of an
  increment ``dF = F F_n^-1`` exists only while sin^2(theta) = omega^2 <= 1, omega = (dF21 - dF12)/2
  (docs/theory.md 2.3), so omega^2 > 1 somewhere means "S-R split beyond 90 degrees"; an in-plane
  det F <= 0 means an inverted element (the plane-stress thickness law takes a power of it and
  returns NaN before det F is checked); anything else stays "NaN in the stress update";
* at every Newton iteration (the accepted iterate, not the line search's trials) the active contact
  set is recorded: the contact boundary's nodes with a negative gap to the obstacle (for Nitsche the
  pressure also depends on the traction, so the gap is a proxy). A Newton solve that fails while
  this set keeps changing and comes back to a set it had left (a cycle) is "contact chatter".

Outputs in --out: ``<scene>.csv`` (one row per run), ``<scene>.png`` (heat maps: rows methods,
columns increments or gamma0; the cause written in failed cells) and ``stability.md`` (the breaking
points with their numbers, rebuilt from every CSV in the folder). Each run's history.csv and
run.json go to out/runs/<scene>/<tag>/. CPU seconds are this process's, run by run (compilation
included when a run meets a new kind of model). docs/stability.md explains the cases.
"""
from __future__ import annotations

import argparse
import contextlib
import csv
import dataclasses
import logging
import math
import pathlib
import re
import subprocess
import sys
import time

# --------------------------------------------------------------------------------------------------
# Causes
# --------------------------------------------------------------------------------------------------
SR_RANGE = "S-R split beyond 90 deg"
INVERTED = "inverted element"
NAN = "NaN in the stress update"
RETURN_MAP = "return map failed"
NO_CONVERGENCE = "Newton: no convergence"
DIVERGED = "Newton: diverged"
LINEAR = "linear solve failed"
CHATTER = "contact chatter"
OTHER = "other"
CAUSES = (SR_RANGE, INVERTED, NAN, RETURN_MAP, NO_CONVERGENCE, DIVERGED, LINEAR, CHATTER, OTHER)

SHORT = {SR_RANGE: "S-R > 90°", INVERTED: "det F ≤ 0", NAN: "NaN", RETURN_MAP: "return map",
         NO_CONVERGENCE: "no conv.", DIVERGED: "diverged", LINEAR: "lin. solve", CHATTER: "chatter",
         OTHER: "other"}


def classify(message: str, nan_diagnosis: str | None = None, chatter: bool = False) -> str:
    """The cause of a failed run from the increment loop's message (the reason of its last failed
    attempt is at the end of it). ``nan_diagnosis``: what the failing iterate showed when the update
    returned NaN (SR_RANGE, INVERTED or None); ``chatter``: whether the last failed Newton solve
    cycled through contact sets (then a Newton failure is put down to chatter)."""
    text = message.lower()
    if "returned nan" in text:
        return nan_diagnosis if nan_diagnosis in (SR_RANGE, INVERTED) else NAN
    if "det f" in text or "folds" in text:
        return INVERTED
    if "s-r" in text and ("90" in text or "range" in text):
        return SR_RANGE
    if "constitutive update failed" in text or "return map" in text or "return mapping" in text:
        return RETURN_MAP
    if "linear solve" in text or "not finite" in text or "linear solver" in text:
        return LINEAR
    if "no convergence" in text:
        return CHATTER if chatter else NO_CONVERGENCE
    if "diverged" in text:
        return CHATTER if chatter else DIVERGED
    return OTHER


def is_cycling(sets: list, window: int = 6) -> bool:
    """Whether a sequence of active contact sets (hashable, one per Newton iteration) chatters:
    within its last ``window`` entries the set changes at least three times and comes back to a
    set it had left (A -> B -> A)."""
    tail = sets[-window:]
    changes = sum(1 for a, b in zip(tail, tail[1:]) if a != b)
    revisit = any(tail[k] == tail[j] and any(tail[i] != tail[j] for i in range(j + 1, k))
                  for j in range(len(tail)) for k in range(j + 2, len(tail)))
    return changes >= 3 and revisit


# --------------------------------------------------------------------------------------------------
# Instruments: what the failing iterate and the Newton iterations show
# --------------------------------------------------------------------------------------------------
class Recorder:
    """What the instruments saw during one run."""

    def __init__(self):
        self.nan_diagnosis: str | None = None      # of the last NaN of the stress update
        self.max_omega2 = 0.0                     # sin^2 of the increment's S-R angle there
        self.sets: list = []                      # active contact sets of the current Newton solve
        self.last_failed_chatter = False
        self.last_failed_changes = 0              # active-set changes in the last failed solve
        self.chatter_solves = 0                   # failed Newton solves that cycled
        self.failed_solves = 0
        self.total_its = 0                        # Newton iterations of every solve, failed ones too


def _diagnose_nan(model, rec: Recorder) -> None:
    """At an iterate whose stress update returned NaN: the largest omega^2 of the increment and the
    smallest in-plane det F at the quadrature points."""
    import numpy as np
    import ufl
    from mpi4py import MPI

    from . import compat
    exprs = getattr(model, "_stability_exprs", None)
    if exprs is None:
        F = ufl.Identity(2) + ufl.grad(model.u)
        Fn = ufl.Identity(2) + ufl.grad(model.u_n)
        dF = F * ufl.inv(Fn)
        omega = 0.5 * (dF[1, 0] - dF[0, 1])
        pts = model.rule.points
        exprs = (compat.expression(omega * omega, pts), compat.expression(ufl.det(F), pts))
        model._stability_exprs = exprs
    w2 = compat.evaluate(exprs[0], model.mesh, model.rule.cells)
    det = compat.evaluate(exprs[1], model.mesh, model.rule.cells)
    w2 = w2[np.isfinite(w2)]                   # (an iterate that is NaN itself tells nothing)
    det = det[np.isfinite(det)]
    w2max = model.comm.allreduce(float(w2.max()) if w2.size else 0.0, op=MPI.MAX)
    detmin = model.comm.allreduce(float(det.min()) if det.size else 1.0, op=MPI.MIN)
    rec.max_omega2 = w2max
    if w2max > 1.0 and model.body.update == "sr":
        rec.nan_diagnosis = SR_RANGE
    elif detmin <= 0.0:
        rec.nan_diagnosis = INVERTED
    else:
        rec.nan_diagnosis = None


def _active_set(model):
    """The contact boundaries' nodes with a negative gap, as a hashable tuple (empty without contact)."""
    import numpy as np
    out = []
    X = None
    for item in model.items:
        if getattr(item, "kind", "") != "contact":
            continue
        if X is None:
            X = model.V.tabulate_dof_coordinates()[:, :2]
        nodes = item.nodes
        x = X[nodes] + model.u.x.array.reshape(-1, 2)[nodes]
        g = item.obstacle.gap_np(x, item.obstacle.displacement(item.factor))
        out.append(tuple(np.flatnonzero(g < 0.0)))
    return tuple(out)


@contextlib.contextmanager
def instruments(rec: Recorder):
    """Wrap Model.evaluate_stress (NaN diagnosis) and Newton._converged / Newton.solve (the active
    contact set at each iteration) for the duration of the block; restored after."""
    from .mechanics.model import Model
    from .mechanics.state import ReturnMapFailure
    from .solver.newton import Newton
    orig_eval, orig_conv, orig_solve = Model.evaluate_stress, Newton._converged, Newton.solve

    def evaluate_stress(self):
        try:
            return orig_eval(self)
        except ReturnMapFailure as err:
            if "nan" in str(err).lower():
                try:
                    _diagnose_nan(self, rec)
                except Exception:              # noqa: BLE001 - a diagnosis must not change the run
                    rec.nan_diagnosis = None
            raise

    def converged(self, rnorm):
        if any(getattr(i, "kind", "") == "contact" for i in self.model.items):
            rec.sets.append(_active_set(self.model))
        return orig_conv(self, rnorm)

    def solve(self):
        rec.sets = []
        ok, its, reason = orig_solve(self)
        rec.total_its += its
        if not ok:
            rec.failed_solves += 1
            rec.last_failed_chatter = is_cycling(rec.sets)
            rec.last_failed_changes = sum(1 for a, b in zip(rec.sets, rec.sets[1:]) if a != b)
            rec.chatter_solves += int(rec.last_failed_chatter)
        return ok, its, reason

    Model.evaluate_stress, Newton._converged, Newton.solve = evaluate_stress, converged, solve
    try:
        yield rec
    finally:
        Model.evaluate_stress, Newton._converged, Newton.solve = orig_eval, orig_conv, orig_solve


# --------------------------------------------------------------------------------------------------
# One run
# --------------------------------------------------------------------------------------------------
_MESHES: dict = {}
RESULT_LABEL = {"elastica": "tip v", "beam": "tip v", "plate": "w0", "ring": "P"}
RESULT = {"elastica": ("tip_uy", -1.0), "beam": ("tip_uy", -1.0), "plate": ("center_uz", -1.0),
          "ring": ("force", 1.0)}


def _mesh(scene, comm):
    key = (scene.name, scene.size, scene.geometry_order, scene.mesh,
           getattr(scene, "L", None), getattr(scene, "h", None))
    if key not in _MESHES:
        _MESHES[key] = scene.mesh_data(comm)
    return _MESHES[key]


def run_case(name: str, sets: list[str], folder: pathlib.Path) -> dict:
    """Run scene ``name`` with ``--set`` overrides into ``folder`` (history.csv, run.json) and
    classify the outcome."""
    from mpi4py import MPI

    from .io import HistoryCSV, RunInfo
    from .presets import get_scene
    comm = MPI.COMM_WORLD
    scene = get_scene(name, sets)
    folder.mkdir(parents=True, exist_ok=True)
    rec = Recorder()
    cpu0, wall0 = time.process_time(), time.perf_counter()
    error = None
    with instruments(rec):
        try:
            md = _mesh(scene, comm)
            writers = [HistoryCSV(folder / "history.csv"),
                       RunInfo(folder / "run.json", {"scene": scene.name, **dataclasses.asdict(scene)})]
            res = scene.job(md, writers).run()
        except Exception as err:               # noqa: BLE001 - a run that cannot start is a failure
            res, error = None, f"{type(err).__name__}: {err}"
    cpu = time.process_time() - cpu0
    key, sign = RESULT[name]
    row = {"n_steps": scene.n_steps, "gamma0": getattr(scene, "gamma0", ""),
           "max_cutbacks": scene.max_cutbacks, "cpu_s": round(cpu, 2),
           "wall_s": round(time.perf_counter() - wall0, 2), "chatter_solves": rec.chatter_solves,
           "set_changes_last_fail": rec.last_failed_changes if rec.failed_solves else ""}
    if res is None:
        return {**row, "status": "failed", "cutbacks": 0, "load_reached": 0.0, "load_max": scene.load_max,
                "cause": OTHER, "message": error, "newton_its": 0, "failed_its": 0, "increments": 0,
                "result": float("nan"), "max_penetration": float("nan"), "penetration_per_h": float("nan"),
                "max_omega2": rec.max_omega2}
    cutbacks = sum(inc.cutbacks for inc in res.increments)
    m = re.search(r"after (\d+) cut-backs in a row", res.message)
    if not res.completed and m:
        cutbacks += int(m.group(1))             # the halvings of the increment that failed for good
    status = "failed" if not res.completed else ("cutbacks" if cutbacks else "converged")
    pen = res.contact.get("max_penetration", float("nan")) if res.contact else float("nan")
    last = res.last
    return {**row, "status": status, "cutbacks": cutbacks,
            "load_reached": float(last.get("load", 0.0)), "load_max": scene.load_max,
            "cause": "" if res.completed else classify(res.message, rec.nan_diagnosis, rec.last_failed_chatter),
            "message": "" if res.completed else res.message,
            "newton_its": rec.total_its, "failed_its": rec.total_its - sum(res.newton_its),
            "increments": len(res.increments),
            "result": sign * float(last[key]) if key in last else float("nan"),
            "max_penetration": pen,
            "penetration_per_h": pen / scene.size if math.isfinite(pen) else float("nan"),
            "max_omega2": rec.max_omega2}


# --------------------------------------------------------------------------------------------------
# The grids
# --------------------------------------------------------------------------------------------------
@dataclasses.dataclass
class Panel:
    """One heat map: rows (label, --set list), columns (label, --set list), what the columns vary."""

    title: str
    rows: list
    columns: list
    column_name: str


UPDATES = ("sr", "hughes_winget", "polar", "svk", "neo_hooke")
ELASTICA_LAMS = (5, 10, 20, 30, 32, 34, 40, 80)
CONTACTS = (("penalty", ["contact=penalty"]), ("nitsche θ=1", ["contact=nitsche", "theta=1"]),
            ("nitsche θ=0", ["contact=nitsche", "theta=0"]), ("nitsche θ=-1", ["contact=nitsche", "theta=-1"]))
GAMMA0 = {"beam": (0.01, 0.1, 1.0, 10.0, 100.0, 1000.0), "plate": (0.01, 0.1, 1.0, 10.0, 100.0, 1000.0),
          "ring": (0.01, 0.1, 1.0, 10.0, 100.0)}


def _steps(values):
    return [(str(n), [f"n_steps={n}"]) for n in values]


def panels(scene: str) -> list[Panel]:
    """The grid of a scene."""
    if scene == "elastica":
        steps = _steps((1, 2, 3, 4, 5, 10))
        return [Panel("elastica lam = 5: stress update x increments (cut-backs allowed)",
                      [(u, [f"update={u}"]) for u in UPDATES], steps, "n_steps"),
                Panel("elastica lam = 5: no cut-backs (max_cutbacks = 0)",
                      [(u, [f"update={u}", "max_cutbacks=0"]) for u in UPDATES], steps, "n_steps"),
                Panel("elastica: the whole load in one increment, no cut-backs: final load lam",
                      [(u, [f"update={u}", "n_steps=1", "max_cutbacks=0"]) for u in UPDATES],
                      [(f"{lam:g}", [f"lam={lam:g}"]) for lam in ELASTICA_LAMS], "lam")]
    if scene in ("beam", "plate"):
        return [Panel(f"{scene}: contact method x gamma0 (20 increments)", list(CONTACTS),
                      [(f"{g:g}", [f"gamma0={g:g}"]) for g in GAMMA0[scene]], "gamma0"),
                Panel(f"{scene}: stress update x increments (penalty, gamma0 = 100)",
                      [(u, [f"update={u}"]) for u in UPDATES], _steps((2, 5, 10, 20)), "n_steps")]
    if scene == "ring":
        rows = [(f"{law} {u}", [f"law={law}", f"update={u}"]) for law in ("j2", "chen")
                for u in ("sr", "hughes_winget")]
        return [Panel("ring: plasticity law and update x increments (penalty, gamma0 = 1)", rows,
                      _steps((1, 3, 6, 9, 12, 18, 36)), "n_steps"),
                Panel("ring: contact method x gamma0 (36 increments, J2)", list(CONTACTS),
                      [(f"{g:g}", [f"gamma0={g:g}"]) for g in GAMMA0["ring"]], "gamma0")]
    raise ValueError(f"unknown scene {scene!r}")


def _tag(sets: list[str]) -> str:
    return "_".join(s.replace("=", "") for s in sets).replace("-", "m") or "default"


FIELDS = ["scene", "panel", "method", "column", "sets", "n_steps", "gamma0", "max_cutbacks", "status",
          "cutbacks", "load_reached", "load_max", "cause", "newton_its", "failed_its", "increments",
          "cpu_s", "wall_s", "result", "max_penetration", "penetration_per_h", "chatter_solves",
          "set_changes_last_fail", "peak_gamma",
          "max_omega2", "message"]


def run_scene_grid(scene: str, out: pathlib.Path) -> list[dict]:
    """Every run of a scene's grid; the CSV and heat map into ``out``."""
    rows = []
    for k, panel in enumerate(panels(scene)):
        for label, rsets in panel.rows:
            for col, csets in panel.columns:
                sets = rsets + csets
                r = run_case(scene, sets, out / "runs" / scene / _tag(sets))
                rows.append({"scene": scene, "panel": k, "method": label, "column": col,
                             "sets": " ".join(sets), **r})
                print(f"{scene:8s} {label:22s} {panel.column_name}={col:6s} {r['status']:9s} "
                      f"cut {r['cutbacks']:2d} load {r['load_reached']:.4g}/{r['load_max']:.4g} "
                      f"{r['cause']:24s} cpu {r['cpu_s']:.1f} s", flush=True)
    write_csv(out / f"{scene}.csv", rows)
    heatmap(out / f"{scene}.png", rows, panels(scene))
    return rows


def write_csv(path: pathlib.Path, rows: list[dict]) -> None:
    with open(path, "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=FIELDS, extrasaction="ignore")
        w.writeheader()
        for r in rows:
            w.writerow({k: (f"{v:.6g}" if isinstance(v, float) else v) for k, v in r.items()})


def read_csv(path: pathlib.Path) -> list[dict]:
    with open(path) as fh:
        return list(csv.DictReader(fh))


# --------------------------------------------------------------------------------------------------
# Jaumann simple shear (public API)
# --------------------------------------------------------------------------------------------------
SHEAR_ROWS = (("hughes_winget", "hughes_winget", 6), ("sr", "sr", 6), ("sr, no cut-backs", "sr", 0),
              ("polar", "polar", 6), ("neo_hooke", "neo_hooke", 6), ("svk", "svk", 6))
SHEAR_DGAMMA = (0.02, 0.1, 0.5, 1.0, 2.5)
SHEAR_GAMMA = 10.0


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
                 nu: float = 0.3, size: float = 1.0):
    """A unit square in homogeneous simple shear x = X + gamma t Y (every boundary node prescribed)
    in n equal increments; returns the Results (columns gamma, s12, s11 = stresses / G, the mean
    over the quadrature points)."""
    import comove_dolfinx as cm
    from mpi4py import MPI
    E = 2.0 * G * (1.0 + nu)
    md = _MESHES.get(("shear", size))
    if md is None:
        md = _MESHES[("shear", size)] = cm.rectangle(1.0, 1.0, size, order=1, comm=MPI.COMM_WORLD)

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
    job = cm.Job(body, items, [cm.Step(n, max_cutbacks=max_cutbacks)], probes,
                 load=lambda t: gamma * t)
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
            with instruments(rec):
                res = simple_shear(u, SHEAR_GAMMA, n, max_cutbacks=max_cut)
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
                         "sets": f"update={u} dgamma={dg:g}", "n_steps": n, "gamma0": "",
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


def replot(out: pathlib.Path) -> None:
    """The heat maps again from the CSV files in ``out`` (no runs)."""
    for scene in ("elastica", "beam", "plate", "ring", "shear"):
        path = out / f"{scene}.csv"
        if path.exists():
            heatmap(out / f"{scene}.png", read_csv(path), shear_panels() if scene == "shear" else panels(scene))


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


# --------------------------------------------------------------------------------------------------
# Heat maps
# --------------------------------------------------------------------------------------------------
COLOURS = {"converged": "#4caf50", "cutbacks": "#ffc107", "failed": "#e53935", "": "#bdbdbd"}


def _cell_text(r: dict) -> str:
    cut = int(float(r["cutbacks"] or 0))
    if r["status"] == "failed":
        cause = str(r["cause"])
        if cause.startswith("non-monotone"):
            return (f"oscillates:\ns12 peaks at\nγ = {_f(r.get('peak_gamma')):.3g}" +
                    (f"\n({cut} cut)" if cut else ""))
        return f"{SHORT.get(cause, cause)}\nat {float(r['load_reached']):.3g}/{float(r['load_max']):.3g}"
    its = int(float(r["newton_its"] or 0))
    text = (f"ok, {its} its" if r["status"] == "converged" else f"{cut} cut, {its} its")
    pen = _f(r.get("penetration_per_h"))
    if math.isfinite(pen):
        text += f"\npen {pen:.2g} h"
    label = RESULT_LABEL.get(r.get("scene", ""))
    if label and math.isfinite(_f(r.get("result"))):
        text += f"\n{label} {_f(r['result']):.4g}"
    return text


def heatmap(path: pathlib.Path, rows: list[dict], panel_list: list[Panel]) -> None:
    """One panel per Panel: rows methods, columns its values, coloured by status, text inside."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.patches import Patch, Rectangle
    heights = [len(p.rows) + 1.6 for p in panel_list]
    width = max(len(p.columns) for p in panel_list)
    fig, axes = plt.subplots(len(panel_list), 1, figsize=(2.2 + 1.45 * width, 0.62 * sum(heights) + 0.8),
                             gridspec_kw={"height_ratios": heights}, squeeze=False)
    for k, (ax, p) in enumerate(zip(axes[:, 0], panel_list)):
        cells = {(r["method"], r["column"]): r for r in rows if int(r["panel"]) == k}
        for i, (label, _) in enumerate(p.rows):
            for j, (col, _) in enumerate(p.columns):
                r = cells.get((label, col))
                status = r["status"] if r else ""
                ax.add_patch(Rectangle((j, i), 1, 1, facecolor=COLOURS[status], edgecolor="white", lw=2))
                ax.text(j + 0.5, i + 0.5, _cell_text(r) if r else "not run", ha="center", va="center",
                        fontsize=8.5)
        ax.set_xlim(0, len(p.columns))
        ax.set_ylim(len(p.rows), 0)
        ax.set_xticks([j + 0.5 for j in range(len(p.columns))], [c for c, _ in p.columns])
        ax.set_yticks([i + 0.5 for i in range(len(p.rows))], [lab for lab, _ in p.rows])
        ax.set_xlabel(p.column_name)
        ax.set_title(p.title, fontsize=9.5)
        ax.tick_params(length=0)
        for s in ax.spines.values():
            s.set_visible(False)
    handles = [Patch(color=COLOURS[s], label=lab) for s, lab in
               (("converged", "converged"), ("cutbacks", "converged with cut-backs"), ("failed", "failed"))]
    fig.legend(handles=handles, loc="lower center", ncol=3, fontsize=8, frameon=False)
    fig.tight_layout(rect=(0, 0.04, 1, 1))
    fig.savefig(path, dpi=130)
    plt.close(fig)


# --------------------------------------------------------------------------------------------------
# The summary
# --------------------------------------------------------------------------------------------------
def _f(x) -> float:
    try:
        return float(x)
    except (TypeError, ValueError):
        return float("nan")


def summary(out: pathlib.Path) -> str:
    """stability.md from every scene CSV in ``out``: per row of each grid, where it fails or needs
    cut-backs, and the specific breaking points."""
    lines = ["# Stability map", "",
             "Generated by `python -m comove_dolfinx.stability` from the CSV files in this folder "
             "(docs/stability.md explains the cases). Load levels are the scene's `load` column "
             "(elastica lam, beam q, plate p, ring delta, shear gamma).", ""]
    for scene in ("elastica", "beam", "plate", "ring", "shear"):
        path = out / f"{scene}.csv"
        if not path.exists():
            continue
        rows = read_csv(path)
        lines += [f"## {scene}", "", f"Heat map: `{scene}.png`; runs: `{scene}.csv`.", ""]
        plist = shear_panels() if scene == "shear" else panels(scene)
        for k, panel in enumerate(plist):
            lines += [f"### {panel.title}", ""]
            what = panel.column_name
            for method, _ in panel.rows:
                rs = [r for r in rows if int(r["panel"]) == k and r["method"] == method]
                if not rs:
                    continue
                fails = [f"{what} {r['column']}: {r['cause']}" +
                         ("" if scene == "shear" else
                          f" at load {_f(r['load_reached']):.4g} of {_f(r['load_max']):.4g}")
                         for r in rs if r["status"] == "failed"]
                cuts = [f"{r['column']} ({r['cutbacks']})" for r in rs if r["status"] == "cutbacks"]
                text = f"- **{method}**: "
                text += ("fails at " + "; ".join(fails)) if fails else "no failure"
                if cuts:
                    text += f". Cut-backs (count) at {what} " + ", ".join(cuts)
                pens = [(r["column"], _f(r["penetration_per_h"])) for r in rs
                        if r["status"] != "failed" and math.isfinite(_f(r["penetration_per_h"]))]
                if pens and what == "gamma0":
                    text += ". Largest penetration / h: " + ", ".join(f"{c}: {p:.3g}" for c, p in pens)
                lines.append(text + ".")
            lines.append("")
        lines.append("")
        lines += _specific(scene, rows)
    text = "\n".join(lines) + "\n"
    (out / "stability.md").write_text(text)
    return text


def _specific(scene: str, rows: list[dict]) -> list[str]:
    out = []
    if scene == "ring":
        ref = {(r["method"].split()[1], r["column"]): _f(r["result"]) for r in rows
               if r["method"].startswith("j2 ") and r["status"] != "failed"}
        devs = []
        for r in rows:
            key = (r["method"].split()[-1], r["column"])
            if r["method"].startswith("chen ") and key in ref and r["status"] != "failed":
                devs.append(f"{r['method']}, n_steps {r['column']}: P(6.6) = {_f(r['result']):.5g} "
                            f"({100 * (_f(r['result']) / ref[key] - 1):+.3f} % against j2 {key[0]}; "
                            f"{r['cutbacks']} cut-backs)")
        if devs:
            out += ["Chen's law against J2 (same update, same increments; P = force at the end of the "
                    "crush):", ""] + [f"- {d}" for d in devs] + [""]
    if scene == "shear":
        out += ["Peak of the shear stress (where it first falls) and the distance from the closed form "
                "up to gamma = 3 are in `shear_detail.csv`; the curves at dgamma = 0.1 in "
                "`shear_curves.png`.", ""]
    return out


# --------------------------------------------------------------------------------------------------
def main(argv=None) -> int:
    p = argparse.ArgumentParser(prog="python -m comove_dolfinx.stability", description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("scene", choices=["elastica", "beam", "plate", "ring", "shear", "all", "replot"],
                   help="a scene, the shear case, all of them, or replot (heat maps and summary "
                   "again from the CSV files)")
    p.add_argument("--out", default="results/stability")
    p.add_argument("--jobs", type=int, default=2, help="scenes at a time with 'all' (default 2)")
    args = p.parse_args(argv)
    out = pathlib.Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    if args.scene == "replot":
        replot(out)
        summary(out)
        return 0
    if args.scene == "all":
        todo = ["elastica", "beam", "plate", "ring", "shear"]
        running: list = []
        while todo or running:
            while todo and len(running) < max(args.jobs, 1):
                s = todo.pop(0)
                running.append(subprocess.Popen([sys.executable, "-m", "comove_dolfinx.stability", s,
                                                 "--out", str(out)]))
            for proc in list(running):
                if proc.poll() is not None:
                    running.remove(proc)
            time.sleep(0.5)
        summary(out)
        return 0
    import os
    os.environ.setdefault("PETSC_OPTIONS", "-no_signal_handler")
    logging.disable(logging.INFO)
    if args.scene == "shear":
        run_shear(out)
    else:
        run_scene_grid(args.scene, out)
    summary(out)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

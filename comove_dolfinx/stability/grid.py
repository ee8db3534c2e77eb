"""The scenes' grids: one parameter changed per row (stress update, contact method and Nitsche
variant, plasticity law), one per column (nominal increments ``n_increments`` or the contact weight
``gamma0``); each cell one run of the scene, classified."""
from __future__ import annotations

import dataclasses
import math
import pathlib
import re
import time

from .causes import OTHER, Recorder, classify
from .report import Panel, heatmap, write_csv
from .shear import shear_panels

UPDATES = ("sr", "hughes_winget", "polar", "svk", "neo_hooke")
ELASTICA_LAMS = (5, 10, 20, 30, 32, 34, 40, 80)
CONTACTS = (("penalty", ["contact=penalty"]), ("nitsche θ=1", ["contact=nitsche", "theta=1"]),
            ("nitsche θ=0", ["contact=nitsche", "theta=0"]), ("nitsche θ=-1", ["contact=nitsche", "theta=-1"]))
GAMMA0 = {"beam": (0.01, 0.1, 1.0, 10.0, 100.0, 1000.0), "plate": (0.01, 0.1, 1.0, 10.0, 100.0, 1000.0),
          "ring": (0.01, 0.1, 1.0, 10.0, 100.0)}
RESULT = {"elastica": ("tip_uy", -1.0), "beam": ("tip_uy", -1.0), "plate": ("center_uz", -1.0),
          "ring": ("force", 1.0)}
_MESHES: dict = {}


def _steps(values):
    return [(str(n), [f"n_increments={n}"]) for n in values]


def panels(scene: str) -> list[Panel]:
    """The grid of a scene."""
    if scene == "elastica":
        steps = _steps((1, 2, 3, 4, 5, 10))
        return [Panel("elastica lam = 5: stress update x increments (cut-backs allowed)",
                      [(u, [f"update={u}"]) for u in UPDATES], steps, "n_increments"),
                Panel("elastica lam = 5: no cut-backs (max_cutbacks = 0)",
                      [(u, [f"update={u}", "max_cutbacks=0"]) for u in UPDATES], steps, "n_increments"),
                Panel("elastica: the whole load in one increment, no cut-backs: final load lam",
                      [(u, [f"update={u}", "n_increments=1", "max_cutbacks=0"]) for u in UPDATES],
                      [(f"{lam:g}", [f"lam={lam:g}"]) for lam in ELASTICA_LAMS], "lam")]
    if scene in ("beam", "plate"):
        return [Panel(f"{scene}: contact method x gamma0 (20 increments)", list(CONTACTS),
                      [(f"{g:g}", [f"gamma0={g:g}"]) for g in GAMMA0[scene]], "gamma0"),
                Panel(f"{scene}: stress update x increments (penalty, gamma0 = 100)",
                      [(u, [f"update={u}"]) for u in UPDATES], _steps((2, 5, 10, 20)), "n_increments")]
    if scene == "ring":
        rows = [(f"{law} {u}", [f"law={law}", f"update={u}"]) for law in ("j2", "chen")
                for u in ("sr", "hughes_winget")]
        return [Panel("ring: plasticity law and update x increments (penalty, gamma0 = 1)", rows,
                      _steps((1, 3, 6, 9, 12, 18, 36)), "n_increments"),
                Panel("ring: contact method x gamma0 (36 increments, J2)", list(CONTACTS),
                      [(f"{g:g}", [f"gamma0={g:g}"]) for g in GAMMA0["ring"]], "gamma0")]
    raise ValueError(f"unknown scene {scene!r}")


def panels_of(scene: str) -> list[Panel]:
    """The panels of a scene, of the shear case or of the friction case."""
    if scene == "friction":
        from .friction import friction_panels
        return friction_panels()
    return shear_panels() if scene == "shear" else panels(scene)


def _tag(sets: list[str]) -> str:
    return "_".join(s.replace("=", "") for s in sets).replace("-", "m") or "default"


def _mesh(scene, comm):
    key = (scene.name, scene.size, scene.geometry_order, scene.mesh,
           getattr(scene, "L", None), getattr(scene, "h", None))
    if key not in _MESHES:
        _MESHES[key] = scene.mesh_data(comm)
    return _MESHES[key]


def run_case(name: str, sets: list[str], folder: pathlib.Path) -> dict:
    """Run scene ``name`` with ``--set`` overrides into ``folder`` (history.csv, run.json) and
    classify the outcome; Newton reports to a :class:`Recorder` through its settings' monitor."""
    from mpi4py import MPI

    from ..io import HistoryCSV, RunInfo
    from ..presets import get_scene
    comm = MPI.COMM_WORLD
    scene = get_scene(name, sets)
    folder.mkdir(parents=True, exist_ok=True)
    rec = Recorder()
    cpu0, wall0 = time.process_time(), time.perf_counter()
    error = None
    try:
        md = _mesh(scene, comm)
        writers = [HistoryCSV(folder / "history.csv"),
                   RunInfo(folder / "run.json", {"scene": scene.name, **dataclasses.asdict(scene)})]
        job = scene.job(md, writers)
        job.newton = dataclasses.replace(job.newton, monitor=rec)
        res = job.run()
    except Exception as err:                   # noqa: BLE001 - a run that cannot start is a failure
        res, error = None, f"{type(err).__name__}: {err}"
    cpu = time.process_time() - cpu0
    key, sign = RESULT[name]
    row = {"n_increments": scene.n_increments, "gamma0": getattr(scene, "gamma0", ""),
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

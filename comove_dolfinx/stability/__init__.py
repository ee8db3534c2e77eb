"""The stability map: where each scene's methods converge, need cut-backs, or fail, and why.

    python -m comove_dolfinx.stability elastica --out results/stability   # one scene
    python -m comove_dolfinx.stability shear --out results/stability      # Jaumann simple shear
    python -m comove_dolfinx.stability friction --out results/stability   # frictional Hertz slide
    python -m comove_dolfinx.stability all --out results/stability        # everything, 2 at a time

For each scene the grid runs the scene with one parameter changed per row (stress update, contact
method and Nitsche variant, plasticity law) and one per column (nominal increments ``n_increments`` or the
contact weight ``gamma0``), with the scene's cut-backs allowed unless the row says otherwise, and
classifies each run:

* ``converged``: no increment had to be halved (a scene may start at a smaller first increment);
* ``cutbacks``: the run reached the end, but some increments had to be halved (column ``cutbacks``);
* ``failed``: an increment of the smallest size failed; ``load_reached`` is the load level of the last
  converged increment and ``cause`` the class of the last failure (:func:`classify`).

Causes come from the increment loop's failure message (solver/increments.py, newton.py,
mechanics/state.py), sharpened by what a :class:`Recorder` sees as the monitor of the run's Newton
solver (``NewtonSettings.monitor``):

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

The friction case (friction.py) presses a half-cylinder onto a rigid flat and slides the flat, for
each contact method and friction law (rows) against gamma0 and the number of sliding increments
(columns); its cells give the Newton iterations and Q / (mu P) at the end, and
``friction_detail.csv`` the iterations per pressing and per sliding increment.

Modules: causes.py (the causes, the classifier and the Recorder), grid.py (the scenes' grids and
one run), shear.py (the simple-shear case), friction.py (the frictional slide), report.py (CSV, heat
maps, summary).
"""
from __future__ import annotations

import argparse
import logging
import pathlib
import subprocess
import sys
import time

from .causes import (CAUSES, CHATTER, DIVERGED, INVERTED, LINEAR, NAN, NO_CONVERGENCE, OTHER,
                     RETURN_MAP, SHORT, SR_RANGE, Recorder, classify, is_cycling)
from .friction import friction_panels, hertz_slide, run_friction
from .grid import Panel, panels, panels_of, run_case, run_scene_grid
from .report import heatmap, read_csv, replot, summary, write_csv
from .shear import (first_decrease, green_naghdi_shear, jaumann_shear, run_shear, shear_panels,
                    simple_shear)

__all__ = ["CAUSES", "CHATTER", "DIVERGED", "INVERTED", "LINEAR", "NAN", "NO_CONVERGENCE", "OTHER",
           "RETURN_MAP", "SHORT", "SR_RANGE", "Panel", "Recorder", "classify", "first_decrease",
           "friction_panels", "green_naghdi_shear", "hertz_slide", "heatmap", "is_cycling", "jaumann_shear", "main", "panels", "panels_of",
           "read_csv", "replot", "run_case", "run_friction", "run_scene_grid", "run_shear", "shear_panels",
           "simple_shear", "summary", "write_csv"]

SCENES = ["elastica", "beam", "plate", "ring", "shear", "friction"]


def main(argv=None) -> int:
    p = argparse.ArgumentParser(prog="python -m comove_dolfinx.stability", description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("scene", choices=[*SCENES, "all", "replot"],
                   help="a scene, the shear case, all of them, or replot (heat maps and summary "
                   "again from the CSV files)")
    p.add_argument("--out", default="results/stability")
    p.add_argument("--jobs", type=int, default=2, help="scenes at a time with 'all' (default 2)")
    args = p.parse_args(argv)
    out = pathlib.Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    if args.scene == "replot":
        replot(out, panels_of)
        summary(out, panels_of)
        return 0
    if args.scene == "all":
        todo = list(SCENES)
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
        summary(out, panels_of)
        return 0
    import os
    os.environ.setdefault("PETSC_OPTIONS", "-no_signal_handler")
    logging.disable(logging.INFO)
    if args.scene == "shear":
        run_shear(out)
    elif args.scene == "friction":
        run_friction(out)
    else:
        run_scene_grid(args.scene, out)
    summary(out, panels_of)
    return 0

"""Running a scene: mesh, model, increments, XDMF, CSV history, progress bar and timing.

Output folder (created if needed):
``history.csv``   one row per converged increment (columns named by the scene)
``results.xdmf``  (+ ``.h5``) fields per converged increment, time = load factor
``run.json``      parameters, outcome, increments, Newton iterations, the timing breakdown and, for
                  contact scenes, the load at first contact and the largest penetration
Every file is flushed after each increment, so a run that stops part-way keeps what converged.
"""
from __future__ import annotations

import dataclasses
import json
import logging
import pathlib
import time

from mpi4py import MPI
from tqdm import tqdm

from .output import History, XDMFOutput
from .parallel import on_root
from .scenes import Scene
from .solver import IncrementalSolver, NewtonSettings, RunResult, StepSettings, Timer

log = logging.getLogger("comove")


def _print(comm, text: str) -> None:
    if comm.rank == 0:
        tqdm.write(text)


def run_scene(scene: Scene, out_dir, comm=MPI.COMM_WORLD, progress: bool = True,
              newton: NewtonSettings | None = None, callbacks=(),
              steps: StepSettings | None = None) -> RunResult:
    """Run ``scene`` and write its results into ``out_dir``; returns the solver's RunResult.

    ``newton``, ``steps``: solver settings instead of the scene's own.
    ``callbacks``: extra ``f(scene, model, increment)`` called after each converged increment (after
    the history row is written, before the state is committed), e.g. to take snapshots for plots.
    """
    out = pathlib.Path(out_dir)
    on_root(comm, out.mkdir, parents=True, exist_ok=True)
    timer = Timer()
    t_start = time.perf_counter()
    with timer("mesh"):
        md = scene.mesh_data(comm)
    with timer("setup and compilation"):
        model = scene.build_model(md)
        model.finalize()
    contacts = scene.contacts()
    for c in contacts:
        c.check_start()
    extra = []
    for c in contacts:
        extra.append(("contact_pressure", lambda c=c: (c.update_fields(), c.pressure)[1]))
        if c.mu > 0:
            extra.append(("contact_shear", lambda c=c: c.shear))
    history = History(out / "history.csv", scene.history_columns(), comm)
    xdmf = XDMFOutput(out / "results.xdmf", model, extra, scene.fibres(model))
    stats = {"first_contact_load": None, "max_penetration": 0.0}
    _print(comm, f"{scene.name}: {model.num_dofs()} dofs, {md.mesh.topology.index_map(2).size_global}"
                 f" cells, {model.kin.model}, update {scene.update}, {scene.n_steps} increments nominal")

    def record(m, inc):
        row = {"step": inc.step, "load": inc.load * scene.load_max, **scene.history_row(m),
               "newton_its": inc.newton_its, "wall_s": inc.wall_s}
        history.append(**row)
        xdmf.write(inc.load)
        for c in contacts:
            z = c.zone()
            stats["max_penetration"] = max(stats["max_penetration"], z.max_penetration)
            if z.in_contact and stats["first_contact_load"] is None:
                stats["first_contact_load"] = row["load"]
        extra = ", ".join(f"{k} {row[k]:.5g}" for k in scene.columns)
        cut = f" after {inc.cutbacks} cut-back(s)" if inc.cutbacks else ""
        for cb in callbacks:
            cb(scene, m, inc)
        _print(comm, f"  step {inc.step:3d}  load {row['load']:.5g}  {inc.newton_its} its{cut}  "
                     f"{extra}  ({inc.wall_s:.2f} s)")

    solver = IncrementalSolver(model, steps or scene.step_settings(),
                               newton or scene.newton_settings(), timer)
    bar = tqdm(total=1.0, unit="load", disable=not progress or comm.rank != 0,
               bar_format="{l_bar}{bar}| {n:.3f}/{total:.0f} [{elapsed}<{remaining}]")
    try:
        result = solver.run([record], progress=bar)
    finally:
        bar.close()
        history.close()
        xdmf.close()
    wall = time.perf_counter() - t_start
    its = result.newton_its
    _print(comm, f"{scene.name}: {result.message}; Newton iterations mean "
                 f"{(sum(its) / len(its)) if its else 0:.2f}, max {max(its) if its else 0}; "
                 f"wall {wall:.2f} s")
    _print(comm, timer.report())
    if contacts:
        if stats["first_contact_load"] is None:
            _print(comm, f"warning: the obstacle never touched the body up to load "
                         f"{(result.increments[-1].load if result.increments else 0) * scene.load_max:.5g}"
                         "; check the gap and the load")
        else:
            _print(comm, f"first contact at load {stats['first_contact_load']:.5g}; largest "
                         f"penetration {stats['max_penetration']:.3g}")
    info = {"scene": scene.name, "parameters": dataclasses.asdict(scene),
            "completed": result.completed, "message": result.message,
            "increments": len(its), "newton_its": its,
            "failed_its": sum(i.failed_its for i in result.increments),
            "dofs": model.num_dofs(), "ranks": comm.size, "wall_s": wall,
            "timing": dict(timer.totals), **(stats if contacts else {})}
    on_root(comm, (out / "run.json").write_text, json.dumps(info, indent=1))
    return result

"""Checkpoints: the full state of a converged increment, to restart a run from it.

The :class:`Checkpoint` writer saves, every ``every`` converged increments, into ``folder``:
``state_NNNNN_rankR.npz`` (each rank's displacement, quadrature state, items' state - friction
history, obstacle positions, load factors - and the predictor's past states), ``tangent_NNNNN.petsc``
(the last factorised tangent, which the tangent predictor reuses) and ``meta.json`` (the step, the
increment loop's counters, Newton's residual scale and the history rows so far), written last and
renamed into place: it names the files of the newest complete checkpoint, whose files are never
removed before it. ``Job.run(restart=folder)`` (``comove run ... --restart``) goes on from it with the
same number of ranks and gives the history of the uninterrupted run.
"""
from __future__ import annotations

import json
import os
import pathlib

import numpy as np
from petsc4py import PETSc

from ..parallel import on_root
from .writers import Writer, write_atomic


class CheckpointError(ValueError):
    """A checkpoint that cannot be used; the message names it and the fix."""


class Checkpoint(Writer):
    def __init__(self, folder, every: int = 1):
        if not (isinstance(every, int) and every >= 1):
            raise CheckpointError(f"every = {every!r}: give a whole number >= 1")
        self.folder, self.every = pathlib.Path(folder), every
        self.count = 0

    def open(self, run) -> None:
        on_root(run.comm, self.folder.mkdir, parents=True, exist_ok=True)
        self.count = len(run.resumed_rows)

    def write(self, run, row, increment) -> None:
        self.count += 1
        if self.count % self.every:
            return
        comm, n = run.comm, row["step"]
        m, solver, newton = run.model, run.solver, run.newton
        arrays = {f"model_{k}": v for k, v in m.save_state().items()}
        for i, item in enumerate(m.items):
            arrays.update({f"item{i}_{k}": np.asarray(v) for k, v in item.save_state().items()})
        rs = solver.resume_state
        for j, (_, u) in enumerate(rs["past"]):
            arrays[f"past{j}"] = u
        name = self.folder / f"state_{n:05d}_rank{comm.rank}.npz"
        tmp = name.with_name(f".{name.stem}.tmp.npz")
        np.savez(tmp, **arrays)
        os.replace(tmp, name)
        tangent = self.folder / f"tangent_{n:05d}.petsc"
        if newton.factorised:
            viewer = PETSc.Viewer().createBinary(str(tangent), "w", comm=comm)
            newton.A.view(viewer)
            viewer.destroy()
        comm.barrier()
        meta = {"increment": n, "ranks": comm.size, "step_index": run.step_index,
                "resume": {"t": rs["t"], "dt": rs["dt"], "step": rs["step"], "easy": rs["easy"],
                           "past_t": [t for t, _ in rs["past"]]},
                "residual_scale": newton.residual_scale, "factorised": bool(newton.factorised),
                "rows": run.job_rows, "contact": run.contact_stats, "warnings": run.warnings}
        on_root(comm, self._commit, n, json.dumps(meta, default=float))

    def _commit(self, n: int, text: str) -> None:
        write_atomic(self.folder / "meta.json", text)
        for f in self.folder.iterdir():                # older checkpoints, now superseded
            if f.name.startswith(("state_", "tangent_")) and f"_{n:05d}" not in f.name:
                f.unlink(missing_ok=True)


def load(folder, comm) -> tuple[dict, dict]:
    """(meta, this rank's arrays) of the newest checkpoint in ``folder``."""
    folder = pathlib.Path(folder)
    try:
        meta = json.loads((folder / "meta.json").read_text())
    except (OSError, ValueError):
        raise CheckpointError(f"{folder}: no checkpoint to restart from (meta.json missing or unreadable): "
                              "run without --restart") from None
    if meta["ranks"] != comm.size:
        raise CheckpointError(f"{folder}: the checkpoint was written by {meta['ranks']} ranks, this run has "
                              f"{comm.size}: restart with mpirun -n {meta['ranks']}")
    n = meta["increment"]
    with np.load(folder / f"state_{n:05d}_rank{comm.rank}.npz") as f:
        arrays = {k: f[k] for k in f.files}
    meta["tangent"] = str(folder / f"tangent_{n:05d}.petsc")
    return meta, arrays


def restore(meta: dict, arrays: dict, model, newton) -> dict:
    """Put the model, its items and Newton back at the checkpoint; the loop's resume dict."""
    mstate = {k[6:]: v for k, v in arrays.items() if k.startswith("model_")}
    items = []
    for i, _ in enumerate(model.items):
        p = f"item{i}_"
        items.append({k[len(p):]: v for k, v in arrays.items() if k.startswith(p)})
    model.load_state(mstate, items)
    newton.residual_scale = meta["residual_scale"]
    if meta["factorised"]:
        viewer = PETSc.Viewer().createBinary(meta["tangent"], "r", comm=model.comm)
        newton.A.zeroEntries()
        newton.A.load(viewer)
        viewer.destroy()
        newton.ksp.setOperators(newton.A)
        newton.factorised = True
    r = dict(meta["resume"])
    r["past"] = [(t, arrays[f"past{j}"]) for j, t in enumerate(r.pop("past_t"))]
    return r

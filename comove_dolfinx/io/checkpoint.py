"""Checkpoints: the full state of a converged increment, to restart a run from it.

The :class:`Checkpoint` writer saves converged increments (every ``every``-th, at most one per
``interval`` seconds, and the last one when the run ends) into ``folder``:
``state_NNNNN_rankR.npz`` (each rank's displacement, quadrature state, the items' state - friction
history, obstacle positions, load factors -, the predictor's past states, and the iterate whose
tangent Newton factorised last, rebuilt at a restart for the tangent predictor) and ``meta.json``
(the step, the increment loop's counters, Newton's residual scale and force level, the history's
columns and rows so far, the job's steps, and what the run is: its ``identity``, io/restart.py),
written last and renamed into place: it names the files of the newest complete checkpoint, which are
never removed before it. Values are stored with the positions of their nodes and quadrature points, so
nothing depends on how the mesh was partitioned (which changes from run to run on several ranks).
``Job.run(restart=folder)`` (``comove run ... --restart``) goes on from it, on any number of ranks,
and gives the history of the uninterrupted run. :func:`load` refuses, before the job's writers
touch anything, a checkpoint of another job: other history columns, another number of steps, or
another mesh.
"""
from __future__ import annotations

import io
import json
import os
import pathlib
import time

import numpy as np
from mpi4py import MPI

from ..parallel import collective, on_root
from .csv_tables import current_names
from .writers import Writer, write_atomic


class CheckpointError(ValueError):
    """A checkpoint that cannot be used; the message names it and the fix."""


def _owned(model, kind, arr, X=None):
    """(key coordinates, values) of this rank's owned entries of a saved array (``X``: the local
    coordinates of that kind, if known)."""
    X = _local_coordinates(model, kind) if X is None else X
    if isinstance(kind, str) and kind == "V":
        n = model.V.dofmap.index_map.size_local
        return X[:n], np.asarray(arr).reshape(-1, model.V.dofmap.index_map_bs)[:n]
    if isinstance(kind, str) and kind == "Q":
        tdim = model.mesh.topology.dim
        n = model.mesh.topology.index_map(tdim).size_local * model.rule.points.shape[0]
        return X[:n], np.asarray(arr)[:n]
    n = kind.dofmap.index_map.size_local                        # a space of an item's field
    return X[:n], np.asarray(arr).reshape(-1, kind.dofmap.index_map_bs)[:n]


def _local_coordinates(model, kind):
    """Reference coordinates (entries, the body's dimension) of the local entries of a kind of array
    ("V", "Q" or an item's space)."""
    gdim = model.mesh.geometry.dim
    if isinstance(kind, str) and kind == "V":
        return model.V.tabulate_dof_coordinates()[:, :gdim]
    if isinstance(kind, str) and kind == "Q":
        return model.point_coordinates()
    return kind.tabulate_dof_coordinates()[:, :gdim]


def _pack(arrays: dict) -> tuple[dict, np.ndarray]:
    """Every array's bytes in one buffer, and where each lies (dtype, shape, offset): an archive of
    two entries, where one entry per array cost more in the zip file's bookkeeping than the data."""
    layout, chunks, offset = {}, [], 0
    for name, a in arrays.items():
        a = np.asarray(a)                    # (np.ascontiguousarray would make a 0-d array 1-d)
        layout[name] = [a.dtype.str, list(a.shape), offset]
        chunks.append(np.ascontiguousarray(a).reshape(-1).view(np.uint8))
        offset += a.nbytes
    return layout, np.concatenate(chunks) if chunks else np.zeros(0, dtype=np.uint8)


def _unpack(layout: dict, data: np.ndarray) -> dict:
    out = {}
    for name, (dtype, shape, offset) in layout.items():
        dt = np.dtype(dtype)
        n = int(np.prod(shape, dtype=np.int64)) * dt.itemsize
        out[name] = data[offset:offset + n].copy().view(dt).reshape(shape)
    return out


def _key(X: np.ndarray):
    return [tuple(k) for k in np.round(X, 9)]


class Checkpoint(Writer):
    """Saves the converged increments to go on from: every ``every`` increments, and no sooner than
    ``interval`` seconds (wall time) after the last save; the newest converged increment is always
    saved when the run ends (completed, stopped or interrupted), so a restart after an ordinary end
    goes on from where the run stood, and after a kill -9 from at most ``interval`` seconds before
    it. Each increment's state is taken (copied) when it converges; the files are written when a
    save is due. ``interval = 0``: every ``every``-th increment, as it converges."""

    def __init__(self, folder, every: int = 1, interval: float = 0.0, identity: dict | None = None):
        if not (isinstance(every, int) and every >= 1):
            raise CheckpointError(f"every = {every!r}: give a whole number >= 1")
        if not (isinstance(interval, (int, float)) and 0.0 <= interval < float("inf")):
            raise CheckpointError(f"interval = {interval!r}: give a number of seconds >= 0")
        self.folder, self.every, self.interval = pathlib.Path(folder), every, float(interval)
        self.identity = identity               # what the run is (io/restart.py), kept in meta.json
        self.count = 0
        self._pending = None                 # (increment, packed arrays, meta) not yet on disk

    def open(self, run) -> None:
        on_root(run.comm, self.folder.mkdir, parents=True, exist_ok=True)
        self.count = len(run.resumed_rows)
        self._prev, self._ranks = None, run.comm.size
        self._pending, self._saved_at = None, time.perf_counter()
        self._coords = {}                    # the entries' reference coordinates, per kind (fixed)

    def write(self, run, row, increment) -> None:
        self.count += 1
        self._pending = self._take(run, row["increment"])
        if self.count % self.every:
            return
        # the same decision on every rank (wall clocks differ): rank 0's
        due = run.comm.bcast(time.perf_counter() - self._saved_at >= self.interval, root=0)
        if due:
            self._save(run.comm)

    def close(self, run, results) -> None:
        if self._pending is not None:
            self._save(run.comm)

    def _take(self, run, n: int) -> tuple:
        """(increment, packed arrays of this rank, meta.json's content) of the converged increment
        that the model holds (before it commits); the content is turned into text when it is saved
        (the rows grow with the run: text at every increment would cost quadratic time)."""
        comm = run.comm
        m, solver, newton = run.model, run.solver, run.newton
        arrays, kinds, coords = {}, {}, self._coords

        def put(name, value):
            if isinstance(value, tuple):              # (kind, local array): owned entries, keyed by position
                kind, arr = value
                tag = kind if isinstance(kind, str) else name      # an item's field: keyed by its own nodes
                key = tag if isinstance(kind, str) else id(kind)
                if key not in coords:
                    coords[key] = _local_coordinates(m, kind)
                X, vals = _owned(m, kind, arr, coords[key])
                arrays[f"X{tag}"], arrays[name], kinds[name] = X, vals, tag
            else:
                arrays[name] = np.asarray(value)

        for k, v in m.save_state().items():
            put(f"model_{k}", v)
        for i, item in enumerate(m.items):
            for k, v in item.save_state().items():
                put(f"item{i}_{k}", v)
        rs = solver.resume_state
        for j, (_, u) in enumerate(rs["past"]):
            put(f"past{j}", ("V", u))
        if newton.factorised:
            put("u_factorised", ("V", newton.u_factorised))
        meta = {"increment": n, "ranks": comm.size, "step_index": run.step_index,
                "resume": {"t": rs["t"], "dt": rs["dt"], "increment": rs["increment"], "easy": rs["easy"],
                           "past_t": [t for t, _ in rs["past"]], "use_pred": bool(rs["use_pred"])},
                "residual_scale": newton.residual_scale, "force_level": newton.force_level,
                "factorised": bool(newton.factorised), "columns": list(run.columns),
                "steps": [int(s.n) for s in run.job.steps], "identity": self.identity,
                "rows": list(run.job_rows), "contact": dict(run.contact_stats), "warnings": list(run.warnings),
                "failures": run.failures,
                "kinds": kinds}
        return n, _pack(arrays), meta              # (packing copies the arrays; the lists are copied)

    def _save(self, comm) -> None:
        n, (layout, data), meta = self._pending
        name = self.folder / f"state_{n:05d}_rank{comm.rank}.npz"
        tmp = name.with_name(f".{name.stem}.tmp.npz")

        def save():
            buf = io.BytesIO()                  # one write of the whole archive
            np.savez(buf, layout=np.frombuffer(json.dumps(layout).encode(), dtype=np.uint8), data=data)
            tmp.write_bytes(buf.getbuffer())
            os.replace(tmp, name)
        # every rank's file is complete before meta.json names it; a rank that cannot write (a full
        # disk) fails the write on every rank instead of leaving the others waiting
        collective(comm, save)
        on_root(comm, self._commit, n, json.dumps(meta, default=float))
        self._pending, self._saved_at = None, time.perf_counter()

    def _commit(self, n: int, text: str) -> None:
        write_atomic(self.folder / "meta.json", text)
        # older checkpoints, now superseded: a sweep of the folder the first time (files of an
        # earlier run), then the previous increment's files by name
        if self._prev is None:
            old = [f for f in self.folder.iterdir() if f.name.startswith("state_")]
        else:
            old = [self.folder / f"state_{self._prev:05d}_rank{r}.npz" for r in range(self._ranks)]
        for f in old:
            if f"_{n:05d}" not in f.name:
                f.unlink(missing_ok=True)
        self._prev = n


def load(folder, comm, job=None) -> tuple[dict, list]:
    """(meta, every rank's saved arrays) of the newest checkpoint in ``folder``; any number of
    ranks' files are read, and matched to this run's numbering by position in ``restore``.
    ``job``: the job that restarts (its model built), refused with a JobError unless the checkpoint
    is one of its runs (:func:`check_job`). ``folder`` may be an io.restart.RestartPoint, whose time
    scale and increment cap are applied here."""
    folder = pathlib.Path(folder) if not hasattr(folder, "time_scale") else folder
    try:
        meta = json.loads((folder / "meta.json").read_text())
    except (OSError, ValueError):
        raise CheckpointError(f"{folder}: no checkpoint to restart from (meta.json missing or unreadable): "
                              "run without --restart") from None
    n = meta["increment"]
    parts = []
    for r in range(meta["ranks"]):
        path = folder / f"state_{n:05d}_rank{r}.npz"
        try:
            with np.load(path) as f:
                parts.append(_unpack(json.loads(f["layout"].tobytes()), f["data"]))
        except (OSError, ValueError, KeyError):
            raise CheckpointError(f"{path}: missing or not a checkpoint of this version: run without "
                                  "--restart") from None
    meta = _renamed(meta)
    if job is not None:
        check_job(folder, meta, parts, job, comm)
    scale, dt_max = getattr(folder, "time_scale", 1.0), getattr(folder, "dt_max", None)
    if scale != 1.0 or dt_max is not None:
        if len(meta.get("steps", [])) != 1:
            raise CheckpointError(f"{folder}: a new final load or increment applies to a job of one step")
        _rescale(meta, parts, scale, dt_max)
    return meta, parts


def _renamed(meta: dict) -> dict:
    """``meta`` with the names of today where a checkpoint written before a rename has the old ones:
    the history rows' and the increment loop's increment counter ``step``, now ``increment``."""
    rows = meta.get("rows", [])
    names = current_names(rows[0] if rows else [])
    meta["rows"] = [{names.get(k, k): v for k, v in row.items()} for row in rows]
    resume = meta.get("resume", {})
    if "step" in resume and "increment" not in resume:
        resume["increment"] = resume.pop("step")
    return meta


def check_job(folder, meta: dict, parts: list, job, comm) -> None:
    """JobError (on every rank) unless the checkpoint in ``folder`` can be a state of ``job``: the
    same history columns, as many steps (their counts of increments may differ), and nodes where
    the job's mesh has its nodes."""
    from ..job import JobError
    columns = meta.get("columns") or (list(meta["rows"][0]) if meta.get("rows") else None)
    if columns is not None and list(columns) != list(job.columns):
        gone = [c for c in columns if c not in job.columns]
        new = [c for c in job.columns if c not in columns]
        what = "; ".join(x for x in (f"only the checkpoint has {', '.join(gone)}" if gone else "",
                                     f"only this job has {', '.join(new)}" if new else "") if x)
        raise JobError(f"restart from {folder}: the checkpoint's history has other columns "
                       f"({what or 'in another order'}): restart the job that wrote it")
    steps = meta.get("steps")
    if (steps is not None and len(steps) != len(job.steps)) or meta["step_index"] >= len(job.steps):
        raise JobError(f"restart from {folder}: the checkpoint is of a job with {len(steps or [])} step(s) "
                       f"(at step {meta['step_index'] + 1}), this job has {len(job.steps)}: restart the job "
                       "that wrote it")
    model = getattr(job, "model", None)
    if model is not None:
        def fits():
            X = np.concatenate([p["XV"] for p in parts])
            where = set(_key(X))
            return len(X) == model.V.dofmap.index_map.size_global and all(
                k in where for k in _key(_local_coordinates(model, "V")))
        if not comm.allreduce(bool(fits()), op=MPI.LAND):
            raise JobError(f"restart from {folder}: the checkpoint's nodes are not those of this job's mesh: "
                           "restart the job that wrote it, on the same mesh")


def _rescale(meta: dict, parts: list, scale: float, dt_max: float | None) -> None:
    """The checkpoint's time (the load factor of its one step) multiplied by ``scale``: the loop's
    load factor, increment and past states, the model's and the items' factors, the rows' time
    (their load stays); the increment at most ``dt_max``."""
    r = meta["resume"]
    r["t"], r["dt"] = r["t"] * scale, r["dt"] * scale
    if dt_max is not None:
        r["dt"] = min(r["dt"], dt_max)
    r["past_t"] = [t * scale for t in r["past_t"]]
    for row in meta["rows"]:
        row["time"] = row["time"] * scale
    for p in parts:
        for name in list(p):
            if name == "model_load" or (name.startswith("item") and name.endswith(("_factor", "_start", "_factor_n"))):
                p[name] = p[name] * scale


def restore(meta: dict, parts: list, model, newton) -> dict:
    """Put the model, its items and Newton back at the checkpoint (whatever the partition of the
    run that wrote it); the increment loop's resume dict."""
    kinds = meta["kinds"]
    spaces = {"V": "V", "Q": "Q"}
    for i, item in enumerate(model.items):          # the spaces of the items' fields
        for k, v in item.save_state().items():
            if isinstance(v, tuple) and not isinstance(v[0], str):
                spaces[f"item{i}_{k}"] = spaces["S"] = v[0]     # ("S": older checkpoints' one tag)
    index = {}

    def local(name):
        tag = kinds.get(name)
        if tag is None:
            return parts[0][name]
        if tag not in index:
            X = np.concatenate([p[f"X{tag}"] for p in parts])
            where = dict(zip(_key(X), range(len(X))))
            try:
                index[tag] = np.array([where[k] for k in _key(_local_coordinates(model, spaces[tag]))])
            except KeyError:
                raise CheckpointError("the checkpoint does not fit this mesh: restart the same problem") from None
        vals = np.concatenate([p[name] for p in parts])[index[tag]]
        return vals if tag == "Q" else vals.ravel()

    names = parts[0].keys()
    mstate = {k[6:]: local(k) for k in names if k.startswith("model_")}
    items = []
    for i, _ in enumerate(model.items):
        p = f"item{i}_"
        items.append({k[len(p):]: local(k) for k in names if k.startswith(p)})
    newton.residual_scale = meta["residual_scale"]
    newton.force_level = meta.get("force_level", meta["residual_scale"])   # (not in older checkpoints)
    u_fact = local("u_factorised") if meta["factorised"] else None
    model.load_state(mstate, items, u_fact, newton.A)
    if u_fact is not None:
        newton.ksp.setOperators(newton.A)
        newton.factorised = True
    r = dict(meta["resume"])
    r["past"] = [(t, local(f"past{j}")) for j, t in enumerate(r.pop("past_t"))]
    return r

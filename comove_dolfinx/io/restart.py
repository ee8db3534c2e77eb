"""What a run is, recorded with its checkpoint, and whether a restart may go on from it.

A run's identity is a dict: for a scene ``{"scene": name, "parameters": {...}}`` (every parameter,
resolved: defaults and ``--set`` values, the mesh file as an absolute path), for a problem file
``{"problem": path, "sha256": ..., "files": {path: sha256}}`` (the file's content and that of the
files it names: a mesh, an obstacle's profile), and the package ``version``; after a restart that
changed parameters, ``changes`` says which, from what to what, at which increment. The checkpoint writer
stores it in ``meta.json`` (io/checkpoint.py) and the run summary in ``run.json``.

``comove run ... --restart`` compares the identity of the run it is asked for with the one stored,
before dolfinx is loaded and before anything in the folder is touched (:func:`check`): another scene
or problem file is refused, and so is every parameter that differs, named with both values, unless
``--allow-change`` names it; even then a parameter that shapes what the checkpoint holds (the mesh,
the fields, the items) cannot change, nor can the final load go below the load already reached
(presets/base.py, ``Scene.restart_change_error``). A larger final load goes on along the same path:
the checkpoint's time is rescaled so that its state keeps its load (:class:`RestartPoint`). A
checkpoint written before identities were recorded is accepted with a warning.

Nothing here imports dolfinx, mpi4py or numpy.
"""
from __future__ import annotations

import dataclasses
import hashlib
import json
import os
import pathlib


def _sha256(path) -> str:
    with open(path, "rb") as fh:
        return hashlib.file_digest(fh, "sha256").hexdigest()


def _version() -> str:
    from .. import __version__
    return __version__


def scene_identity(scene) -> dict:
    """The identity of a run of the preset ``scene`` (the module docstring)."""
    params = json.loads(json.dumps(dataclasses.asdict(scene)))
    if params.get("mesh"):
        params["mesh"] = str(pathlib.Path(params["mesh"]).resolve())
    return {"scene": scene.name, "parameters": params, "version": _version()}


def problem_identity(path, data: dict) -> dict:
    """The identity of a run of the problem file ``path`` (``data``: its checked tables, whose file
    names problem.read made absolute)."""
    files = [data.get("mesh", {}).get("file")]
    files += [item.get("obstacle", {}).get("file") for item in data.get("items", [])]
    return {"problem": str(path), "sha256": _sha256(path),
            "files": {f: _sha256(f) for f in files if f}, "version": _version()}


def saved_meta(out) -> dict | None:
    """The checkpoint's meta.json in the run folder ``out``, or None if there is none to read."""
    try:
        return json.loads((pathlib.Path(out) / "checkpoint" / "meta.json").read_text())
    except (OSError, ValueError):
        return None


def reached_load(meta: dict) -> float | None:
    """The history's ``load`` at the checkpoint (None without a row)."""
    rows = meta.get("rows") or []
    return float(rows[-1]["load"]) if rows and "load" in rows[-1] else None


@dataclasses.dataclass
class Verdict:
    """What :func:`check` decided: ``error`` (one line, or None), ``warnings`` (lines), the
    parameters that change (name -> (old, new)) and the factor the checkpoint's time is multiplied
    by (the old final load over the new one; 1 if it does not change)."""

    error: str | None = None
    warnings: list = dataclasses.field(default_factory=list)
    changes: dict = dataclasses.field(default_factory=dict)
    time_scale: float = 1.0
    earlier: list = dataclasses.field(default_factory=list)   # the changes of earlier restarts
    increment: int = 0                                        # the checkpoint's increment

    def record(self, identity: dict) -> None:
        """Put the changes of this and earlier restarts into ``identity`` (``changes``: a list of
        {"increment": n, "parameters": {name: [old, new]}}), for meta.json and run.json."""
        done = list(self.earlier)
        if self.changes:
            done.append({"increment": self.increment,
                         "parameters": {k: list(v) for k, v in self.changes.items()}})
        if done:
            identity["changes"] = done


def _fmt(v) -> str:
    """A parameter's value as the message shows it: floats short where that is exact."""
    if isinstance(v, float):
        return f"{v:g}" if float(f"{v:g}") == v else repr(v)
    return repr(v) if isinstance(v, str) else str(v)


def _what(identity: dict) -> str:
    return (f"the scene {identity['scene']!r}" if "scene" in identity
            else f"the problem file {identity['problem']}")


def check(out, identity: dict, allow=(), scene=None) -> Verdict:
    """May the run of ``identity`` (``scene``: the preset, for a scene) go on from the checkpoint in
    the folder ``out``? ``allow``: the parameters that may change (``problem`` for a problem
    file's content)."""
    meta = saved_meta(out)
    verdict = Verdict()
    if meta is None:
        return verdict                       # io/folder.py says so (no checkpoint to restart from)
    old = meta.get("identity")
    verdict.increment = int(meta.get("increment", 0))
    if not old:
        verdict.warnings.append(
            f"{out}/checkpoint records no parameters (written by an earlier version): the restart cannot "
            "check that they are those of the run it goes on from")
        return verdict
    verdict.earlier = list(old.get("changes", []))
    if old.get("version") != identity.get("version"):
        verdict.warnings.append(f"the checkpoint in {out} was written by comove {old.get('version')}, this "
                                f"is {identity.get('version')}")
    if ("scene" in old) != ("scene" in identity) or old.get("scene", "") != identity.get("scene", ""):
        verdict.error = (f"--restart: {out} holds a run of {_what(old)}, not of {_what(identity)}: restart "
                         "it with the same scene or problem file, or choose another --out")
        return verdict
    if "scene" in identity:
        _compare_scene(verdict, out, old["parameters"], identity["parameters"], set(allow), scene,
                       reached_load(meta))
    else:
        _compare_problem(verdict, out, old, identity, set(allow))
    return verdict


def _compare_scene(verdict: Verdict, out, old: dict, new: dict, allow: set, scene, reached) -> None:
    """The parameters that differ: refused unless allowed, and allowed only where the scene says a
    restart can take the change; the time scale of a new final load."""
    differ = {k: (old.get(k), new.get(k)) for k in sorted(set(old) | set(new)) if old.get(k) != new.get(k)}
    if not differ:
        return
    named = ", ".join(f"{k} {_fmt(a)} (now {_fmt(b)})" for k, (a, b) in differ.items())
    refused = [k for k in differ if k not in allow]
    if refused:
        same = " ".join(f"--set {k}={differ[k][0]}" for k in refused)
        free = [k for k in refused if scene.restart_change_error(k, differ[k][0], reached) is None]
        fixed = [k for k in refused if k not in free]
        verdict.error = (f"--restart: {out} was run with other parameters: {named}: restart with {same}"
                         + (f", or pass --allow-change {','.join(free)} to go on with the new "
                            f"value{'s' if len(free) > 1 else ''}" if free else "")
                         + (f" ({', '.join(fixed)} cannot change at a restart)" if fixed else ""))
        return
    for k, (a, _) in differ.items():
        why = scene.restart_change_error(k, a, reached)
        if why is not None:
            verdict.error = f"--restart --allow-change {k}: {why}"
            return
    verdict.changes = differ
    if scene.load_parameter in differ:
        a, b = differ[scene.load_parameter]
        verdict.time_scale = a / b
    verdict.warnings.append(f"the restart goes on with {named}")


def _compare_problem(verdict: Verdict, out, old: dict, new: dict, allow: set) -> None:
    """The problem file's content and that of the files it names."""
    differ = []
    if old.get("sha256") != new["sha256"]:
        differ.append(f"the problem file {new['problem']} (sha256 {old.get('sha256', '?')[:12]} then, "
                      f"{new['sha256'][:12]} now)")
    for f in sorted(set(old.get("files", {})) | set(new["files"])):
        if old.get("files", {}).get(f) != new["files"].get(f):
            differ.append(f"the file {f}")
    if not differ:
        return
    if "problem" in allow:
        verdict.changes = {"problem": (old.get("sha256"), new["sha256"])}
        verdict.warnings.append(f"the restart goes on with changed content: {', '.join(differ)}")
        return
    verdict.error = (f"--restart: {out} was run from other content: {', '.join(differ)} differ: restore "
                     "them, or pass --allow-change problem to go on with the new content")


class RestartPoint(os.PathLike):
    """A checkpoint folder to restart from (``Job.run(restart=...)`` takes it as it takes the
    folder's path), with the changes a restart allowed: the checkpoint's time is multiplied by
    ``time_scale`` (the old final load over the new one: the state keeps its load, the rest of the
    path runs to the new final load) and its increment size is at most ``dt_max`` (the new nominal
    increment, in the new time)."""

    def __init__(self, folder, time_scale: float = 1.0, dt_max: float | None = None):
        self.folder, self.time_scale, self.dt_max = pathlib.Path(folder), float(time_scale), dt_max

    def __fspath__(self) -> str:
        return str(self.folder)

    def __truediv__(self, name):
        return self.folder / name

    def __str__(self) -> str:
        return str(self.folder)


class RestartError(ValueError):
    """A restart refused: the checkpoint is of another scene, problem file or parameters; the
    message names each difference and the fix."""


def allowed(values) -> set:
    """The parameter names of ``--allow-change`` options (each repeated, or separated by commas)."""
    return {k.strip() for v in values for k in v.split(",") if k.strip()}


def early_error(out, what: str, scene, data, allow: set) -> str | None:
    """Why the run of the scene ``scene`` (or of the problem file ``what`` with the tables ``data``)
    may not go on from the checkpoint in ``out``, or None: the command asks before it loads
    dolfinx."""
    known = {"problem"} if scene is None else {k for k, _, _ in scene.parameters()}
    unknown = sorted(allow - known)
    if unknown:
        return (f"--allow-change {','.join(unknown)}: not a parameter of {what}; its parameters are "
                f"{', '.join(sorted(known))}")
    identity = scene_identity(scene) if scene is not None else problem_identity(what, data)
    return check(out, identity, allow, scene).error


def restart_point(out, identity: dict, allow, scene, comm) -> RestartPoint:
    """The checkpoint of the folder ``out`` to go on from, with the changes allowed (recorded in
    ``identity``); RestartError if the run of ``identity`` may not go on from it. Warnings go to
    rank 0's stderr."""
    import sys
    verdict = check(out, identity, set(allow), scene)
    if verdict.error is not None:
        raise RestartError(verdict.error)
    verdict.record(identity)
    if comm.rank == 0:
        for w in verdict.warnings:
            print(f"comove: warning: {w}", file=sys.stderr)
    steps = scene is not None and "n_increments" in verdict.changes
    return RestartPoint(pathlib.Path(out) / "checkpoint", verdict.time_scale,
                        1.0 / scene.n_increments if steps else None)

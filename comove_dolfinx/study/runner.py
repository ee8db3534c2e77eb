"""Run the study's cases as separate processes (`comove run`), through an executor, and read what they left.

A case's cost is the CPU time of its whole process (start-up, imports, mesh, compilation, the run and
its output; the C compiler counts, as a child it waited for), taken from the kernel's accounting of
the finished child (os.wait4), and its Newton iterations, failed attempts included. Each case runs
``repeat`` times; the CPU time is their median and the spread their range. The first run of a kind
of model compiles its forms, later ones find them in the JIT cache: the spread shows it.

The cases go to a ``concurrent.futures`` executor (executors.py): threads that each start and wait
for one process at a time, or the workers of an MPI pool, each of which does the same where it runs.
"""
from __future__ import annotations

import json
import os
import pathlib
import shutil
import statistics
import subprocess
import sys
from concurrent.futures import as_completed

import numpy as np

from ..io.csv_tables import read_history
from . import executors
from .plan import Case, ScenePlan


def _launch(scene: str, case: Case, folder: pathlib.Path) -> tuple[float, int]:
    """One process; (its CPU seconds with its children, its exit code)."""
    cmd = [sys.executable, "-m", "comove_dolfinx.cli", "run", scene, "--out", str(folder), "--overwrite",
           "--no-progress"] + [a for s in case.sets for a in ("--set", s)]
    env = executors.child_environment()
    with open(folder.parent / f"{folder.name}.log", "w") as log:
        proc = subprocess.Popen(cmd, stdout=log, stderr=subprocess.STDOUT, env=env)
        _, status, usage = os.wait4(proc.pid, 0)
    proc.returncode = os.waitstatus_to_exitcode(status)
    return usage.ru_utime + usage.ru_stime, proc.returncode


def _read(folder: pathlib.Path) -> tuple[dict, dict]:
    """(run.json, the history's columns led by the unloaded state), empty where unreadable."""
    try:
        info = json.loads((folder / "run.json").read_text())
    except (OSError, ValueError):
        info = {}
    try:
        history = read_history(folder / "history.csv", origin=True)
    except (OSError, ValueError):
        history = {}
    return info, history


def quantity(plan: ScenePlan, history: dict) -> float:
    """q of a run from its history's columns (led by the unloaded state, csv_tables.read_history with
    ``origin``): the column at the plan's load level (linear between increments), nan where the run
    did not get there; or in the last row (the caller keeps it for completed runs only)."""
    if len(history.get("load", ())) < 2:
        return float("nan")
    y = history[plan.column]
    if plan.at is None:
        return plan.sign * float(y[-1])
    x = history["load"]
    if x[-1] < plan.at - 1e-12:
        return float("nan")
    return plan.sign * float(np.interp(plan.at, x, y))


def run_case(plan: ScenePlan, case: Case, out: pathlib.Path, repeat: int) -> dict:
    """Run ``case`` ``repeat`` times into out/runs/<tag>; the row of the study's table."""
    folder = out / "runs" / case.tag
    folder.parent.mkdir(parents=True, exist_ok=True)
    cpus, code = [], 0
    for _ in range(repeat):
        cpu, code = _launch(plan.name, case, folder)
        cpus.append(cpu)
    info, history = _read(folder)
    status = info.get("status", "crashed" if code else "unknown")
    its = info.get("newton_its", [])
    complete = status == "completed"
    q = quantity(plan, history) if complete or plan.at is not None else float("nan")
    increments = len(its)
    cut = max(increments - _nominal(case, plan), 0)          # increments added by cut-backs
    return {"family": case.family, "x": case.x, "settings": " ".join(case.sets), "status": status,
            "message": info.get("message", f"exit code {code}"), "increments": increments,
            "extra_increments": cut, "q": q,
            "newton_its": sum(its) + info.get("failed_its", 0), "failed_its": info.get("failed_its", 0),
            "dofs": info.get("dofs", 0), "cpu_s": statistics.median(cpus),
            "cpu_spread_s": max(cpus) - min(cpus), "repeats": repeat,
            "compile_cpu_s": (info.get("process") or {}).get("compiler_cpu_s", 0.0),
            "max_penetration": info.get("max_penetration", float("nan"))}


def _nominal(case: Case, plan: ScenePlan) -> int:
    for s in case.sets:
        if s.startswith("n_increments="):
            return int(s.split("=", 1)[1])
    return plan.n0


def run_all(plan: ScenePlan, cases: list[Case], out: pathlib.Path, repeat: int, jobs: int = 2,
            progress=None, pool=None) -> list[dict]:
    """Every case through the executor ``pool`` (default: a local one of ``jobs`` threads, made and
    shut down here); ``progress(case, row)`` is called here as each finishes; the rows in the order
    of ``cases``."""
    if pool is None:
        with executors.make("local", jobs) as local:
            return run_all(plan, cases, out, repeat, jobs, progress, local)
    out = out.resolve()                        # a worker may start in another folder
    pending = {pool.submit(run_case, plan, case, out, repeat): k for k, case in enumerate(cases)}
    rows: list = [None] * len(cases)
    for done in as_completed(pending):
        k = pending[done]
        rows[k] = done.result()
        if progress is not None:
            progress(cases[k], rows[k])
    return rows


def clean(out: pathlib.Path) -> None:
    shutil.rmtree(out / "runs", ignore_errors=True)

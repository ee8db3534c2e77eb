"""The history as CSV, the run's summary as JSON, and the console's lines."""
from __future__ import annotations

import csv
import json
import os
import pathlib
import sys
import time

import numpy as np

from ..parallel import on_root


class Writer:
    """Base class: every hook optional. ``run`` is the job's run state (comove_dolfinx.results.RunState:
    the job, its compiled model, the history's columns, the warnings so far, ...), ``row`` the
    history row of the converged increment, ``increment`` the increment loop's report of it
    (solver.Increment), ``results`` the job's Results."""

    def open(self, run) -> None:
        pass

    def write(self, run, row: dict, increment) -> None:
        pass

    def close(self, run, results) -> None:
        pass


def _fmt(v) -> str:
    if isinstance(v, (int, np.integer)):
        return str(int(v))
    return f"{float(v):.10g}"


class HistoryCSV(Writer):
    """``path``: one row per converged increment (the job's columns, 10 significant digits), written
    by rank 0 and flushed at once."""

    def __init__(self, path):
        self.path = pathlib.Path(path)
        self._fh = None

    def _open(self, columns, rows=()) -> None:
        self._fh = open(self.path, "w", newline="")
        self._csv = csv.writer(self._fh)
        self._csv.writerow(columns)
        for r in rows:                       # a restarted run: the rows up to its checkpoint
            self._csv.writerow([_fmt(r[c]) for c in columns])
        self._fh.flush()

    def _write(self, values) -> None:
        self._csv.writerow([_fmt(v) for v in values])
        self._fh.flush()

    def open(self, run) -> None:
        self.columns = run.columns
        on_root(run.comm, self._open, self.columns, run.resumed_rows)

    def write(self, run, row, increment) -> None:
        on_root(run.comm, self._write, [row[c] for c in self.columns])

    def close(self, run, results) -> None:
        if self._fh is not None:
            self._fh.close()
            self._fh = None


def write_atomic(path: pathlib.Path, text: str) -> None:
    """Write a file under a temporary name and rename it into place: a reader (or a kill) never
    sees half of it."""
    tmp = path.with_name(f".{path.name}.tmp")
    try:
        tmp.write_text(text)
        os.replace(tmp, path)
    except BaseException:                    # (a full disk, a signal): no half-written file left
        tmp.unlink(missing_ok=True)
        raise


class RunInfo(Writer):
    """``path`` (JSON): the job's parameters, outcome, increments, Newton iterations, the failed
    attempts per cause (``failures``), the cut-backs and retries, what to change if the run stopped
    (``advice``), timing and,
    with contact, the load at first contact and the largest penetration. Written when the run
    starts (``"status": "running"``) and after an increment at most every ``interval`` seconds, so
    that a run that is killed leaves a summary that says it is incomplete and about how far it got
    (history.csv has every increment); at the end ``"status"`` is ``"completed"``, ``"stopped"`` (an
    increment could not be solved) or ``"interrupted"``; the command's output folder turns a
    ``running`` left by a signal during start-up into ``"interrupted"``, and a run ended by an error
    into ``"failed"``, each with its message (io/folder.py). ``identity``: what the run is (scene
    and parameters, or problem file and its hash, the package version: io/restart.py)."""

    def __init__(self, path, parameters: dict | None = None, interval: float = 1.0, identity: dict | None = None):
        self.path, self.parameters, self.interval = pathlib.Path(path), parameters or {}, interval
        self.identity = identity             # what the run is (io/restart.py), if known
        self.rows = 0
        self._written = -float("inf")

    def _info(self, run, status: str, message: str, results=None) -> str:
        info = {"parameters": self.parameters, "status": status, "completed": status == "completed",
                "message": message, "increments": self.rows, "ranks": run.comm.size,
                "warnings": list(run.warnings), "failures": run.failures}
        if self.identity is not None:
            info["identity"] = self.identity
        if results is not None:
            info.update(increments=len(results.increments), newton_its=results.newton_its,
                        failed_its=results.failed_its, failures=dict(results.failures),
                        cutbacks=results.cutbacks, retries=results.retries, advice=results.advice,
                        dofs=results.dofs, wall_s=results.wall_s,
                        timing=results.timing, process=results.process, startup=results.startup, **results.contact)
        return json.dumps(info, indent=1, default=str)

    def open(self, run) -> None:
        self.rows = len(run.resumed_rows)
        on_root(run.comm, write_atomic, self.path, self._info(run, "running", "the run is going on"))

    def write(self, run, row, increment) -> None:
        self.rows += 1
        on_root(run.comm, self._running, run, row)

    def _running(self, run, row) -> None:
        if time.perf_counter() - self._written < self.interval:
            return
        write_atomic(self.path, self._info(
            run, "running", f"converged up to increment {row['increment']} (time {row['time']:.6g})"))
        self._written = time.perf_counter()

    def close(self, run, results) -> None:
        status = ("completed" if results.completed else
                  "interrupted" if results.interrupted else "stopped")
        on_root(run.comm, write_atomic, self.path, self._info(run, status, results.message, results))


class Console(Writer):
    """One line per increment (load, Newton iterations, the named columns) and a summary: the
    message, the Newton iterations, the failed attempts per cause with the cut-backs and retries,
    the wall time."""

    def __init__(self, title: str = "", columns=()):
        self.title, self.columns = title, tuple(columns)

    def _print(self, run, text: str) -> None:
        if run.comm.rank == 0:
            bars = sys.modules.get("tqdm")      # a progress bar shown (job.py): its write keeps it whole
            if bars is not None:
                bars.tqdm.write(text)
            else:
                sys.stdout.write(f"{text}\n")

    def open(self, run) -> None:
        m = run.model
        ncells = m.mesh.topology.index_map(m.mesh.topology.dim).size_global
        self._print(run, f"{self.title}: {m.num_dofs()} dofs, {ncells} cells, {m.kin.model}, "
                         f"update {m.body.update}, {sum(s.n for s in run.job.steps)} increments nominal")

    def _warn(self, run) -> None:
        """The warnings not printed yet."""
        for w in run.warnings[getattr(self, "_said", 0):]:
            self._print(run, f"warning: {w}")
        self._said = len(run.warnings)

    def write(self, run, row, inc) -> None:
        self._warn(run)
        extra = ", ".join(f"{k} {row[k]:.5g}" for k in self.columns)
        done = ([f"{inc.retries} retr{'ies' if inc.retries > 1 else 'y'} from the other start"] if inc.retries else []) + \
            ([f"{inc.cutbacks} cut-back(s)"] if inc.cutbacks else [])
        cut = f" after {' and '.join(done)}" if done else ""
        self._print(run, f"  increment {row['increment']:3d}  load {row['load']:.5g}  {inc.newton_its} its{cut}  "
                         f"{extra}  ({inc.wall_s:.2f} s)")

    def close(self, run, results) -> None:
        self._warn(run)
        its = results.newton_its
        self._print(run, f"{self.title}: {results.message}; Newton iterations mean "
                         f"{(sum(its) / len(its)) if its else 0:.2f}, max {max(its) if its else 0}; "
                         f"{results.failure_summary()}; wall {results.wall_s:.2f} s")
        self._print(run, results.timing_report)
        c = results.contact
        if c:
            if c["first_contact_load"] is None:
                last = results.rows[-1]["load"] if results.rows else 0.0
                self._print(run, f"warning: the obstacle never touched the body up to load {last:.5g}; "
                                 "check the gap and the load")
            else:
                self._print(run, f"first contact at load {c['first_contact_load']:.5g}; largest "
                                 f"penetration {c['max_penetration']:.3g}")

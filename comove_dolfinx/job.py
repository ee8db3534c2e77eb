"""Steps and jobs: load a body in steps, record probes, hand every converged increment to writers.

::

    job = cm.Job(body, items, steps=[cm.Step(20), cm.Step(10, ramp={press: 0.0})],
                 probes=[cm.NodeDisplacement("tip", (10, 0))], writers=[cm.HistoryCSV("h.csv")])
    results = job.run()
    results["tip_uy"]                 # the column as an array, one value per converged increment

Each item carries a factor (loads.py); a :class:`Step` moves the factors over its increments:
``ramp=None`` takes every item to 1 from where it stands, ``ramp={item: target}`` the items named
(a number, or a callable of the step's fraction s in [0, 1] for a path of its own) while the others
hold. The history's ``time`` runs from k - 1 to k over step k; its ``load`` is ``time`` unless the
job maps it (``load=lambda time: ...``, e.g. a physical load level), and is the XDMF time.

Data flows one way: the job compiles the model, runs the increment loop of each step
(solver/increments.py), turns every converged increment into a history row (the probes) and gives
it to the writers; nothing calls back into the problem. A step that cannot go on ends the job with
its message; the results hold every increment converged before.
"""
from __future__ import annotations

import contextlib
import logging
import os
import time
from dataclasses import dataclass, field
from typing import Callable

import numpy as np
from mpi4py import MPI
from tqdm import tqdm

from .mechanics.model import Model
from .names import PREDICTORS, first_increment_error
from .parallel import Interrupts, collective
from .solver import (
    Increment,
    IncrementalSolver,
    Newton,
    NewtonSettings,
    RunResult,
    StepSettings,
    Timer,
)


class JobError(ValueError):
    """A step or job that cannot run; the message names the value and the fix."""


@dataclass
class Step:
    """A stage of the loading: ``n`` nominal increments, the factors' targets, increment control.

    ``predictor``: where each increment starts, "tangent" (the default: Euler step along the path's
    tangent), "none" (the last converged state), "linear" or "quadratic" (extrapolation of the last
    converged states), docs/theory.md section 7.2. ``retry``: a failed increment is tried once more
    at the same size from the other start (a predictor if it started from the last state, the last
    state if it started from a predictor) before it is halved; a predictor that rescued an increment
    begun from the last state is kept for the rest of the step. ``max_cutbacks``: halvings of a
    failed increment.
    ``first``: the step's first increment as a fraction 1, 1/2, 1/4, ... of the nominal one (at most
    ``max_cutbacks`` halvings), doubled back to it after easy increments: a hard start (a first
    contact and its first yield) at a size that converges instead of failed attempts at the nominal.
    ``release``: supports (``Fixed``, ``Displacement``) taken away at the start of the step: the
    force each exerted there becomes a nodal force that the step ramps down to 0 (or to the target
    ``ramp`` gives it, as a fraction of that force), so the body is let go smoothly, e.g. a clamp
    opened after forming; a released support stays released.
    """

    n: int = 10
    ramp: dict | None = None
    predictor: str = "tangent"
    max_cutbacks: int = 6
    name: str = ""
    release: tuple = ()
    first: float = 1.0
    retry: bool = True

    def __post_init__(self):
        self.release = tuple(self.release) if isinstance(self.release, (list, tuple)) else (self.release,)
        if isinstance(self.n, bool) or not isinstance(self.n, (int, np.integer)) or not 1 <= self.n <= 10**6:
            raise JobError(f"step {self.name or ''} n = {self.n!r}: give a whole number of increments "
                           "from 1 to 1000000")
        if self.predictor not in PREDICTORS:
            raise JobError(f"predictor = {self.predictor!r} is unknown: choose one of {', '.join(PREDICTORS)}")
        if isinstance(self.max_cutbacks, bool) or not (isinstance(self.max_cutbacks, int) and
                                                       0 <= self.max_cutbacks <= 30):
            raise JobError(f"max_cutbacks = {self.max_cutbacks!r}: give a whole number from 0 to 30")
        why = first_increment_error(self.first, self.max_cutbacks)
        if why:
            raise JobError(why)
        if not isinstance(self.retry, (bool, np.bool_)):
            raise JobError(f"retry = {self.retry!r}: give True or False")

    def settings(self) -> StepSettings:
        return StepSettings(n_steps=int(self.n), max_cutbacks=self.max_cutbacks,
                            predictor=PREDICTORS[self.predictor], first=float(self.first),
                            retry=bool(self.retry))

    def check(self, items) -> None:
        """JobError if the step names an item that is not the job's, or releases what is not a
        support."""
        for k in list(self.ramp or {}) + list(self.release):
            if not any(k is item for item in items):
                verb = "ramps" if k in (self.ramp or {}) else "releases"
                raise JobError(f"step {self.name!r} {verb} {k!r}, which is not an item of the job")
        for k in self.release:
            if not callable(getattr(k, "release", None)):
                raise JobError(f"step {self.name!r} releases {k!r}: only supports (Fixed, Displacement) "
                               "can be released")

    def start(self, items, model=None) -> None:
        """Release the step's supports (with the model at its converged state), then set every
        item's ramp for this step."""
        self.check(items)
        ramp = self.ramp
        for item in self.release:
            if not item.released:
                model.release(item)
        for item in items:
            if ramp is not None and any(item is k for k in ramp):
                item.ramp(next(v for k, v in ramp.items() if k is item))
            elif any(item is k for k in self.release):
                item.ramp(0.0)
            elif ramp is None and not getattr(item, "released", False):
                item.ramp(1.0)
            else:
                item.hold()


class _CompilerLines(logging.Filter):
    """Drops the progress lines of the form compiler's C build (INFO and below, logged on the root
    logger by the distutils of setuptools that cffi drives) and the INFO of ffcx and UFL; every
    other record passes."""

    SOURCES = ("distutils", "setuptools", "cffi")

    def filter(self, record: logging.LogRecord) -> bool:
        if record.levelno >= logging.WARNING:
            return True
        if record.name.split(".")[0] in ("ffcx", "UFL", "ufl"):
            return False
        path = record.pathname.replace("\\", "/")
        return not (record.name == "root" and any(f"/{s}" in path for s in self.SOURCES))


@contextlib.contextmanager
def quiet_compilers():
    """Within the block, the form compiler's INFO lines are not shown; afterwards the root logger
    has its level back (distutils lowers it to INFO for every later record of the process).

    The user's own logging stays as it was: records of other loggers pass, and the filter comes
    off when the block ends. :meth:`Job.run` runs inside it."""
    root = logging.getLogger()
    level, filt = root.level, _CompilerLines()
    handlers = list(root.handlers)
    root.addFilter(filt)                 # records logged on the root logger itself (distutils)
    for h in handlers:                   # and those that reach its handlers from ffcx's or UFL's
        h.addFilter(filt)
    try:
        yield
    finally:
        root.removeFilter(filt)
        for h in handlers:
            h.removeFilter(filt)
        root.setLevel(level)


def process_clock() -> tuple[float, float, float]:
    """(wall seconds since this process started, CPU seconds of the process, CPU seconds of the
    child processes it waited for: the C compiler of the form compiler). The start is read from
    /proc (Linux); elsewhere the wall time counts from the import of this module."""
    import resource
    me, kids = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
    try:
        with open("/proc/self/stat") as fh:
            start = float(fh.read().rsplit(")", 1)[1].split()[19]) / os.sysconf("SC_CLK_TCK")
        with open("/proc/uptime") as fh:
            wall = float(fh.read().split()[0]) - start
    except (OSError, ValueError, IndexError):
        wall = time.perf_counter() - _IMPORTED
    return wall, me.ru_utime + me.ru_stime, kids.ru_utime + kids.ru_stime


_IMPORTED = time.perf_counter()


@dataclass
class Results:
    """A job's outcome: the history as columns, the increments, Newton statistics, the failed
    attempts per cause (``failures``, keys of solver/failures.py) with what to change if a step
    stopped (``advice``), and timing."""

    columns: list[str]
    rows: list[dict] = field(default_factory=list)
    increments: list = field(default_factory=list)
    completed: bool = False
    message: str = ""
    wall_s: float = 0.0
    dofs: int = 0
    timing: dict = field(default_factory=dict)      # wall seconds per part of the whole process
    timing_report: str = ""
    process: dict = field(default_factory=dict)     # wall_s, cpu_s, compiler_cpu_s of the process
    contact: dict = field(default_factory=dict)
    interrupted: bool = False       # by a signal or Ctrl-C (the exception goes on after the writers)
    warnings: list = field(default_factory=list)
    failures: dict = field(default_factory=dict)    # failed attempts per cause (solver/failures.py)
    advice: str = ""                # what to change, when a step stopped at its smallest increment

    def __getitem__(self, column: str) -> np.ndarray:
        if column not in self.columns:
            raise KeyError(f"no column {column!r}; the columns are {', '.join(self.columns)}")
        return np.array([row[column] for row in self.rows])

    def __len__(self) -> int:
        return len(self.rows)

    @property
    def newton_its(self) -> list[int]:
        return [inc.newton_its for inc in self.increments]

    @property
    def failed_its(self) -> int:
        return sum(inc.failed_its for inc in self.increments)

    @property
    def cutbacks(self) -> int:
        """Halvings of increments that then converged (those of a step that stopped are in
        ``failures`` and the message)."""
        return sum(inc.cutbacks for inc in self.increments)

    @property
    def retries(self) -> int:
        """Failed attempts tried again at the same size from the other start."""
        return sum(inc.retries for inc in self.increments)

    def failure_summary(self) -> str:
        """The failed attempts in words, e.g. "3 failed attempts (inadmissible 2, max_it 1), 2
        cut-backs, 1 retry"; "no failed attempts" if none failed."""
        n = sum(self.failures.values())
        if not n:
            return "no failed attempts"
        causes = ", ".join(f"{k} {v}" for k, v in sorted(self.failures.items(), key=lambda kv: -kv[1]))
        return (f"{n} failed attempt{'s' if n != 1 else ''} ({causes}), {self.cutbacks} cut-back"
                f"{'s' if self.cutbacks != 1 else ''}, {self.retries} retr{'ies' if self.retries != 1 else 'y'}")

    @property
    def last(self) -> dict:
        return self.rows[-1] if self.rows else {}


@dataclass
class Run:
    """What writers see: the job, its compiled model and the history's columns."""

    job: "Job"
    model: Model
    columns: list[str]
    warnings: list[str] = field(default_factory=list)     # the run's warnings so far, in order
    resumed_rows: list = field(default_factory=list)      # rows of the run restarted from
    job_rows: list = field(default_factory=list)          # every row so far (resumed ones first)
    solver: object = None                                 # the increment loop of the current step
    newton: object = None
    step_index: int = 0
    contact_stats: dict = field(default_factory=dict)    # first contact, largest penetration
    attempts: list = field(default_factory=list)          # each step's RunResult (failed attempts)

    @property
    def failures(self) -> dict:
        """Failed attempts per cause so far (those of the run restarted from among them)."""
        out: dict = {}
        for rr in self.attempts:
            for cause, count in rr.failures.items():
                out[cause] = out.get(cause, 0) + count
        return out

    @property
    def comm(self):
        return self.model.comm


def _topics(run: Run) -> set[str]:
    """What the run has warned of so far: each warning's topic, the words before its colon."""
    return {w.split(":")[0] for w in run.warnings}


class Job:
    """A body, its items, the steps, the probes and the writers (see the module docstring)."""

    def __init__(self, body, items=(), steps=(), probes=(), writers=(), newton: NewtonSettings | None = None,
                 load: Callable[[float], float] | None = None, form_options: dict | None = None):
        self.body, self.items = body, list(items)
        self.steps = list(steps) or [Step()]
        self.probes, self.writers = list(probes), list(writers)
        self.newton, self.load, self.form_options = newton or NewtonSettings(), load, form_options
        for s in self.steps:
            if not isinstance(s, Step):
                raise JobError(f"steps: {s!r} is not a Step")
        columns = ["step", "time", "load"] + [c for p in self.probes for c in p.columns]
        if len(set(columns)) != len(columns):
            dup = sorted({c for c in columns if columns.count(c) > 1})
            raise JobError(f"the history would have the column(s) {dup} twice: rename a probe")
        self.columns = columns + ["newton_its", "wall_s"]

    def run(self, progress: bool = False, restart=None) -> Results:
        """Compile, run every step, write; returns the :class:`Results` (also when a step fails).
        ``restart``: a checkpoint folder (io.Checkpoint) to go on from, on any number of ranks.
        The form compiler's INFO lines are not shown (:func:`quiet_compilers`)."""
        with quiet_compilers():
            return self._run(progress, restart)

    def _run(self, progress: bool, restart) -> Results:
        t_start, before = time.perf_counter(), process_clock()[0]
        timer = Timer()
        for item in self.items:              # the same items may serve an earlier run
            item.reset()
        with timer("setup and compilation"):
            model = Model(self.body, self.items)
            model.finalize(self.form_options)
        self.model = model
        comm = model.comm
        contacts = [item for item in self.items if item.kind == "contact"]
        for c in contacts:
            c.check_start()
        for p in self.probes:
            p.attach(model)
        run = Run(self, model, self.columns)
        res = Results(list(self.columns), dofs=model.num_dofs())
        saved = None
        if restart is not None:
            from .io import checkpoint
            saved = checkpoint.load(restart, comm, self)       # refuses another job's checkpoint
            run.resumed_rows = [dict(r) for r in saved[0]["rows"]]
            res.rows = [dict(r) for r in run.resumed_rows]
            res.increments = [Increment(int(r["step"]), float(r["time"]), int(r["newton_its"]), float(r["wall_s"]))
                              for r in res.rows]
        run.job_rows = res.rows
        stats = {"first_contact_load": None, "max_penetration": 0.0}
        if saved is not None:
            stats.update(saved[0].get("contact", {}))
            run.warnings = list(saved[0].get("warnings", []))
        run.contact_stats = stats
        if saved is not None:                # the failed attempts before the checkpoint
            run.attempts.append(RunResult(failures=dict(saved[0].get("failures", {}))))
        with timer("output"):
            for w in self.writers:
                collective(comm, w.open, run)
        newton = Newton(model, self.newton, timer)
        run.newton = newton
        # the bar on rank 0 and only on a terminal (disable=None): a log file gets the console's lines
        bar = tqdm(total=len(self.steps), unit="step", disable=True if not progress or comm.rank != 0 else None,
                   bar_format="{l_bar}{bar}| {n:.3f}/{total:.0f} [{elapsed}<{remaining}]")
        try:
            with Interrupts(comm) as interrupts:      # (parallel.py)
                newton.poll = interrupts.check
                for k, step in enumerate(self.steps):
                    if saved is not None and k < saved[0]["step_index"]:
                        step.start(self.items, model)          # done before the checkpoint: its
                        continue                               # releases (the restore sets the rest)
                    step.start(self.items, model)
                    self._check_supports(run, model, k)
                    if step.release:
                        newton.factorised = False     # its tangent still holds the supports
                    solver = IncrementalSolver(model, step.settings(), newton)
                    run.solver, run.step_index = solver, k
                    resume = None
                    if saved is not None:
                        from .io import checkpoint
                        resume = checkpoint.restore(*saved, model, newton)
                        saved = None
                    rr, last = RunResult(), 0.0
                    run.attempts.append(rr)
                    for inc in solver.increments(rr, resume):
                        t = k + inc.load
                        row = {"step": len(res.rows) + 1, "time": t,
                               "load": self.load(t) if self.load is not None else t}
                        with timer("probes and checks"):
                            for p in self.probes:
                                row.update(collective(comm, p, model))
                            row.update(newton_its=inc.newton_its, wall_s=inc.wall_s)
                            for c in contacts:
                                z = c.zone()
                                stats["max_penetration"] = max(stats["max_penetration"], z.max_penetration)
                                if z.in_contact and stats["first_contact_load"] is None:
                                    stats["first_contact_load"] = row["load"]
                            self._guards(run, row, contacts, stats)
                            res.rows.append(row)
                            res.increments.append(inc)
                        with timer("output"):
                            for w in self.writers:
                                collective(comm, w.write, run, row, inc)
                        interrupts.check()
                        bar.update(inc.load - last)
                        last = inc.load
                    if not rr.completed:
                        res.advice = rr.advice
                        name = f" {step.name!r}" if step.name else ""
                        res.message = f"step {k + 1}{name}: {rr.message}" if len(self.steps) > 1 else rr.message
                        break
                else:
                    res.completed = True
                    res.message = f"completed {len(res.rows)} increments"
        except KeyboardInterrupt as err:
            res.completed, res.interrupted = False, True
            res.message = f"interrupted ({err or 'Ctrl-C'}) after {len(res.rows)} converged increments"
            raise
        finally:
            newton.poll = None
            bar.close()
            res.wall_s = time.perf_counter() - t_start
            res.failures = run.failures
            self._account(res, timer, before)
            res.contact = stats if contacts else {}
            self._check_workspace(run)             # also when no increment converged
            res.warnings = list(run.warnings)
            for w in self.writers:
                collective(comm, w.close, run, res)
        return res

    @staticmethod
    def _account(res: Results, timer: Timer, before: float) -> None:
        """The timing of the whole process: what came before the run (start-up, imports, mesh), the
        parts the run timed, the rest of the run; and the process's wall and CPU seconds."""
        wall, cpu, compiler = process_clock()
        parts = {"before the run (start-up, imports, mesh)": before, **timer.totals}
        parts["other"] = max(res.wall_s - sum(timer.totals.values()), 0.0)
        report = Timer()
        report.totals.update(parts)
        res.timing = dict(parts)
        res.process = {"wall_s": wall, "cpu_s": cpu, "compiler_cpu_s": compiler}
        res.timing_report = (f"{report.report()}\nprocess: wall {wall:.2f} s, CPU {cpu + compiler:.2f} s "
                             f"({compiler:.2f} s of it in the C compiler)")

    def _check_supports(self, run: Run, model: Model, k: int) -> None:
        """Warn (once) when a step starts with supports that leave a rigid-body motion free."""
        free = model.free_motions()
        if free and "supports" not in _topics(run):
            when = f"from step {k + 1} " if len(self.steps) > 1 else ""
            run.warnings.append(
                f"supports: {when}the supports leave the body free to move rigidly ({', '.join(free)}); "
                "only contact can hold it there, and until it does the tangent is singular and that "
                "motion is left to round-off: add a support")

    @staticmethod
    def _check_workspace(run: Run) -> None:
        """Warn (once) when MUMPS ran out of workspace and the solver gave it more (solver/linear.py,
        grow_workspace): each time costs a new analysis and factorisation."""
        grown = run.newton.workspace
        if grown is not None and "linear solver" not in _topics(run):
            run.warnings.append(
                f"linear solver: MUMPS's workspace was too small for a tangent and was raised to {grown} % "
                "over its estimate, each time with a new analysis and factorisation: start with "
                f"-comove_mat_mumps_icntl_14 {grown} (the solver's PETSc options, docs/performance.md)")

    #: a penetration beyond this fraction of the smallest cell is warned about
    PENETRATION_WARNING = 0.02

    def _guards(self, run: Run, row: dict, contacts, stats) -> None:
        """Warn (once each) of a plastic strain beyond the hardening table and of a penetration that
        is a sizeable part of an element: results that are computed but should not be trusted; and
        of a linear solver that had to be given more workspace (the run repeats factorisations)."""
        self._check_workspace(run)
        m, said = run.model, _topics(run)
        if m.plastic is not None and "plastic strain" not in said:
            last = m.plastic.hardening.strain[-1]
            p = m.comm.allreduce(float(m.p.x.array.max()) if m.p.x.array.size else 0.0, op=MPI.MAX)
            if len(m.plastic.hardening.strain) > 1 and p > last:
                run.warnings.append(
                    f"plastic strain: {p:.3g} at increment {row['step']} (time {row['time']:.4g}) is beyond the "
                    f"hardening table's last point ({last:.3g}), where the yield stress is extrapolated "
                    f"(slope {m.plastic.hardening.tail_slope:.3g}): extend the table")
        if contacts and "penetration" not in said:
            h = m.comm.allreduce(min(float(c.h.x.array.min()) for c in contacts), op=MPI.MIN)
            pen = stats["max_penetration"]
            if pen > self.PENETRATION_WARNING * h:
                run.warnings.append(
                    f"penetration: {pen:.3g} at increment {row['step']} is {100 * pen / h:.0f} % of the smallest "
                    "element: raise gamma0, use nitsche, or refine the mesh")


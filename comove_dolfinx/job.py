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
job maps it (``load=lambda time: ...``, e.g. a physical load level). The field writers (VTK, XDMF)
label each increment's fields with its ``time``, which always increases (the load may go down and
up again).

Data flows one way: the job compiles the model, runs the increment loop of each step
(solver/increments.py), turns every converged increment into a history row (the probes) and gives
it to the writers; nothing calls back into the problem. A step that cannot go on ends the job with
its message; the results hold every increment converged before.

The job's parts, each in a module of its own beside this one: the stages of the loading
(steps.py: :class:`Step`, :class:`JobError`), the increment loop that turns converged increments
into rows for the writers (loop.py), what the run gives and what writers see while it runs
(results.py: :class:`Results`, :class:`RunState`), the restart from a checkpoint (restart.py), the
warnings of results to look at (guards.py), and the process around it: the form compiler's log
lines and the clocks (process.py). Their public names are importable from here as before.
"""
from __future__ import annotations

import sys
import time
from typing import Callable

from . import startup
from .deprecated import warn_renamed
from .guards import PENETRATION_WARNING, check_workspace
from .loop import IncrementLoop
from .checks import check_job
from .mechanics.model import Model
from .parallel import Interrupts, collective
from .process import _CompilerLines, account, process_clock, quiet_compilers  # noqa: F401 - importable here
from .restart import Restart
from .results import Results, RunState
from .solver import Newton, NewtonSettings, Timer
from .steps import JobError, Step

__all__ = ["Job", "JobError", "Results", "RunState", "Step", "process_clock", "quiet_compilers"]


#: the clock of a job's timer (its timing print and ``Results.timing``): wall time; the output
#: benchmark sets ``time.process_time`` (benchmarks/output_share.py)
TIMING_CLOCK = time.perf_counter

class Job:
    """A body, its items, the steps, the probes and the writers (see the module docstring).

    ``items``, ``probes`` and ``writers`` are lists, ``steps`` a non-empty list of :class:`Step`
    (left out: one ``Step()``). A single item where a list belongs is refused, with the fix "pass
    [item]", and so is an empty list of steps or a probe of a contact that is not one of the items
    (checks.check_job: :class:`JobError`, ``ProbeError``).
    """

    def __init__(self, body, items=(), steps=None, probes=(), writers=(), newton: NewtonSettings | None = None,
                 load: Callable[[float], float] | None = None, form_options: dict | None = None):
        check_job(body, items, steps, probes, writers, newton, load)
        self.body, self.items = body, list(items)
        self.steps = [Step()] if steps is None else list(steps)
        self.probes, self.writers = list(probes), list(writers)
        self.newton, self.load, self.form_options = newton or NewtonSettings(), load, form_options
        for s in self.steps:
            if not isinstance(s, Step):
                raise JobError(f"steps: {s!r} is not a Step")
        columns = ["increment", "time", "load"] + [c for p in self.probes for c in p.columns]
        if len(set(columns)) != len(columns):
            dup = sorted({c for c in columns if columns.count(c) > 1})
            raise JobError(f"the history would have the column(s) {dup} twice: rename a probe")
        self.columns = columns + ["newton_its", "wall_s"]

    #: a penetration beyond this fraction of the smallest cell is warned about (guards.py)
    PENETRATION_WARNING = PENETRATION_WARNING

    def run(self, progress: bool = False, restart=None) -> Results:
        """Compile, run every step, write; returns the :class:`Results` (also when a step fails).
        ``restart``: a checkpoint folder (io.Checkpoint) to go on from, on any number of ranks.
        The form compiler's INFO lines are not shown (:func:`quiet_compilers`)."""
        with quiet_compilers():
            return self._run(progress, restart)

    def _run(self, progress: bool, restart) -> Results:
        """:meth:`run` itself: compile, start (or go on from ``restart``), open the writers, run the
        increment loop (loop.py), and finish, also after a failure or an interrupt."""
        t_start, before = time.perf_counter(), process_clock()[0]
        timer, first = Timer(TIMING_CLOCK), startup.claim()
        with startup.part("setup and compilation"):
            model = self._compile(timer)
        run, res, resumed = self._start(model, restart)
        with timer("output"), startup.part("writers opened"):
            for w in self.writers:
                collective(model.comm, w.open, run)
        newton = Newton(model, self.newton, timer)
        run.newton = newton
        bar = _progress_bar(len(self.steps), progress and model.comm.rank == 0)
        loop = IncrementLoop(self, run, res, newton, timer, resumed)
        try:
            with Interrupts(model.comm) as interrupts:      # (parallel.py)
                newton.poll = interrupts.check
                if first:                   # the process's start-up ends here (its timing print)
                    res.startup = {**startup.PARTS, "total": startup.cpu_now()}
                loop.steps(interrupts, bar)
        except KeyboardInterrupt as err:
            res.completed, res.interrupted = False, True
            res.message = f"interrupted ({err or 'Ctrl-C'}) after {len(res.rows)} converged increments"
            raise
        finally:
            newton.poll = None
            bar.close()
            res.wall_s = time.perf_counter() - t_start
            self._finish(run, res, timer, before, bool(loop.contacts))
        return res

    def _compile(self, timer: Timer) -> Model:
        """The job's model, compiled, with its contacts checked and the probes attached to it."""
        for item in self.items:              # the same items may serve an earlier run
            item.reset()
        with timer("setup and compilation"):
            model = Model(self.body, self.items)
            model.finalize(self.form_options)
        self.model = model
        for item in self.items:
            if item.kind == "contact":
                item.check_start()
        for p in self.probes:
            p.attach(model)
        return model

    def _start(self, model, restart) -> tuple[RunState, Results, Restart | None]:
        """The run state and the results as the run starts, and the checkpoint it goes on from
        (``restart``: a checkpoint folder, or None), whose rows, warnings and failed attempts the
        state and the results then hold."""
        run = RunState(self, model, self.columns)
        res = Results(list(self.columns), dofs=model.num_dofs())
        run.contact_stats = {"first_contact_load": None, "max_penetration": 0.0}
        resumed = Restart(restart, model.comm, self) if restart is not None else None
        if resumed is not None:
            resumed.resume_records(run, res)
        run.job_rows = res.rows
        return run, res, resumed

    def _finish(self, run: RunState, res: Results, timer: Timer, before: float, contact: bool) -> None:
        """The run's closing figures (failed attempts, timing, contact statistics, warnings) into
        ``res``, then every writer closed."""
        res.failures = run.failures
        account(res, timer, before)
        res.contact = run.contact_stats if contact else {}
        check_workspace(run)             # also when no increment converged
        res.warnings = list(run.warnings)
        for w in self.writers:
            collective(run.comm, w.close, run, res)


class _NoBar:
    """The progress bar where none is shown."""

    def update(self, n: float) -> None:
        pass

    def close(self) -> None:
        pass


def _progress_bar(steps: int, wanted: bool):
    """A bar over the steps, advanced by the load factor, if ``wanted`` (rank 0) and only on a
    terminal: a log file gets the console's lines (and tqdm is not loaded for nothing)."""
    if not wanted or not sys.stderr.isatty():
        return _NoBar()
    from tqdm import tqdm
    return tqdm(total=steps, unit="step", bar_format="{l_bar}{bar}| {n:.3f}/{total:.0f} [{elapsed}<{remaining}]")


def __getattr__(name: str):
    """The old name of :class:`RunState` (``Run``), with a DeprecationWarning."""
    if name == "Run":
        warn_renamed("comove_dolfinx.job.Run", "RunState")
        return RunState
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")

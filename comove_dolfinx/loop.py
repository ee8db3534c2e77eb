"""A job's increment loop: each step's increments (solver/increments.py) turned into history rows
and handed to the writers.

For every step the loop starts the step (its releases and ramps, steps.py), warns of free supports
(guards.py), and runs the step's increment loop with Newton; each converged increment becomes a
history row (``increment``, ``time``, ``load``, the probes' columns, ``newton_its``, ``wall_s``),
the contact statistics and the guards are brought up to date, and every writer gets the row while
the model still holds the increment. A step that cannot go on ends the loop with its message.
"""
from __future__ import annotations

from .guards import check_increment, check_supports
from .parallel import collective
from .solver import IncrementalSolver, StepOutcome
from .io.csv_tables import Columns


class IncrementLoop:
    """The steps of ``job`` run with ``newton`` into the run state ``run`` (results.RunState) and
    ``results``; ``restart`` (restart.Restart or None) the checkpoint the run goes on from,
    ``timer`` (solver.Timer) times the probes and the output."""

    def __init__(self, job, run, results, newton, timer, restart=None):
        self.job, self.run, self.results = job, run, results
        self.newton, self.timer, self.restart = newton, timer, restart
        self.model, self.comm = run.model, run.model.comm
        self.contacts = [item for item in job.items if item.kind == "contact"]

    def steps(self, interrupts, bar) -> None:
        """Run every step (``interrupts``: parallel.Interrupts, checked after every increment;
        ``bar``: the progress bar, advanced by the load factor); the results say how it ended."""
        job, res = self.job, self.results
        for k, step in enumerate(job.steps):
            if self.restart is not None and self.restart.done_before(k):
                step.start(job.items, self.model)      # done before the checkpoint: its releases
                continue                               # (the restore sets the rest)
            outcome = self.step(k, step, interrupts, bar)
            if not outcome.completed:
                res.advice = outcome.advice
                name = f" {step.name!r}" if step.name else ""
                res.message = f"step {k + 1}{name}: {outcome.message}" if len(job.steps) > 1 else outcome.message
                return
        res.completed = True
        res.message = f"completed {len(res.rows)} increments"

    def step(self, k: int, step, interrupts, bar) -> StepOutcome:
        """Run the step ``step`` (number ``k`` from 0): every converged increment recorded and
        handed out; how the step's increment loop ended."""
        job, run, model, newton = self.job, self.run, self.model, self.newton
        step.start(job.items, model)
        check_supports(run, k, len(job.steps))
        if step.release:
            newton.factorised = False     # its tangent still holds the supports
        solver = IncrementalSolver(model, step.settings(), newton)
        run.solver, run.step_index = solver, k
        resume = self.restart.take(model, newton) if self.restart is not None else None
        outcome, last = StepOutcome(), 0.0
        run.attempts.append(outcome)
        for inc in solver.increments(outcome, resume):
            row = self.record(k, inc)
            with self.timer("output"):
                for w in job.writers:
                    collective(self.comm, w.write, run, row, inc)
            interrupts.check()
            bar.update(inc.load - last)
            last = inc.load
        return outcome

    def record(self, k: int, inc) -> Columns:
        """The history row of the converged increment ``inc`` of step ``k``, with the contact
        statistics and the guards brought up to date, appended to the results."""
        job, res, stats = self.job, self.results, self.run.contact_stats
        t = k + inc.load
        row = Columns({"increment": len(res.rows) + 1, "time": t,
                       "load": job.load(t) if job.load is not None else t})
        with self.timer("probes and checks"):
            for p in job.probes:
                row.update(collective(self.comm, p, self.model))
            row.update(newton_its=inc.newton_its, wall_s=inc.wall_s)
            for c in self.contacts:
                z = c.zone()
                stats["max_penetration"] = max(stats["max_penetration"], z.max_penetration)
                if z.in_contact and stats["first_contact_load"] is None:
                    stats["first_contact_load"] = row["load"]
            check_increment(self.run, row, self.contacts, job.PENETRATION_WARNING)
            res.rows.append(row)
            res.increments.append(inc)
        return row

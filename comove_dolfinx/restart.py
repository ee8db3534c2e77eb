"""Going on from a checkpoint (io/checkpoint.py): what a restarted job takes over from the run that
wrote it.

The history rows, the contact statistics, the warnings and the failed attempts before the
checkpoint go into the new run's state and results (:meth:`Restart.resume_records`); the steps done
before it are started again only for their releases (:meth:`Restart.done_before`); the step it
was written in restores the model, its items and Newton, and hands the increment loop the dict it
goes on from (:meth:`Restart.take`), once.
"""
from __future__ import annotations

from .solver import Increment, StepOutcome
from .io.csv_tables import Columns


class Restart:
    """The newest checkpoint in ``folder``, read on every rank of ``comm`` (any number of ranks); with
    ``job``, refused unless it is that job's (io/checkpoint.py, check_job)."""

    def __init__(self, folder, comm, job=None):
        from .io import checkpoint
        self.meta, self.parts = checkpoint.load(folder, comm, job)
        self.pending = True             # the model is not restored yet

    def resume_records(self, run, results) -> None:
        """Put what the run restarted from recorded into the run state ``run`` (results.RunState)
        and ``results``: its rows, increments, contact statistics, warnings and failed attempts."""
        meta = self.meta
        run.resumed_rows = [Columns(r) for r in meta["rows"]]
        results.rows = [Columns(r) for r in run.resumed_rows]
        results.increments = [Increment(int(r["increment"]), float(r["time"]), int(r["newton_its"]),
                                        float(r["wall_s"])) for r in results.rows]
        run.contact_stats.update(meta.get("contact", {}))
        run.warnings = list(meta.get("warnings", []))
        run.attempts.append(StepOutcome(failures=dict(meta.get("failures", {}))))

    def done_before(self, step_index: int) -> bool:
        """Whether the step ``step_index`` (from 0) ended before the checkpoint was written."""
        return self.pending and step_index < self.meta["step_index"]

    def take(self, model, newton) -> dict | None:
        """Put the model, its items and Newton back at the checkpoint, the first time only; the
        increment loop's resume dict (None after the first time)."""
        if not self.pending:
            return None
        from .io import checkpoint
        self.pending = False
        return checkpoint.restore(self.meta, self.parts, model, newton)

"""What a job gives: :class:`Results` (the history's columns and rows, the increments, what failed,
the timing), and :class:`RunState`, what its writers see while it runs.

A history row is a :class:`comove_dolfinx.tables.Columns`: a column that was renamed
(``step``, now ``increment``) still reads under its old name, with a DeprecationWarning.
"""
from __future__ import annotations

import warnings
from dataclasses import dataclass, field

import numpy as np

from .io.csv_tables import RENAMED


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
    startup: dict = field(default_factory=dict)     # CPU seconds before the first increment, per part
                                                    # and "total" (the process's first job only)
    process: dict = field(default_factory=dict)     # wall_s, cpu_s, compiler_cpu_s of the process
    contact: dict = field(default_factory=dict)
    interrupted: bool = False       # by a signal or Ctrl-C (the exception goes on after the writers)
    warnings: list = field(default_factory=list)
    failures: dict = field(default_factory=dict)    # failed attempts per cause (solver/failures.py)
    advice: str = ""                # what to change, when a step stopped at its smallest increment

    def __getitem__(self, column: str) -> np.ndarray:
        """The column as an array, one value per converged increment (a renamed column's old name,
        tables.RENAMED, gives the column with a DeprecationWarning)."""
        if column not in self.columns and RENAMED.get(column) in self.columns:
            warnings.warn(f"the history column {column!r} is now called {RENAMED[column]!r}",
                          DeprecationWarning, stacklevel=2)
            column = RENAMED[column]
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
class RunState:
    """What writers see of a running job (their ``run`` argument): the job, its compiled model,
    the history's columns, the rows and warnings so far, the increment loop and Newton of the
    current step, the contact statistics and the failed attempts of every step so far."""

    job: object                                           # the Job
    model: object                                         # its compiled mechanics.model.Model
    columns: list[str]
    warnings: list[str] = field(default_factory=list)     # the run's warnings so far, in order
    resumed_rows: list = field(default_factory=list)      # rows of the run restarted from
    job_rows: list = field(default_factory=list)          # every row so far (resumed ones first)
    solver: object = None                                 # the increment loop of the current step
    newton: object = None
    step_index: int = 0
    contact_stats: dict = field(default_factory=dict)    # first contact, largest penetration
    attempts: list = field(default_factory=list)          # each step's StepOutcome (failed attempts)

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

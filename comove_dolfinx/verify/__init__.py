"""Verification against published benchmarks (docs/verification.md).

    comove verify all --out results/verify      # or one case by name

Each case is a module of this package with

* ``NAME`` (its name on the command line), ``TITLE`` and ``SOURCE`` (the publication it checks);
* ``run(out: pathlib.Path, small: bool = False) -> list[Check]``: builds the problem with the public
  API, runs it, writes ``out/NAME.png`` (and whatever tables it keeps) and returns one
  :class:`Check` per compared quantity. ``small`` takes the coarse mesh of the test suite, with the
  tolerance that mesh is known to reach. A quantity that needs a feature this version lacks is
  returned as a skipped check (``skipped`` says why), which the table shows and which is no failure.

The command (verify/runner.py) runs each case as a process of its own and gathers the checks into
one table; it exits with 0 only when every check holds.

Nothing heavy is imported here: the command checks its arguments before dolfinx is loaded.
:data:`CASES` lists the cases by name in the order ``all`` runs them; a name whose module is not
(yet) in the package is skipped by ``all`` with a line saying so (:func:`available`).
"""
from __future__ import annotations

import math
import pathlib
from dataclasses import asdict, dataclass

#: every case by its name on the command line (the name of its module in this package)
CASES = ("patch", "hertz_line", "hertz_sphere", "indentation", "cattaneo_mindlin", "punch", "slices", "plate3d",
         "necking")


def available(name: str) -> bool:
    """Whether the case ``name`` has its module in this package's folder (not imported here; an
    editable install's finder could otherwise offer a module of another checkout)."""
    return name in CASES and (pathlib.Path(__file__).parent / f"{name}.py").is_file()


@dataclass
class Check:
    """One compared quantity of a benchmark: the result against its reference."""

    benchmark: str        # e.g. "Hertz line contact"
    source: str           # the publication the reference comes from
    quantity: str         # e.g. "contact half-width a"
    reference: float
    result: float
    tolerance: float      # the largest relative error accepted
    newton_its: int = 0   # Newton iterations of the run(s) behind the result
    cpu_s: float = 0.0    # CPU seconds of those runs (process time, all ranks' sum / ranks)
    skipped: str = ""     # why the check could not run here (then it counts as no failure)

    @property
    def error(self) -> float:
        """Relative error ``|result - reference| / |reference|`` (absolute where the reference is 0)."""
        scale = abs(self.reference) if self.reference != 0 else 1.0
        return abs(self.result - self.reference) / scale

    @property
    def ok(self) -> bool:
        """Within tolerance (a skipped check is no failure: see :attr:`status`)."""
        if self.skipped:
            return True
        return math.isfinite(self.result) and self.error <= self.tolerance

    @property
    def status(self) -> str:
        """"ok", "FAIL" or "skipped"."""
        return "skipped" if self.skipped else ("ok" if self.ok else "FAIL")

    def row(self) -> dict:
        return {**asdict(self), "error": float(self.error), "ok": bool(self.ok), "status": self.status}

"""Verification against published benchmarks (docs/verification.md).

    comove verify all --out results/verify      # or one case by name

Each case is a module of this package with

* ``NAME`` (its name on the command line), ``TITLE`` and ``SOURCE`` (the publication it checks);
* ``run(out: pathlib.Path, small: bool = False) -> list[Check]``: builds the problem with the public
  API, runs it, writes ``out/NAME.png`` (and whatever tables it keeps) and returns one
  :class:`Check` per compared quantity. ``small`` takes the coarse mesh of the test suite, with the
  tolerance that mesh is known to reach.

Nothing heavy is imported here: the command checks its arguments before dolfinx is loaded.
"""
from __future__ import annotations

import math
from dataclasses import asdict, dataclass


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

    @property
    def error(self) -> float:
        """Relative error ``|result - reference| / |reference|`` (absolute where the reference is 0)."""
        scale = abs(self.reference) if self.reference != 0 else 1.0
        return abs(self.result - self.reference) / scale

    @property
    def ok(self) -> bool:
        return math.isfinite(self.result) and self.error <= self.tolerance

    def row(self) -> dict:
        return {**asdict(self), "error": self.error, "ok": self.ok}

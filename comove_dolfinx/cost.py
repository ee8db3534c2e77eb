"""Deprecated: the cost benchmarks are :mod:`comove_dolfinx.benchmarks` (docs/performance.md).

``python -m comove_dolfinx.cost STUDY ...`` still runs ``python -m comove_dolfinx.benchmarks STUDY
...``, and ``comove_dolfinx.cost.NAME`` still gives the benchmarks' ``NAME`` (e.g. ``SlopeProbe``),
each with a DeprecationWarning.
"""
import warnings

_MESSAGE = "comove_dolfinx.cost is deprecated: use comove_dolfinx.benchmarks"


def __getattr__(name: str):
    from . import benchmarks
    value = getattr(benchmarks, name)            # AttributeError for a name the benchmarks lack
    warnings.warn(f"{_MESSAGE} (comove_dolfinx.benchmarks.{name})", DeprecationWarning, stacklevel=2)
    return value


if __name__ == "__main__":
    warnings.warn(f"{_MESSAGE} (python -m comove_dolfinx.benchmarks)", DeprecationWarning, stacklevel=1)
    from comove_dolfinx.benchmarks.command import main
    main(prog="python -m comove_dolfinx.cost")

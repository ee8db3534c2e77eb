"""``python -m comove_dolfinx.benchmarks STUDY ...`` (see :mod:`comove_dolfinx.benchmarks.command`)."""
from .command import main

main()

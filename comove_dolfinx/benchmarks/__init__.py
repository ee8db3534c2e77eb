"""Benchmarks of the solver's cost: a tool beside the library, not part of its API (docs/performance.md).

What a Newton iteration costs against plain dolfinx's on the same mesh and against what it cannot
cost less than, the linear solvers, the MPI ranks, the residual along Newton's correction, and the
parts of an iteration. Each study writes CSV files and charts into ``--out`` and never asserts::

    python -m comove_dolfinx.benchmarks dolfinx --out results/cost   # ring: iteration vs plain dolfinx
    python -m comove_dolfinx.benchmarks floor   --out results/cost   # ring: iteration vs linear-elastic floor
    python -m comove_dolfinx.benchmarks parts   --out results/cost   # ring: each part, alone and in the loop
    python -m comove_dolfinx.benchmarks solvers --out results/cost   # ring: direct solvers, orderings, GAMG
    mpirun -n 2 python -m comove_dolfinx.benchmarks scale --out results/cost   # ring, plate: 1 or 2 ranks
    python -m comove_dolfinx.benchmarks slopes  --out results/cost   # ring: the residual along du
    python -m comove_dolfinx.benchmarks output  --out results/cost   # scenes, demos: the output's share

The modules: ``runs`` (a scene's short run, the linear-elastic floor, a factorisation with another
solver), ``plain_dolfinx`` (the neo-Hookean problem solved by dolfinx alone), ``iteration_dolfinx``
(dolfinx), ``iteration_floor`` (floor), ``loop_parts`` (parts), ``linear_solvers`` (solvers),
``ranks`` (scale), ``line_search`` (slopes), ``output_share`` (output), ``charts`` and ``command``
(the command line).

CPU time is ``time.process_time`` (the process's, not the machine's); every figure is the median of
``--repeats`` runs with its spread (max - min) beside it. Other processes on the machine lengthen
wall times, and CPU times much less.

The names below are imported on first use: importing the package loads neither dolfinx nor MPI.
"""

_WHERE = {"RING_SIZES": "runs", "ElasticFloor": "runs", "build": "runs", "short_run": "runs",
          "factor_solve": "runs", "PlainNeoHooke": "plain_dolfinx",
          "against_dolfinx": "iteration_dolfinx", "floor": "iteration_floor", "floor_chart": "charts",
          "parts": "loop_parts", "SOLVERS": "linear_solvers", "solvers": "linear_solvers",
          "SCALE": "ranks", "scale": "ranks", "SLOPE_STEPS": "line_search", "SlopeProbe": "line_search",
          "slopes": "line_search", "output": "output_share", "main": "command"}
__all__ = sorted(_WHERE)

from .. import lazy_names  # noqa: E402

__getattr__, __dir__ = lazy_names(__name__, _WHERE, globals())

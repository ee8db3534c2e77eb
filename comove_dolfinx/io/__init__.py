"""Writers: what a job writes as it goes (plug-ins of :class:`comove_dolfinx.Job`).

A writer has ``open(run)`` (``run``: the job's run state, comove_dolfinx.results.RunState: the
compiled model, the history's columns, the job), ``write(run, row, increment)`` after every
converged increment (before the state moves on) and ``close(run, results)`` at the end, also after
a failure. Every rank calls them; a failure on one rank stops all.

The names below are imported on first use, so that ``comove_dolfinx.io.folder`` (the output folder's
checks, which the command makes before it loads dolfinx) and ``comove_dolfinx.io.csv_tables`` (the
CSV tables: histories, and the tables of the study, the stability map and the benchmarks; csv and
NumPy only, read by the study's parent process without dolfinx) stay light.
"""

_WHERE = {"Snapshots": "plots", "draw_plane": "plots", "snapshot_grid": "plots", "VTK": "vtk",
          "Console": "writers", "HistoryCSV": "writers", "RunInfo": "writers", "Writer": "writers",
          "read_history": "csv_tables", "XDMF": "xdmf", "FibreStress": "xdmf"}
__all__ = sorted(_WHERE)

from .. import lazy_names  # noqa: E402

__getattr__, __dir__ = lazy_names(__name__, _WHERE, globals())

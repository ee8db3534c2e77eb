"""Writers: what a job writes as it goes (plug-ins of :class:`comove_dolfinx.Job`).

A writer has ``open(run)`` (the compiled model, the history's columns, the job), ``write(run, row,
increment)`` after every converged increment (before the state moves on) and ``close(run, results)``
at the end, also after a failure. Every rank calls them; a failure on one rank stops all.
"""
from .plots import Snapshots, draw_plane, snapshot_grid
from .vtk import VTK
from .writers import Console, HistoryCSV, RunInfo, Writer, read_history
from .xdmf import XDMF, FibreStress

__all__ = ["VTK", "XDMF", "Console", "FibreStress", "HistoryCSV", "RunInfo", "Snapshots", "Writer", "draw_plane",
           "read_history", "snapshot_grid"]

"""Gmsh's Python module, imported, started and finalised without taking Ctrl-C away from Python.

Gmsh's Python API sets SIGINT to the system's default action (the process dies without a word) so
that Ctrl-C can stop a long meshing: gmsh 4.8 when the module is imported, 4.13 in ``initialize``,
and neither gives the previous handler back on every path (4.13's ``finalize`` never does). A run
that followed a mesh build would then die at Ctrl-C instead of ending cleanly with its increments
written (job.py, cli.py). Here every such call keeps Python's handler as it was.
"""
from __future__ import annotations

import contextlib
import signal
import threading


@contextlib.contextmanager
def _sigint_kept():
    """Python's SIGINT handler as it was before the block (handlers live in the main thread)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    handler = signal.getsignal(signal.SIGINT)
    try:
        yield
    finally:
        if handler is not None:                     # None: not installed from Python, leave it
            signal.signal(signal.SIGINT, handler)


with _sigint_kept():
    import gmsh


def start() -> None:
    """Initialize gmsh without user configuration files and with terminal output off."""
    with _sigint_kept():
        gmsh.initialize(readConfigFiles=False)
    gmsh.option.setNumber("General.Terminal", 0)  # errors still raise, with gmsh's message


def stop() -> None:
    """Finalize gmsh."""
    with _sigint_kept():
        gmsh.finalize()

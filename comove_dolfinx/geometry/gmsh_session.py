"""Gmsh's Python module, imported on first use, started and finalised without taking Ctrl-C away
from Python.

Gmsh's Python API sets SIGINT to the system's default action (the process dies without a word) so
that Ctrl-C can stop a long meshing: gmsh 4.8 when the module is imported, 4.13 in ``initialize``,
and neither gives the previous handler back on every path (4.13's ``finalize`` never does). A run
that followed a mesh build would then die at Ctrl-C instead of ending cleanly with its increments
written (job.py, cli.py). Here every such call holds SIGINT and SIGTERM back and puts Python's
handler back before letting them through: a signal that came meanwhile is handled then.

:data:`gmsh` stands for the module and imports it at the first use of one of its names (a run
whose mesh is in the cache never loads gmsh, geometry/meshes.py); :func:`version` tells its
version without importing it.
"""
from __future__ import annotations

import contextlib
import importlib
import importlib.util
import re
import signal
import sys
import threading

_SIGNALS = {signal.SIGINT, signal.SIGTERM}


@contextlib.contextmanager
def _sigint_kept():
    """SIGINT and SIGTERM held back within the block, then Python's handlers put back as they were
    before it and the signals let through (handlers live in the main thread)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    handlers = {sig: signal.getsignal(sig) for sig in _SIGNALS}
    signal.pthread_sigmask(signal.SIG_BLOCK, _SIGNALS)
    try:
        yield
    finally:
        for sig, handler in handlers.items():
            if handler is not None:                 # None: not installed from Python, leave it
                signal.signal(sig, handler)
        signal.pthread_sigmask(signal.SIG_UNBLOCK, _SIGNALS)


def _module():
    """Gmsh's module, imported with the signals held (above) the first time."""
    module = sys.modules.get("gmsh")
    if module is None:
        with _sigint_kept():
            module = importlib.import_module("gmsh")
    return module


class _Gmsh:
    """Gmsh's module, imported at the first use of one of its names (attributes read and set pass
    through to it)."""

    def __getattr__(self, name: str):
        return getattr(_module(), name)

    def __setattr__(self, name: str, value) -> None:
        setattr(_module(), name, value)

    def __repr__(self) -> str:
        return "<gmsh, imported on first use>" if "gmsh" not in sys.modules else repr(sys.modules["gmsh"])


#: gmsh's module, imported on first use
gmsh = _Gmsh()


def version() -> str | None:
    """Gmsh's version (``gmsh.__version__``) without importing it where its module says it in the
    line ``GMSH_API_VERSION = "x.y.z"`` (Debian's and PyPI's gmsh.py do); None without gmsh."""
    if "gmsh" in sys.modules:
        return sys.modules["gmsh"].__version__
    spec = importlib.util.find_spec("gmsh")
    if spec is None:
        return None
    try:
        with open(spec.origin, encoding="utf-8") as fh:
            found = re.search(r'^GMSH_API_VERSION\s*=\s*"([^"]+)"', fh.read(20000), re.MULTILINE)
    except (OSError, TypeError, UnicodeDecodeError):
        found = None
    return found.group(1) if found else _module().__version__


def start() -> None:
    """Initialize gmsh without user configuration files and with terminal output off."""
    with _sigint_kept():
        _module().initialize(readConfigFiles=False)
    gmsh.option.setNumber("General.Terminal", 0)  # errors still raise, with gmsh's message


def stop() -> None:
    """Finalize gmsh."""
    with _sigint_kept():
        _module().finalize()


@contextlib.contextmanager
def opened(path, what: str, error):
    """Gmsh started with the user's file ``path`` open, and finalised after the block; a file that
    Gmsh cannot read raises ``error`` (the caller's exception type) in one line that names it as
    the ``what`` file."""
    start()
    try:
        try:
            gmsh.open(str(path))
        except Exception as err:                  # noqa: BLE001 - gmsh raises plain Exception
            raise error(f"{what} file {path}: gmsh cannot read it ({err})") from None
        yield gmsh
    finally:
        stop()

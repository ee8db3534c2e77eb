"""The process's start-up: the CPU seconds of its parts before the first increment, and the
imports made cheaper where a library loads more than it uses.

The ``comove`` command records its parts (:func:`part`): the interpreter up to the command
(``python``), the arguments' checks, the imports, the output folder, the mesh; the job adds the
set-up and compilation of its forms and the opening of its writers. The first job of the process
reports them with the CPU seconds of the whole start-up (up to its first increment) in its timing
print (process.py: the parts not recorded are "other"), so that the start-up's share of the run can be read there.

Nothing here imports dolfinx, mpi4py or NumPy: the command uses it before they load.
"""
from __future__ import annotations

import contextlib
import resource
import sys
import types

#: part name -> CPU seconds (this process and the children it waited for) spent in it
PARTS: dict[str, float] = {}
_claimed = False


def cpu_now() -> float:
    """CPU seconds of this process and of the child processes it waited for (the C compiler)."""
    me, kids = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
    return me.ru_utime + me.ru_stime + kids.ru_utime + kids.ru_stime


def begin() -> None:
    """Start the record (the command's first act): the CPU seconds so far are the interpreter's
    start and the command's own import (``python``)."""
    global _claimed
    PARTS.clear()
    PARTS["python"] = cpu_now()
    _claimed = False


@contextlib.contextmanager
def part(name: str):
    """Add the CPU seconds of the block to the part ``name``."""
    start = cpu_now()
    try:
        yield
    finally:
        PARTS[name] = PARTS.get(name, 0.0) + cpu_now() - start


def claim() -> bool:
    """True for the first job of the process (whose start-up the record is), False after."""
    global _claimed
    first, _claimed = not _claimed, True
    return first


@contextlib.contextmanager
def versions_without_pkg_resources():
    """Within the block, ``import pkg_resources`` gives a small stand-in whose ``get_distribution(name)
    .version`` comes from importlib.metadata: UFL and FFCx of Debian 12 import pkg_resources (a
    tenth of a second) only for their own version. Any other name of it loads the real module,
    as does a version that importlib.metadata cannot find; after the block an import gets the real
    one. Nothing changes where pkg_resources is loaded already."""
    if "pkg_resources" in sys.modules:
        yield
        return
    stand_in = types.ModuleType("pkg_resources")

    def real():
        if sys.modules.get("pkg_resources") is stand_in:
            del sys.modules["pkg_resources"]
        import pkg_resources
        return pkg_resources

    def get_distribution(name: str):
        import importlib.metadata
        try:
            return types.SimpleNamespace(version=importlib.metadata.version(name), project_name=name)
        except importlib.metadata.PackageNotFoundError:
            return real().get_distribution(name)

    stand_in.get_distribution = get_distribution
    stand_in.__getattr__ = lambda name: getattr(real(), name)
    sys.modules["pkg_resources"] = stand_in
    try:
        yield
    finally:
        if sys.modules.get("pkg_resources") is stand_in:
            del sys.modules["pkg_resources"]

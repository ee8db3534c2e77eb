"""The process around a job: the form compiler's log lines kept off the console
(:func:`quiet_compilers`), the process's wall and CPU clock (:func:`process_clock`), and the timing
report of a run (:func:`account`).
"""
from __future__ import annotations

import contextlib
import logging
import os
import time

from .solver import Timer


class _CompilerLines(logging.Filter):
    """Drops the progress lines of the form compiler's C build (INFO and below, logged on the root
    logger by the distutils of setuptools that cffi drives) and the INFO of ffcx and UFL; every
    other record passes."""

    SOURCES = ("distutils", "setuptools", "cffi")

    def filter(self, record: logging.LogRecord) -> bool:
        if record.levelno >= logging.WARNING:
            return True
        if record.name.split(".")[0] in ("ffcx", "UFL", "ufl"):
            return False
        path = record.pathname.replace("\\", "/")
        return not (record.name == "root" and any(f"/{s}" in path for s in self.SOURCES))


@contextlib.contextmanager
def quiet_compilers():
    """Within the block, the form compiler's INFO lines are not shown; afterwards the root logger
    has its level back (distutils lowers it to INFO for every later record of the process).

    The user's own logging stays as it was: records of other loggers pass, and the filter comes
    off when the block ends. :meth:`Job.run` runs inside it."""
    root = logging.getLogger()
    level, filt = root.level, _CompilerLines()
    handlers = list(root.handlers)
    root.addFilter(filt)                 # records logged on the root logger itself (distutils)
    for h in handlers:                   # and those that reach its handlers from ffcx's or UFL's
        h.addFilter(filt)
    try:
        yield
    finally:
        root.removeFilter(filt)
        for h in handlers:
            h.removeFilter(filt)
        root.setLevel(level)


def process_clock() -> tuple[float, float, float]:
    """(wall seconds since this process started, CPU seconds of the process, CPU seconds of the
    child processes it waited for: the C compiler of the form compiler). The start is read from
    /proc (Linux); elsewhere the wall time counts from the import of this module."""
    import resource
    me, kids = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
    try:
        with open("/proc/self/stat") as fh:
            start = float(fh.read().rsplit(")", 1)[1].split()[19]) / os.sysconf("SC_CLK_TCK")
        with open("/proc/uptime") as fh:
            wall = float(fh.read().split()[0]) - start
    except (OSError, ValueError, IndexError):
        wall = time.perf_counter() - _IMPORTED
    return wall, me.ru_utime + me.ru_stime, kids.ru_utime + kids.ru_stime


_IMPORTED = time.perf_counter()


def account(results, timer: Timer, before: float) -> None:
    """Put the timing of the whole process into ``results`` (a job's Results): what came before the
    run (start-up, imports, mesh: ``before`` wall seconds), the parts the run timed (``timer``), the
    rest of the run; and the process's wall and CPU seconds. For the process's first job, the
    start-up's CPU seconds per part (``results.startup``, startup.py) and their line."""
    wall, cpu, compiler = process_clock()
    parts = {"before the run (start-up, imports, mesh)": before, **timer.totals}
    parts["other"] = max(results.wall_s - sum(timer.totals.values()), 0.0)
    report = Timer()
    report.totals.update(parts)
    results.timing = dict(parts)
    results.process = {"wall_s": wall, "cpu_s": cpu, "compiler_cpu_s": compiler}
    results.timing_report = (f"{report.report()}\nprocess: wall {wall:.2f} s, CPU {cpu + compiler:.2f} s "
                             f"({compiler:.2f} s of it in the C compiler)")
    if results.startup:
        parts = {k: v for k, v in results.startup.items() if k != "total"}
        parts["other"] = max(results.startup["total"] - sum(parts.values()), 0.0)
        results.startup = {**parts, "total": results.startup["total"]}
        results.timing_report += "\n" + startup_line(parts, results.startup["total"], cpu + compiler)


def startup_line(parts: dict, before: float, total: float) -> str:
    """The timing print's start-up line: the CPU seconds before the first increment (``before``, in
    ``parts``), their share of the process's (``total``)."""
    share = 100.0 * before / total if total > 0 else 0.0
    listed = ", ".join(f"{k} {v:.2f} s" for k, v in parts.items())
    return f"start-up (before the first increment): CPU {before:.2f} s of {total:.2f} s ({share:.0f} %): {listed}"

"""Where the study's runs go: a ``concurrent.futures`` executor (docs/study.md, "On a cluster").

* ``local`` (the default on one process): a thread pool of ``--jobs`` threads, each starting one
  ``comove run`` process at a time and waiting for it (runner.py), so that every case is a whole
  process whose CPU time the kernel accounts;
* ``mpi``: ``mpi4py.futures.MPIPoolExecutor`` when the study was started as::

      mpiexec -n N python -m mpi4py.futures -m comove_dolfinx.study SCENE ...

  rank 0 runs the study and hands the cases to the other N - 1 ranks, which may sit on other
  nodes; each of them starts the case's ``comove run`` process as the local pool does. ``auto``
  (the default) chooses ``mpi`` when started so, else ``local``.

Nothing here loads MPI: the launcher's environment says how many processes there are, and
``python -m mpi4py.futures`` has imported ``mpi4py.futures`` before the study's code runs (a study
started by ``mpiexec`` without it runs on every rank, and is refused).
"""
from __future__ import annotations

import os
import sys

KINDS = ("auto", "local", "mpi")

#: the variables by which an MPI launcher tells its processes that they belong to its job; a
#: ``comove run`` started by a worker of the MPI pool must not see them (it would take itself for
#: one more rank of the pool's job)
LAUNCHER_PREFIXES = ("OMPI_", "PMIX_", "PRTE_", "OPAL_", "PMI_", "HYDRA_", "HYDI_", "MPI_LOCAL")


def launcher_size() -> int:
    """The number of processes of the MPI job this one belongs to (1 without a launcher)."""
    for var in ("OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_SIZE"):
        if var in os.environ:
            return int(os.environ[var])
    return 1


def under_mpi_futures() -> bool:
    """Whether this process is rank 0 of ``python -m mpi4py.futures`` on two or more processes."""
    return "mpi4py.futures" in sys.modules and launcher_size() > 1


def choose(kind: str) -> tuple[str | None, str | None]:
    """(the executor to use, None) for ``--executor kind``, or (None, the one-line reason it cannot be)."""
    run_as = "mpiexec -n N python -m mpi4py.futures -m comove_dolfinx.study ..."
    futures = under_mpi_futures()
    if kind not in KINDS:
        return None, f"--executor {kind!r}: choose {', '.join(KINDS)}"
    if launcher_size() > 1 and "mpi4py.futures" not in sys.modules:
        return None, ("study: it starts its runs as processes of its own, two at a time (--jobs): "
                      f"start it without mpirun, or for a pool of MPI workers as {run_as}")
    if kind == "mpi" and not futures:
        return None, (f"--executor mpi: start the study as {run_as} (N >= 2: one process hands out "
                      "the runs, N - 1 run them)")
    if kind == "auto":
        kind = "mpi" if futures else "local"
    return kind, None


def make(kind: str, jobs: int):
    """A new executor of ``kind`` ("local" or "mpi"); ``jobs`` threads for local, the launcher's
    workers for mpi (``jobs`` is not used there)."""
    if kind == "mpi":
        from mpi4py.futures import MPIPoolExecutor
        return MPIPoolExecutor()
    from concurrent.futures import ThreadPoolExecutor
    return ThreadPoolExecutor(max_workers=jobs)


def workers(kind: str, jobs: int) -> int:
    """How many runs the executor of ``kind`` runs at a time."""
    return launcher_size() - 1 if kind == "mpi" else jobs


def child_environment() -> dict:
    """The environment of a ``comove run`` process: this one's without the launcher's variables,
    with one thread for BLAS and OpenMP."""
    env = {k: v for k, v in os.environ.items() if not k.startswith(LAUNCHER_PREFIXES)}
    env.update(OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1")
    return env

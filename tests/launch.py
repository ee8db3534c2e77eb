"""Python in a process of its own, serial or on n ranks under the MPI launcher of this Python's MPI:
Open MPI's mpirun for Debian's packages, the venv's mpiexec (MPICH) for the PyPI wheel."""
import os
import pathlib
import subprocess
import sys

_VENV_MPIEXEC = pathlib.Path(sys.executable).parent / "mpiexec"
LAUNCHER = str(_VENV_MPIEXEC) if _VENV_MPIEXEC.exists() else "mpirun"
# root may run Open MPI, more ranks than cores are allowed (Open MPI 4: OMPI_MCA_..., 5: PRTE_MCA_...)
ENV = dict(os.environ, MPLBACKEND="Agg", OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1",
           OMPI_ALLOW_RUN_AS_ROOT="1",
           OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1", OMPI_MCA_rmaps_base_oversubscribe="1",
           PRTE_MCA_rmaps_default_mapping_policy=":oversubscribe")


def command(args, n: int = 1) -> list:
    """``python args`` on n ranks."""
    cmd = [sys.executable, *map(str, args)]
    return [LAUNCHER, "-n", str(n), *cmd] if n > 1 else cmd


def run(args, n: int = 1, timeout: float = 600, **kwargs) -> subprocess.CompletedProcess:
    """Run ``python args`` on n ranks, capturing text output."""
    return subprocess.run(command(args, n), capture_output=True, text=True, env=ENV,
                          timeout=timeout, **kwargs)

"""Shared fixtures: an MPI-safe temporary folder, garbage collection between tests, UFL evaluation.

MPI is imported in the fixtures, not here: with pytest-xdist (``make test`` runs the serial suite on
workers, one per core) this file is also loaded by the controlling process, which starts the workers; an MPI
initialised there would leave its singleton's variables (OMPI_*, PMIX_*) in the workers' environment,
and an ``mpirun`` started by a test (launch.py) would then take itself for part of that job and exit.
``comove_dolfinx`` is imported here, which loads nothing heavy: its import hook runs the PyPI wheel's
MPI bootstrap before the first import of mpi4py or dolfinx, so that a test module that imports
dolfinx ahead of comove_dolfinx also runs alone."""
import gc
import logging
import os

import numpy as np
import pytest

import comove_dolfinx  # noqa: F401

os.environ.setdefault("MPLBACKEND", "Agg")
logging.disable(logging.INFO)          # ffcx/cffi compile chatter


@pytest.fixture
def comm():
    from mpi4py import MPI
    return MPI.COMM_WORLD


@pytest.fixture
def mpi_tmp(tmp_path, comm):
    """One temporary folder shared by all ranks (tmp_path differs per rank)."""
    return type(tmp_path)(comm.bcast(str(tmp_path), root=0))


@pytest.fixture(autouse=True)
def _collect(comm):
    yield
    gc.collect()
    comm.barrier()


@pytest.fixture(scope="session")
def unit_mesh():
    """A two-triangle unit square: enough to evaluate expressions of constants or affine fields."""
    from dolfinx import mesh
    from mpi4py import MPI
    return mesh.create_unit_square(MPI.COMM_SELF, 1, 1)


def evaluate(expr, msh, point=(1 / 3, 1 / 3)):
    """Value of a UFL expression at a reference point of cell 0 (shape of the expression)."""
    from comove_dolfinx import compat
    e = compat.expression(expr, np.array([point], dtype=float))
    return compat.evaluate(e, msh, np.array([0], dtype=np.int32)).reshape(expr.ufl_shape)

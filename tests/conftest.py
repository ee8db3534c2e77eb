"""Shared fixtures: an MPI-safe temporary folder, garbage collection between tests, UFL evaluation."""
import gc
import logging
import os

import numpy as np
import pytest
from mpi4py import MPI

os.environ.setdefault("MPLBACKEND", "Agg")
logging.disable(logging.INFO)          # ffcx/cffi compile chatter


@pytest.fixture
def comm():
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
    return mesh.create_unit_square(MPI.COMM_SELF, 1, 1)


def evaluate(expr, msh, point=(1 / 3, 1 / 3)):
    """Value of a UFL expression at a reference point of cell 0 (shape of the expression)."""
    from comove_dolfinx import compat
    e = compat.expression(expr, np.array([point], dtype=float))
    return compat.evaluate(e, msh, np.array([0], dtype=np.int32)).reshape(expr.ufl_shape)

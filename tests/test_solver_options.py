"""The linear solver through PETSc options under the prefix comove_ (solver/linear.py): another direct
solver gives MUMPS's solution to round-off, GMRES with algebraic multigrid (and the rigid-body
near-nullspace) agrees to its tolerance, and options PETSc cannot use end the run with a message
that names them, on every rank, instead of a hang; a failed MUMPS factorisation gives MUMPS's code."""
import numpy as np
import pytest
from mpi4py import MPI

from comove_dolfinx.mechanics.model import Model
from comove_dolfinx.presets import get_scene
from comove_dolfinx.solver import IncrementalSolver, NewtonSettings, StepSettings
from comove_dolfinx.solver.linear import PREFIX, SolverOptionError

ITERATIVE = {"ksp_type": "gmres", "pc_type": "gamg", "ksp_rtol": 1e-12, "ksp_max_it": 500,
             "ksp_gmres_restart": 100}


def _plate(options, max_cutbacks=6):
    """The plate scene (axisymmetric, follower pressure, frictional contact) over its first two
    increments of 10 (before contact: a bending plate), solved with the given options."""
    scene = get_scene("plate", ["size=0.3"])
    body, items, probes = scene.build(scene.mesh_data(MPI.COMM_WORLD))
    model = Model(body, items)
    model.finalize()
    solver = IncrementalSolver(model, StepSettings(n_steps=2, t_end=0.2, max_cutbacks=max_cutbacks),
                               NewtonSettings(petsc_options=options))
    return model, solver, solver.run()


def _nodal(model):
    """(x, y, u_x, u_y) of every node, sorted by position: independent of the partition (each run
    builds its own mesh, which may be distributed differently)."""
    n = model.V.dofmap.index_map.size_local
    rows = np.c_[model.V.tabulate_dof_coordinates()[:n, :2], model.u.x.array.reshape(-1, 2)[:n]]
    rows = np.concatenate(MPI.COMM_WORLD.allgather(rows))
    return rows[np.lexsort((rows[:, 1].round(12), rows[:, 0].round(12)))]


def _difference(model, reference):
    """max |u - u_ref| over the nodes and max |u_ref|."""
    rows = _nodal(model)
    assert np.allclose(rows[:, :2], reference[:, :2], atol=1e-12)
    return np.abs(rows[:, 2:] - reference[:, 2:]).max(), np.abs(reference[:, 2:]).max()


@pytest.fixture(scope="module")
def mumps():
    model, solver, res = _plate({})
    assert res.completed, res.message
    assert solver.newton.ksp.getPC().getFactorSolverType() == "mumps"
    return _nodal(model), res.newton_its


def test_petsc_lu_gives_the_mumps_solution(mumps):
    """PETSc's own LU (nested-dissection ordering) in place of MUMPS: the same iterations and the
    same displacements to round-off. Serial only: PETSc's LU does not run in parallel."""
    if MPI.COMM_WORLD.size > 1:
        pytest.skip("PETSc's own LU is sequential")
    model, solver, res = _plate({"pc_factor_mat_solver_type": "petsc",
                                 "pc_factor_mat_ordering_type": "nd"})
    assert res.completed, res.message
    assert solver.newton.ksp.getPC().getFactorSolverType() == "petsc"
    ref, its = mumps
    assert res.newton_its == its
    diff, size = _difference(model, ref)
    assert diff <= 1e-10 * size


@pytest.mark.mpi
def test_gmres_with_multigrid_agrees_with_mumps(mumps):
    """GMRES + GAMG to rtol 1e-12 (the rigid-body modes as near-nullspace): Newton converges to the
    same state to well within its own tolerance (measured 4e-16 of the largest displacement; 1e-8
    asserted), in the same number of iterations."""
    model, solver, res = _plate(ITERATIVE)
    assert res.completed, res.message
    ksp = solver.newton.ksp
    assert (ksp.getType(), ksp.getPC().getType()) == ("gmres", "gamg")
    assert ksp.getOperators()[0].getNearNullSpace() is not None
    ref, its = mumps
    assert res.newton_its == its
    diff, size = _difference(model, ref)
    assert diff <= 1e-8 * size


@pytest.mark.mpi
def test_unknown_solver_type_is_refused_at_once():
    with pytest.raises(SolverOptionError, match="ksp_type=bogus"):
        _plate({"ksp_type": "bogus"})
    with pytest.raises(SolverOptionError, match="not an option name"):
        _plate({"": 1})


@pytest.mark.mpi
def test_bad_factorisation_option_stops_the_run_with_its_message():
    """An ordering MUMPS does not have is found at the first factorisation: every attempt fails,
    the run stops at load 0 on every rank with PETSc's message, and the options are gone from PETSc's
    database afterwards (the next model does not inherit them)."""
    model, solver, res = _plate({"mat_mumps_icntl_7": 99}, max_cutbacks=1)
    assert not res.completed and not res.increments
    assert "linear solve" in res.message, res.message
    assert "Valid values" in res.message or "out of range" in res.message.lower(), res.message
    messages = MPI.COMM_WORLD.allgather(res.message)
    assert all(m == messages[0] for m in messages)
    from petsc4py import PETSc
    assert not PETSc.Options().hasName(PREFIX + "mat_mumps_icntl_7")


@pytest.mark.mpi
def test_a_failed_mumps_factorisation_says_why():
    """MUMPS's memory limit set to 1 MB (ICNTL(23) = 1), below what the plate's factors need, fails
    the factorisation with MUMPS's error -19 on any number of ranks: the run stops on every rank
    with a message that gives MUMPS's code and the option that cures it (solver/linear.py,
    MUMPS_HINTS)."""
    model, solver, res = _plate({"mat_mumps_icntl_23": 1}, max_cutbacks=1)
    assert not res.completed and not res.increments
    assert "KSP reason -11; MUMPS INFOG(1) = -19" in res.message, res.message
    assert "-comove_mat_mumps_icntl_23 is too low" in res.message, res.message
    messages = MPI.COMM_WORLD.allgather(res.message)
    assert all(m == messages[0] for m in messages)

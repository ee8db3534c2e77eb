"""The iterative linear solver (NewtonSettings.linear_solver, solver/krylov.py): GMRES with algebraic
multigrid reaches the states of the direct solve in about as many Newton iterations, its
near-nullspace is the kernel of the tangent of a body moved rigidly, and a Krylov solve that stops
short is a recorded failure that halves the increment, never an exception."""
from dataclasses import replace

import numpy as np
import pytest
from mpi4py import MPI
from petsc4py import PETSc

from comove_dolfinx import compat, geometry
from comove_dolfinx.checks import SettingsError
from comove_dolfinx.mechanics.body import Body
from comove_dolfinx.mechanics.material_data import Elastic
from comove_dolfinx.mechanics.model import Model
from comove_dolfinx.presets import get_scene
from comove_dolfinx.solver import IncrementalSolver, NewtonSettings, failures, krylov


def _ring(linear_solver, options=None, n=2, **steps):
    """The ring scene (plane strain, J2, penalty contact with a plane) at a coarse size over its
    first ``n`` nominal increments, solved with the given linear solver."""
    scene = get_scene("ring", ["size=0.22"])
    body, items, _ = scene.build(scene.mesh_data(MPI.COMM_WORLD))
    model = Model(body, items)
    model.finalize()
    settings = replace(scene.newton_settings(), linear_solver=linear_solver,
                       petsc_options=dict(options or {}))
    steps = replace(scene.steps()[0].settings(), n_increments=n, t_end=n / scene.n_increments, **steps)
    solver = IncrementalSolver(model, steps, settings)
    return model, solver, solver.run()


def _nodal(model):
    """(x, y, u_x, u_y) of every node sorted by position (independent of the partition)."""
    n = model.V.dofmap.index_map.size_local
    rows = np.c_[model.V.tabulate_dof_coordinates()[:n, :2], model.u.x.array.reshape(-1, 2)[:n]]
    rows = np.concatenate(MPI.COMM_WORLD.allgather(rows))
    return rows[np.lexsort((rows[:, 1].round(12), rows[:, 0].round(12)))]


@pytest.fixture(scope="module")
def direct():
    model, solver, res = _ring("mumps")
    assert res.completed, res.message
    assert solver.newton.krylov_its == [0] * len(solver.newton.krylov_its)
    return _nodal(model), sum(i.newton_its + i.failed_its for i in res.increments), res.increments


def _has_pc(pc: str) -> bool:
    """Whether this PETSc was built with the preconditioner ``pc`` (the PyPI wheel's has no hypre)."""
    try:
        PETSc.PC().create(PETSc.COMM_SELF).setType(pc)
        return True
    except PETSc.Error:
        return False


@pytest.mark.mpi
@pytest.mark.parametrize("name, pc", [("gamg", "gamg"), ("hypre", "hypre")])
def test_multigrid_gives_the_direct_history(direct, name, pc):
    """At Krylov's default tolerance (1e-8 on the true residual) the run takes the increments of
    the direct solve with Newton iterations within 20 % of its, and ends at its state to well
    within Newton's tolerance (1e-6 of the largest displacement asserted); on two ranks too (the
    direct solve's own history being the serial one to round-off: test_parallel). Where PETSc was
    built without the preconditioner (the PyPI wheel has no hypre), skipped."""
    if not _has_pc(pc):
        pytest.skip(f"this PETSc has no {pc}")
    model, solver, res = _ring(name)
    assert res.completed, res.message
    ksp = solver.newton.ksp
    assert (ksp.getType(), ksp.getPC().getType()) == ("gmres", pc)
    ref, its, incs = direct
    mine = sum(i.newton_its + i.failed_its for i in res.increments)
    assert [i.load for i in res.increments] == pytest.approx([i.load for i in incs], abs=1e-12)
    assert abs(mine - its) <= 0.2 * its, (mine, its)
    assert solver.newton.krylov_its and min(solver.newton.krylov_its) >= 1
    rows = _nodal(model)
    assert np.abs(rows[:, 2:] - ref[:, 2:]).max() <= 1e-6 * np.abs(ref[:, 2:]).max()


@pytest.mark.mpi
def test_a_krylov_solve_that_stops_short_is_a_failure_and_a_cutback():
    """Two Krylov iterations reach neither 1e-8 nor krylov.KRYLOV_ACCEPT: every attempt fails with
    the cause "krylov", the increment is halved down to its smallest size, and the run stops with
    the message (the residual reached) and the advice (the iteration limit or the direct solver),
    on every rank alike."""
    model, solver, res = _ring("gamg", {"ksp_max_it": 2}, n=1, max_cutbacks=2, first=1.0,
                                 retry=False)
    assert not res.completed and not res.increments
    assert res.failures == {failures.KRYLOV: 3}          # the nominal increment and two halvings
    assert "did not converge" in res.message and "after 2 iterations" in res.message, res.message
    assert "relative residual" in res.message
    assert "ksp_max_it" in res.advice and "mumps" in res.advice



@pytest.mark.mpi
def test_a_krylov_solve_stopped_near_its_tolerance_is_an_inexact_newton_step(direct):
    """A tolerance out of reach (1e-13) with a limit of 40 iterations: the solves stop at the limit
    with their residuals far below krylov.KRYLOV_ACCEPT, are taken as inexact Newton steps, and
    the run takes the direct solve's increments, with no failure, Newton iterations within 20 % of
    its and its state (a solve counted as failed would halve the increment instead)."""
    model, solver, res = _ring("gamg", {"ksp_max_it": 40, "ksp_rtol": 1e-13})
    assert res.completed and not res.failures, res.message
    assert solver.newton.inexact_solves >= 1
    ref, its, incs = direct
    assert [i.load for i in res.increments] == pytest.approx([i.load for i in incs], abs=1e-12)
    assert abs(sum(i.newton_its + i.failed_its for i in res.increments) - its) <= 0.2 * its
    rows = _nodal(model)
    assert np.abs(rows[:, 2:] - ref[:, 2:]).max() <= 1e-6 * np.abs(ref[:, 2:]).max()


def test_linear_solver_names_are_checked_and_auto_is_the_default_by_size():
    with pytest.raises(SettingsError, match="linear_solver = 'ilu'"):
        NewtonSettings(linear_solver="ilu")
    assert krylov.chosen("auto", 10 ** 9, 2) == "mumps"
    assert NewtonSettings().linear_solver == "auto"
    assert krylov.chosen("auto", 199_999, 3) == "mumps" and krylov.chosen("auto", 200_000, 3) == "gamg"
    assert krylov.chosen("hypre", 10, 2) == "hypre"


@pytest.fixture(scope="module")
def block():
    return geometry.rectangle(1.0, 0.5, 0.125, order=2, comm=MPI.COMM_WORLD)


def _rotated(md, angle):
    """A free block (no support, no load) of neo-Hooke material displaced by a rigid rotation of
    ``angle`` about a point away from it and a translation: a stress-free current configuration;
    the tangent assembled there, without constraints."""
    model = Model(Body(md, "plane_strain", Elastic(1000.0, 0.3), update="neo_hooke"))
    model.finalize()
    X = model.V.tabulate_dof_coordinates()[:, :2]
    c, s = np.cos(angle), np.sin(angle)
    x = (X - [2.0, -1.0]) @ np.array([[c, s], [-s, c]]) + [2.0, -1.0] + [0.3, 0.7]
    model.u.x.array[:] = (x - X).ravel()
    model.evaluate_stress(True)
    A = compat.create_matrix(model.jacobian_form)
    compat.assemble_matrix(A, model.jacobian_form)
    return model, A


def _relative_kernel_residuals(A, space):
    """||A z|| / (||A|| ||z||) for each vector z of a PETSc null space."""
    norm = A.norm(PETSc.NormType.FROBENIUS)
    out = []
    for z in space.getVecs():
        y = A.createVecLeft()
        A.mult(z, y)
        out.append(y.norm() / (norm * z.norm()))
    return out


@pytest.mark.mpi
def test_near_nullspace_is_the_rigid_motions_of_the_current_configuration(block):
    """Rotated rigidly by 60 degrees the block is stress-free, so its tangent maps every rigid motion
    of the current configuration to zero (relative 1e-12 asserted; round-off); the rotation about
    the reference configuration is no such motion (relative above 1e-3), which the
    near-nullspace built on x = X + u avoids. The vectors are orthonormal."""
    model, A = _rotated(block, np.pi / 3)
    current = krylov.near_nullspace(model.V, A, model.u.x.array)
    assert len(current.getVecs()) == 3
    assert max(_relative_kernel_residuals(A, current)) < 1e-12
    reference = krylov.near_nullspace(model.V, A, None)
    assert _relative_kernel_residuals(A, reference)[2] > 1e-3
    vecs = current.getVecs()
    gram = np.array([[a.dot(b) for b in vecs] for a in vecs])
    assert np.allclose(gram, np.eye(3), atol=1e-12)

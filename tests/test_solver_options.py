"""The linear solver through PETSc options under the prefix comove_ (solver/linear.py): another direct
solver gives MUMPS's solution to round-off, GMRES with algebraic multigrid (and the rigid-body
near-nullspace) agrees to its tolerance, and options PETSc cannot use end the run with a message
that names them, on every rank, instead of a hang; a failed MUMPS factorisation gives MUMPS's code,
is done again with more workspace when that is what it lacked, and stops the run at once when no
smaller increment can cure it."""
import numpy as np
import pytest
from mpi4py import MPI

from comove_dolfinx.mechanics.model import Model
from comove_dolfinx.presets import get_scene
from comove_dolfinx.solver import IncrementalSolver, NewtonSettings, StepSettings
from comove_dolfinx.solver.linear import PREFIX, SolverOptionError, make_ksp, matrix_kind

ITERATIVE = {"ksp_type": "gmres", "pc_type": "gamg", "ksp_rtol": 1e-12, "ksp_max_it": 500,
             "ksp_gmres_restart": 100}


def _plate(options, max_cutbacks=6):
    """The plate scene (axisymmetric, follower pressure, frictional contact) over its first two
    increments of 10 (before contact: a bending plate), solved with the given options."""
    scene = get_scene("plate", ["size=0.3"])
    body, items, probes = scene.build(scene.mesh_data(MPI.COMM_WORLD))
    model = Model(body, items)
    model.finalize()
    solver = IncrementalSolver(model, StepSettings(n_increments=2, t_end=0.2, max_cutbacks=max_cutbacks),
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


@pytest.mark.parametrize("options, kind", [
    ({}, "baij"),
    ({"pc_factor_mat_solver_type": "petsc"}, "baij"),
    ({"pc_factor_mat_solver_type": "superlu_dist"}, None),
    ({"pc_factor_mat_solver_type": "umfpack"}, None),
    ({"pc_type": "cholesky"}, None),
    (ITERATIVE, None),
])
def test_the_matrix_type_follows_the_solver(options, kind):
    """An LU factorisation by MUMPS or PETSc gets the blocked matrix (BAIJ); solvers that take AIJ
    only (SuperLU_dist, UMFPACK), MUMPS's Cholesky and the iterative ones get dolfinx's default."""
    ksp = make_ksp(MPI.COMM_WORLD, None, options)
    assert matrix_kind(ksp) == kind
    ksp.destroy()


@pytest.mark.mpi
def test_the_blocked_tangent_is_the_tangent():
    """Newton's matrix with MUMPS is BAIJ; the plate's tangent assembled into it holds the entries of
    the same tangent assembled into dolfinx's AIJ, to the last bit on one rank (the same sums in the
    same order; on two, where rows shared with another rank are summed as the exchanges arrive, to
    round-off), and MUMPS solves the two to the same correction."""
    from comove_dolfinx import compat
    model, solver, res = _plate({})
    assert res.completed, res.message
    newton = solver.newton
    assert newton.A.getType() in ("seqbaij", "mpibaij")
    compat.assemble_matrix(newton.A, model.jacobian_form, model.bcs)
    plain = compat.create_matrix(model.jacobian_form)
    assert plain.getType() in ("seqaij", "mpiaij")
    compat.assemble_matrix(plain, model.jacobian_form, model.bcs)
    from petsc4py import PETSc
    blocked = newton.A.convert("aij", PETSc.Mat())      # a copy (without out: in place)
    blocked.axpy(-1.0, plain)
    diff, size = blocked.norm(), plain.norm()
    if MPI.COMM_WORLD.size == 1:
        assert diff == 0.0 and size > 0.0
    else:          # the entries from other ranks are summed in the order the exchanges arrive
        assert diff <= 1e-14 * size
    rhs = newton.b.duplicate()
    rhs.setRandom()
    solutions = []
    for A in (newton.A, plain):
        ksp = make_ksp(MPI.COMM_WORLD, A, {})
        x = rhs.duplicate()
        ksp.solve(rhs, x)
        assert ksp.getConvergedReason() > 0
        solutions.append(x)
        ksp.destroy()
    solutions[0].axpy(-1.0, solutions[1])
    assert solutions[0].norm() <= 1e-12 * solutions[1].norm()
    for obj in (plain, blocked, rhs, *solutions):
        obj.destroy()


@pytest.mark.mpi
def test_mumps_scales_nothing_unless_asked_and_gives_the_same_solution(mumps):
    """MUMPS factorises without its scaling by default (ICNTL(8) = 0, linear.MUMPS_DEFAULTS); with
    its own default (77: a row and column scaling at each factorisation) given in the settings, the
    plate takes the same iterations to the same displacements, to round-off. A value in PETSc's
    database (PETSC_OPTIONS) is left to it."""
    from petsc4py import PETSc
    from comove_dolfinx.solver.linear import with_defaults
    ref, its = mumps
    for options, icntl_8 in (({}, 0), ({"mat_mumps_icntl_8": 77}, 77)):
        model, solver, res = _plate(options)
        assert res.completed, res.message
        assert solver.newton.ksp.getPC().getFactorMatrix().getMumpsIcntl(8) == icntl_8
        assert res.newton_its == its
        diff, size = _difference(model, ref)
        assert diff <= 1e-10 * size
    db = PETSc.Options()
    db.setValue(PREFIX + "mat_mumps_icntl_8", "77")
    try:
        assert "mat_mumps_icntl_8" not in with_defaults({})
    finally:
        db.delValue(PREFIX + "mat_mumps_icntl_8")
    assert with_defaults({})["mat_mumps_icntl_8"] == 0
    assert with_defaults({"-mat_mumps_icntl_8": 7}) == {"-mat_mumps_icntl_8": 7}


@pytest.mark.mpi
def test_superlu_dist_gives_the_mumps_solution(mumps):
    """SuperLU_dist, which takes AIJ only, runs on dolfinx's default matrix and gives MUMPS's
    iterations and displacements to round-off (skipped where PETSc was built without it)."""
    from petsc4py import PETSc
    if not PETSc.Sys.hasExternalPackage("superlu_dist"):
        pytest.skip("this PETSc has no SuperLU_dist")
    model, solver, res = _plate({"pc_factor_mat_solver_type": "superlu_dist"})
    assert res.completed, res.message
    assert solver.newton.A.getType() in ("seqaij", "mpiaij")
    ref, its = mumps
    assert res.newton_its == its
    diff, size = _difference(model, ref)
    assert diff <= 1e-10 * size


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


class _Attempts:
    """A Newton monitor counting the solves (increment attempts) that end."""

    def __init__(self):
        self.solves = 0

    def solved(self, newton, ok, its, reason):
        self.solves += 1


@pytest.mark.mpi
def test_a_failed_mumps_factorisation_says_why_and_stops_at_once():
    """MUMPS's memory limit set to 1 MB (ICNTL(23) = 1), below what the plate's factors need, fails
    the factorisation with MUMPS's error -19 on any number of ranks: the run stops on every rank
    with a message that gives MUMPS's code and the option that cures it (solver/linear.py,
    MUMPS_HINTS), after one attempt: a smaller increment needs the same memory, so the six
    cut-backs allowed are not spent."""
    attempts = _Attempts()
    scene = get_scene("plate", ["size=0.3"])
    body, items, probes = scene.build(scene.mesh_data(MPI.COMM_WORLD))
    model = Model(body, items)
    model.finalize()
    solver = IncrementalSolver(model, StepSettings(n_increments=2, t_end=0.2, max_cutbacks=6),
                               NewtonSettings(petsc_options={"mat_mumps_icntl_23": 1},
                                              monitor=attempts))
    res = solver.run()
    assert not res.completed and not res.increments
    assert "KSP reason -11; MUMPS INFOG(1) = -19" in res.message, res.message
    assert "-comove_mat_mumps_icntl_23 is too low" in res.message, res.message
    assert "no smaller increment cures" in res.message, res.message
    assert attempts.solves == 1
    messages = MPI.COMM_WORLD.allgather(res.message)
    assert all(m == messages[0] for m in messages)


def _saddle_point(comm, m=24, seed=2):
    """The matrix [[K, B^T], [B, 0]] of a constrained Laplacian: K the 5-point Laplacian on an m x m
    grid, B m^2/3 random constraints of three unknowns each; the zero block admits no diagonal
    pivot, so MUMPS must delay pivots, and with strict pivoting more than its analysis plans for.
    Rows split over the ranks in contiguous blocks; the same matrix on any number of ranks."""
    from petsc4py import PETSc
    n, k = m * m, (m * m) // 3
    rng = np.random.default_rng(seed)
    cons = [(rng.choice(n, 3, replace=False), rng.standard_normal(3)) for _ in range(k)]
    A = PETSc.Mat().createAIJ([n + k, n + k], comm=comm, nnz=(12, 12))
    A.setOption(PETSc.Mat.Option.NEW_NONZERO_ALLOCATION_ERR, False)
    lo, hi = A.getOwnershipRange()
    for i in range(lo, hi):
        if i < n:
            cols = [i] + [j for j in (i - 1, i + 1, i - m, i + m) if 0 <= j < n]
            vals = [4.0] + [-1.0] * (len(cols) - 1)
            for r, (c, v) in enumerate(cons):             # the columns of B^T in row i
                for cc, vv in zip(c, v):
                    if cc == i:
                        cols.append(n + r)
                        vals.append(vv)
        else:
            c, v = cons[i - n]
            cols, vals = list(c), list(v)
        A.setValues(i, np.asarray(cols, dtype=PETSc.IntType), np.asarray(vals), addv=True)
    A.assemble()
    return A


#: MUMPS held to strict pivoting: a pivot must be the largest of its column (threshold 1), with no
#: column permutation or scaling to bring large entries onto the diagonal; and no spare workspace
STRICT = {"mat_mumps_icntl_14": 0, "mat_mumps_cntl_1": 1.0, "mat_mumps_icntl_6": 0,
          "mat_mumps_icntl_8": 0}


@pytest.mark.mpi
def test_mumps_out_of_workspace_factorises_again_with_more():
    """A saddle-point matrix factorised with strict pivoting and no spare workspace: a plain solve fails
    with INFOG(1) = -9 (more delayed pivots than the analysis planned for); linear.solve doubles
    ICNTL(14) from 20 % until the factorisation fits, and its solution satisfies A x = b to round-off,
    on one or two ranks alike (measured: 20 to 160 % on MUMPS 5.5, 20 to 80 % on 5.7)."""
    from petsc4py import PETSc

    from comove_dolfinx.solver import linear
    comm = MPI.COMM_WORLD
    A = _saddle_point(comm)
    b = A.createVecLeft()
    b.set(1.0)
    x = b.duplicate()
    plain = linear.make_ksp(comm, A, STRICT)
    with linear.pushed(STRICT):
        plain.solve(b, x)
    assert plain.getConvergedReason() < 0
    assert linear.mumps_code(plain) == -9
    assert "its workspace was too small at 0 %" in linear.factor_error(plain)

    options = dict(STRICT)
    ksp = linear.make_ksp(comm, A, options)
    failure, grown = linear.solve(ksp, options, b, x, comm)
    assert failure is None and ksp.getConvergedReason() > 0
    assert grown == [20 * 2 ** k for k in range(len(grown))] and grown[-1] <= linear.MAX_WORKSPACE
    assert options["mat_mumps_icntl_14"] == grown[-1]
    assert ksp.getPC().getFactorMatrix().getMumpsIcntl(14) == grown[-1]
    r = b.duplicate()
    A.mult(x, r)
    r.axpy(-1.0, b)
    assert r.norm() <= 1e-10 * b.norm()
    assert not PETSc.Options().hasName(linear.PREFIX + "mat_mumps_icntl_14")
    for obj in (plain, ksp, A, b, x, r):
        obj.destroy()


@pytest.mark.mpi
def test_a_job_warns_once_when_mumps_needed_more_workspace(capsys):
    """The ring crushed in ten increments with MUMPS held to strict pivoting (a pivot must be the
    largest of its column, no permutation or scaling to help) and no spare workspace: a far-from-
    equilibrium iterate delays pivots beyond the analysis's estimate (-9). The solver factorises
    again with more, and the job says so once, on every rank alike, whether or not the run gets
    through (these increments are too large: it stops)."""
    import comove_dolfinx as cm
    from comove_dolfinx.io.writers import Console

    scene = get_scene("ring", [])
    body, items, probes = scene.build(scene.mesh_data(MPI.COMM_WORLD))
    job = cm.Job(body, items, [cm.Step(10, max_cutbacks=1)], writers=[Console("ring")],
                 newton=NewtonSettings(petsc_options=dict(STRICT)))
    res = job.run()
    said = [w for w in res.warnings if w.startswith("linear solver:")]
    assert len(said) == 1, res.warnings
    assert "raised to 20 %" in said[0] and "-comove_mat_mumps_icntl_14 20" in said[0]
    assert MPI.COMM_WORLD.allgather(said) == [said] * MPI.COMM_WORLD.size
    out = capsys.readouterr().out
    if MPI.COMM_WORLD.rank == 0:
        assert out.count("warning: linear solver:") == 1


def _fill_tridiagonal(A, middle: float) -> None:
    """The 1D Laplacian's entries (2, -1) into ``A``, its middle diagonal entry ``middle``."""
    n = A.getSize()[0]
    A.zeroEntries()
    lo, hi = A.getOwnershipRange()
    for i in range(lo, hi):
        cols = [j for j in (i - 1, i, i + 1) if 0 <= j < n]
        A.setValues(i, cols, [middle if i == j == n // 2 else (2.0 if i == j else -1.0) for j in cols])
    A.assemble()


@pytest.mark.mpi
def test_a_failed_solve_leaves_the_solver_usable():
    """Tangents with a NaN (iterates that left the stress update's range) fail their
    factorisation, and a solve after such a failure failed in MUMPS's solve phase with PETSc's
    error; then a sound tangent in the same matrix (a smaller increment) is solved right: no
    failure is left behind in the preconditioner (before, PETSc refused every later solve,
    "Cannot embed PCPreSolve() more than twice", so that each smaller increment failed for the first
    one's reason)."""
    from petsc4py import PETSc

    from comove_dolfinx.solver.linear import solve, with_defaults
    comm = MPI.COMM_WORLD
    options = with_defaults({})
    ksp = make_ksp(comm, None, options)
    A = PETSc.Mat().createAIJ([12, 12], comm=comm, nnz=(3, 2))
    ksp.setOperators(A)
    b, x = A.createVecs()
    b.set(1.0)
    errors = []
    for _ in range(3):
        _fill_tridiagonal(A, float("nan"))
        failure, _ = solve(ksp, options, b, x, comm)
        errors.append(failure)
    assert ksp.getConvergedReason() < 0                      # the NaN's factorisation failed
    _fill_tridiagonal(A, 2.0)
    failure, _ = solve(ksp, options, b, x, comm)
    assert failure is None and ksp.getConvergedReason() > 0, failure
    r = b.duplicate()
    A.mult(x, r)
    r.axpy(-1.0, b)
    assert r.norm() < 1e-12 * b.norm()

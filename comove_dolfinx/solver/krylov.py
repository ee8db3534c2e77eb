"""The iterative path of Newton's linear solver: a Krylov method preconditioned by algebraic multigrid.

``NewtonSettings.linear_solver`` chooses the linear solver by name (:data:`LINEAR_SOLVERS`):

* ``"mumps"``: the direct solve of linear.py (preonly, LU, MUMPS);
* ``"gamg"``: GMRES preconditioned by PETSc's smoothed-aggregation multigrid (:data:`GAMG`);
* ``"hypre"``: GMRES preconditioned by hypre's BoomerAMG with nodal coarsening and the vector
  interpolation that uses the rigid-body modes (:data:`HYPRE`);
* ``"auto"`` (the default): MUMPS below :data:`AUTO_DOFS` dofs of the body's dimension, GAMG from
  there on (2-D bodies: MUMPS at every size; 3-D bodies: GAMG from 200k dofs).

The name gives a set of PETSc options (keys without the prefix ``comove_``); the settings'
``petsc_options`` and PETSc's database (``PETSC_OPTIONS``) are read after them and win, so that
``{"ksp_type": "cg"}`` turns the GMRES of ``"gamg"`` into CG for a tangent known to be symmetric.
GMRES is the default because the tangent is in general not symmetric (Coulomb friction with the
current pressure, Nitsche's variants theta = 0 and -1, follower pressure, the convected stress
rates of the hypoelastic updates); it preconditions on the right, so that its tolerance
(:data:`KRYLOV_RTOL`) bounds the true residual ``||J du + R|| <= rtol ||R||``.

Both multigrid methods take the rigid-body motions of the current configuration ``x = X + u`` as the
matrix's near-nullspace (:func:`near_nullspace`: 3 in 2-D, 6 in 3-D, orthonormalised), set anew
on the matrix at every tangent (:func:`set_near_nullspace`); the matrix carries the block size of
the displacement (dolfinx sets it), which GAMG's aggregation and BoomerAMG's nodal coarsening read.
"""
from __future__ import annotations

import numpy as np
from mpi4py import MPI
from petsc4py import PETSc

from ..choices import LINEAR_SOLVERS  # noqa: F401 - the names, checked with the settings

#: Krylov's relative tolerance on the true residual: Newton's residual falls by at least this
#: factor per iteration from the linear error alone, far below the quadratic rate's until the
#: last iteration, so Newton takes the iterations it takes with a direct solve (docs/performance.md)
KRYLOV_RTOL = 1e-8
#: Krylov iterations before a solve stops (``ksp_max_it``)
KRYLOV_MAX_IT = 500
#: a solve stopped by the iteration limit is still Newton's step when its true residual has fallen by
#: this factor: an inexact Newton step, along which Newton's residual still falls by about as much
#: (the forcing term of inexact Newton methods; any factor below 1 keeps Newton converging, at a
#: linear rate), where halving the increment would cost the iterations of two; one that has not
#: fallen so far counts as failed (failures.KRYLOV: the increment is halved). GAMG's GMRES can
#: stagnate in a plastic zone, whose tangent is nearly incompressible (the bent block at 230k dofs:
#: 3.6e-3 after 500 iterations)
KRYLOV_ACCEPT = 1e-2

_GMRES = {"ksp_type": "gmres", "ksp_pc_side": "right", "ksp_gmres_restart": 100,
          "ksp_rtol": KRYLOV_RTOL, "ksp_atol": 0.0, "ksp_max_it": KRYLOV_MAX_IT}
#: smoothed aggregation with Chebyshev/Jacobi smoothing on the levels (PETSc's default smoother),
#: a drop threshold for weak couplings (keeps the coarse operators sparse on stretched cells)
GAMG = {**_GMRES, "pc_type": "gamg", "pc_gamg_type": "agg", "pc_gamg_agg_nsmooths": 1,
        "pc_gamg_threshold": 0.01,
        "mg_levels_ksp_type": "chebyshev", "mg_levels_pc_type": "jacobi",
        "mg_levels_ksp_max_it": 2}
#: BoomerAMG for systems: nodal coarsening on the block norms (6: the Frobenius norm of each
#: block), vector interpolation variant 2 (the near-nullspace's rigid motions interpolated
#: exactly; PETSc hands the matrix's near-nullspace to hypre when the variant is set), HMIS
#: coarsening with extended+i interpolation
HYPRE = {**_GMRES, "pc_type": "hypre", "pc_hypre_type": "boomeramg",
         "pc_hypre_boomeramg_nodal_coarsen": 6, "pc_hypre_boomeramg_vec_interp_variant": 2,
         "pc_hypre_boomeramg_coarsen_type": "HMIS", "pc_hypre_boomeramg_interp_type": "ext+i",
         "pc_hypre_boomeramg_strong_threshold": 0.25, "pc_hypre_boomeramg_P_max": 4}
PRESETS = {"mumps": {}, "gamg": GAMG, "hypre": HYPRE}
#: "auto" (the default) takes GAMG from this many dofs on (per dimension of the body; None: MUMPS at
#: every size). 2-D: MUMPS was faster per Newton iteration at every size measured
#: (docs/performance.md, the iterative solvers). 3-D: on the bent block (docs/solids.md, the
#: scaling table) MUMPS is faster at 56k dofs, the two cost the same per iteration at 230k with the
#: same Newton iterations, where GAMG needs a sixth of MUMPS's memory (0.9 GB against 5.3 GB), and
#: MUMPS's factors outgrow a workstation's memory soon after
AUTO_DOFS = {2: None, 3: 200_000}


def chosen(name: str, dofs: int, dim: int) -> str:
    """The linear solver that ``name`` stands for at ``dofs`` dofs in ``dim`` dimensions ("auto":
    MUMPS below :data:`AUTO_DOFS`, GAMG from there on; any other name stands for itself)."""
    if name != "auto":
        return name
    limit = AUTO_DOFS.get(dim)
    return "gamg" if limit is not None and dofs >= limit else "mumps"


def options_for(name: str, options: dict) -> dict:
    """The PETSc options (without the prefix) of the linear solver ``name`` (a resolved name, not
    "auto") with ``options`` (the settings' own) after them, so that the settings' win."""
    return {**PRESETS[name], **options}


def rigid_motions(V, u: np.ndarray | None = None) -> np.ndarray:
    """The rigid-body motions of the displacement space V (2 or 3 components per node) at this
    rank's owned nodes, at the current coordinates ``x = X + u`` (``u`` the displacement's local
    array, None for the reference ones): an array (owned nodes * components, motions) with the
    translations first, then the rotations about the centroid of all the nodes, each divided by
    the nodes' rms distance from it (so that all are of one magnitude). Collective."""
    bs = V.dofmap.index_map_bs
    n = V.dofmap.index_map.size_local
    x = V.tabulate_dof_coordinates()[:n, :bs].copy()
    if u is not None:
        x += np.asarray(u)[:n * bs].reshape(n, bs)
    comm = V.mesh.comm
    total = max(comm.allreduce(n, op=MPI.SUM), 1)
    d = x - comm.allreduce(x.sum(axis=0), op=MPI.SUM) / total
    size = float(np.sqrt(comm.allreduce(float((d ** 2).sum()), op=MPI.SUM) / total)) or 1.0
    d /= size
    rotations = [(0, 1)] if bs == 2 else [(1, 2), (2, 0), (0, 1)]    # e_k x d in the plane (i, j)
    modes = np.zeros((n, bs, bs + len(rotations)))
    for k in range(bs):
        modes[:, k, k] = 1.0
    for r, (i, j) in enumerate(rotations):
        modes[:, i, bs + r], modes[:, j, bs + r] = -d[:, j], d[:, i]
    return modes.reshape(n * bs, -1)


def orthonormal(modes: np.ndarray, comm) -> np.ndarray:
    """The columns of ``modes`` (this rank's rows of a distributed array) orthonormalised together,
    by the Cholesky factor of their global Gram matrix (one reduction)."""
    gram = comm.allreduce(modes.T @ modes, op=MPI.SUM)
    L = np.linalg.cholesky(gram)
    return np.linalg.solve(L, modes.T).T


def near_nullspace(V, A: PETSc.Mat, u: np.ndarray | None = None) -> PETSc.NullSpace:
    """The rigid-body motions of :func:`rigid_motions` at ``x = X + u``, orthonormalised, as a
    PETSc null space on A's layout. Collective."""
    values = orthonormal(rigid_motions(V, u), A.getComm().tompi4py())
    vectors = []
    for k in range(values.shape[1]):
        vec = A.createVecRight()
        vec.array[:] = values[:, k]
        vectors.append(vec)
    return PETSc.NullSpace().create(vectors=vectors, comm=A.getComm())


def set_near_nullspace(V, A: PETSc.Mat, u: np.ndarray) -> None:
    """Put the rigid motions at ``x = X + u`` on A as its near-nullspace (the multigrid set-up of the
    next solve reads them), replacing the previous ones."""
    space = near_nullspace(V, A, u)
    A.setNearNullSpace(space)
    space.destroy()                      # A holds its own reference


def iterations(ksp: PETSc.KSP) -> int:
    """The Krylov iterations of the KSP's last solve (0 for a direct solve: one application)."""
    if ksp.getType() == "preonly":
        return 0
    return int(ksp.getIterationNumber())


REASONS = {-3: "the iteration limit", -4: "divergence of the residual", -5: "a breakdown",
           -7: "a non-symmetric operator or preconditioner (CG)", -8: "an indefinite preconditioner",
           -9: "a NaN or Inf", -11: "a failed preconditioner set-up"}


def reached(ksp: PETSc.KSP, rhs: PETSc.Vec) -> float:
    """The relative residual ``||J du - rhs|| / ||rhs||`` the last solve of ``ksp`` reached (for
    GMRES preconditioned on the right, its true residual; collective)."""
    scale = rhs.norm()
    return ksp.getResidualNorm() / scale if scale > 0.0 else 0.0


def inexact(ksp: PETSc.KSP, rhs: PETSc.Vec) -> float | None:
    """The relative residual of a solve that the iteration limit stopped after it had fallen below
    :data:`KRYLOV_ACCEPT` (an inexact Newton step to take); None for any other solve."""
    if ksp.getConvergedReason() != -3:       # KSP_DIVERGED_ITS (REASONS)
        return None
    rel = reached(ksp, rhs)
    return rel if rel <= KRYLOV_ACCEPT else None


def not_converged(ksp: PETSc.KSP, rhs: PETSc.Vec) -> str:
    """Why the iterative solve of ``ksp`` stopped without converging, in one phrase: PETSc's reason,
    the iterations and the relative residual reached."""
    reason = ksp.getConvergedReason()
    why = REASONS.get(reason, "PETSc's reason")
    return (f"the iterative solver ({ksp.getType()} + {ksp.getPC().getType()}) did not converge: "
            f"{why} (KSP reason {reason}) after {ksp.getIterationNumber()} iterations, "
            f"relative residual {reached(ksp, rhs):.1e} (rtol {ksp.getTolerances()[0]:.1e})")

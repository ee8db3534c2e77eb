"""Taylor test of a model's Jacobian: is J the derivative of the residual R at a given state?

For a direction w and steps h_k = h0 / 2^k the remainder

    e(h) = || R(u + h w) - R(u) - h J(u) w ||

falls as h^2 when J is the exact derivative of R, and only as h when it misses a part of it (a state
that is held fixed in the Jacobian but moves with u in the residual). The observed order between two
steps is log2(e(h_k) / e(h_{k+1})). The residual is evaluated exactly as Newton evaluates it: the
constitutive update (return map included) at the quadrature points, then the assembly of every term
(internal forces, loads, contact), without Dirichlet conditions.

Usage::

    result = taylor_test(model)             # at model.u, a random direction
    assert min(result.orders[-3:]) > 1.8
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from dolfinx import fem
from mpi4py import MPI
from petsc4py import PETSc

from . import compat


@dataclass
class TaylorResult:
    steps: np.ndarray          # h_k
    remainders: np.ndarray     # e(h_k)
    first_order: np.ndarray    # || R(u + h w) - R(u) ||, for scale

    @property
    def orders(self) -> np.ndarray:
        """Observed orders log2(e(h_k) / e(h_k+1)) between successive steps."""
        e = self.remainders
        return np.log(e[:-1] / e[1:]) / np.log(self.steps[:-1] / self.steps[1:])

    def __str__(self) -> str:
        rows = [f"h = {h:.3e}  |R(u+hw) - R(u)| = {d:.3e}  remainder = {e:.3e}"
                for h, d, e in zip(self.steps, self.first_order, self.remainders)]
        return "\n".join(rows + ["orders: " + ", ".join(f"{o:.2f}" for o in self.orders)])


def _residual(model, out: PETSc.Vec) -> None:
    model.evaluate_stress()
    compat.assemble_vector(out, model.residual_form, add=model.nodal_loads())   # as Newton does


def random_direction(model, seed: int = 0, scale: float | None = None) -> fem.Function:
    """A random displacement direction, scaled to the largest displacement of the state (or
    ``scale``), the same for any number of ranks (drawn from the dofs' global numbers)."""
    V = model.V
    w = fem.Function(V)
    imap, bs = V.dofmap.index_map, V.dofmap.index_map_bs
    n = imap.size_local
    glob = imap.local_to_global(np.arange(n, dtype=np.int32))
    rng = np.random.default_rng(seed)
    table = rng.uniform(-1.0, 1.0, size=(imap.size_global, bs))
    w.x.array[:n * bs] = table[glob].ravel()
    w.x.scatter_forward()
    if scale is None:
        umax = np.abs(model.u.x.array).max(initial=0.0)
        scale = model.comm.allreduce(umax, op=MPI.MAX) or 1.0
    w.x.array[:] *= scale
    return w


def taylor_test(model, direction: fem.Function | None = None, h0: float = 1e-2,
                n: int = 6) -> TaylorResult:
    """Remainders of the first-order Taylor expansion of the residual at ``model.u``.

    ``model`` must be finalised and hold the state to test (``u``, the converged state of the last
    increment, the load); ``direction`` defaults to :func:`random_direction`. The state is restored
    on return (u and the stresses at u).
    """
    w = direction if direction is not None else random_direction(model)
    u0 = model.u.x.array.copy()
    R0 = compat.create_vector(model.residual_form)
    R = R0.duplicate()
    Jw = R0.duplicate()
    _residual(model, R0)
    A = compat.create_matrix(model.jacobian_form)
    model.assemble_jacobian(A, bcs=[])
    A.mult(compat.petsc_vec(w), Jw)
    steps = h0 / 2.0 ** np.arange(n)
    rem, first = [], []
    try:
        for h in steps:
            model.u.x.array[:] = u0 + h * w.x.array
            _residual(model, R)
            R.axpy(-1.0, R0)
            first.append(R.norm())
            R.axpy(-h, Jw)
            rem.append(R.norm())
    finally:
        model.u.x.array[:] = u0
        model.evaluate_stress()
        for v in (R0, R, Jw):
            v.destroy()
        A.destroy()
    return TaylorResult(steps, np.array(rem), np.array(first))

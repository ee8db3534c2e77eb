"""What a contact item carries from one increment to the next: the obstacle's last converged position,
the lag state of friction and the penalty friction's stick part.

* ``d_n``: the obstacle's displacement at the last converged increment (the slip of an increment is
  measured from it);
* the lag state ``u_lag``, ``d_lag``: the body at u_lag against the obstacle at d_lag, whose pressure
  p_lag gives the lagged law's threshold mu p_lag. It is the last converged increment, or with
  ``relag`` the last pass within the increment. The lag state depends on converged data only, and its
  pressure is the pressure that state converged with, to round-off: Nitsche's stress at u_lag is
  evaluated from the converged state u_lag was solved from (``base``, a FacetBase), not from the
  one after it;
* ``e_n``: the penalty friction's stick part (a length along t_o: the elastic tangential slip; in 3D
  a tangential vector, linear on the facets), a boundary field, the lumped projection of the new
  stick part at each converged increment.
"""
from __future__ import annotations

import numpy as np
import ufl
from dolfinx import fem
from mpi4py import MPI
from petsc4py import PETSc

from .. import compat


class ContactHistory:
    """The converged data of one contact item (``d0``: the obstacle's displacement at the last
    converged increment; ``stick``: keep a stick part, penalty friction)."""

    def __init__(self, ctx, d0, stick: bool):
        msh = ctx.mesh
        zero = (0.0,) * len(d0)
        self.d_n = fem.Constant(msh, PETSc.ScalarType(zero))     # obstacle at the last increment
        self.d_lag = fem.Constant(msh, PETSc.ScalarType(zero))   # obstacle in the lag state
        self.d_n.value = self.d_lag.value = d0
        self.u_lag = fem.Function(ctx.V, name="u_lag")
        self.u_lag.x.array[:] = ctx.u_n.x.array
        self.e_n = None
        if stick:        # a length along t_o in 2D, a tangential vector in 3D
            # in 3D linear: the quadratic vertex functions of a triangular facet integrate to zero,
            # so a lumped projection onto them does not exist
            shape, degree = ((3,), 1) if msh.topology.dim == 3 else ((), ctx.degree)
            self.e_n = fem.Function(compat.function_space(msh, "Lagrange", degree, shape), name="stick_slip")
        self.base = self._base_kept = None
        self._p_lag = self._p_lag_form = None
        self._vecs: dict = {}

    def bind(self, terms, ctx, boundary: str) -> None:
        """Take from the contact's built ``terms`` what the history updates: the lag state's
        pressure (which a relag pass compares), Nitsche's base, and the penalty's new stick part
        (compiled here, with the model's forms: every commit needs it)."""
        self.base = terms.base
        if self.base is not None:
            self._base_kept = self.base.arrays()
        if terms.p_lag is None and self.e_n is None:
            return
        if terms.p_lag is not None:
            phi = ufl.TestFunction(compat.function_space(ctx.mesh, "Lagrange", ctx.degree))
            self._p_lag = terms.p_lag * phi * terms.ds
        if self.e_n is not None:
            S = self.e_n.function_space
            phi = ufl.TestFunction(S)
            if len(phi.ufl_shape):               # 3D: each component lumped with the same weights
                self._e_form = fem.form(ufl.dot(terms.e_new, phi) * terms.ds)
                mass = fem.form(sum(phi[i] for i in range(phi.ufl_shape[0])) * terms.ds)
            else:
                self._e_form = fem.form(terms.e_new * phi * terms.ds)
                mass = fem.form(phi * terms.ds)
            self._lumped = self._assemble(mass, "e")
            sdofs = fem.locate_dofs_topological(S, ctx.mesh.topology.dim - 1, ctx.facets(boundary))
            bs = S.dofmap.index_map_bs
            sdofs = sdofs[sdofs < S.dofmap.index_map.size_local]      # the boundary's owned dofs
            self._sdofs = (bs * sdofs[:, None] + np.arange(bs)).ravel()

    def _assemble(self, form, space: str) -> np.ndarray:
        """Owned entries of an assembled linear form on a boundary field space: ``space`` "p" (the
        scalar one of the lag pressure) or "e" (the stick part's)."""
        if space not in self._vecs:
            self._vecs[space] = compat.create_vector(form)
        compat.assemble_vector(self._vecs[space], form)
        return self._vecs[space].array.copy()

    def commit(self, u, d) -> None:
        """At a converged increment (the body at ``u``, the obstacle at ``d``), before the model's
        own state moves on: the new stick part, and the increment becomes the lag state."""
        if self.e_n is not None:
            vals = self._assemble(self._e_form, "e")
            m, b = self._lumped, self._sdofs      # the boundary's nodes (elsewhere m is round-off)
            self.e_n.x.array[b] = vals[b] / m[b]
            self.e_n.x.scatter_forward()
        self.d_n.value = d
        self.d_lag.value = self.d_n.value
        self.u_lag.x.array[:] = u.x.array
        if self.base is not None:              # the model's state has not moved yet: u's own base
            self.base.capture()
            self._base_kept = self.base.arrays()

    def restore(self, u_n) -> None:
        """Back to the last converged increment (``u_n``) after a failed attempt."""
        self.u_lag.x.array[:] = u_n.x.array
        self.d_lag.value = self.d_n.value
        if self.base is not None:              # a relag pass may have moved it
            self.base.set_arrays(self._base_kept)

    def relag(self, u, d, comm, track=None) -> float:
        """Make the current solution (the body at ``u``, the obstacle at ``d``) the lag state;
        returns how much the lag state's pressure changed, relative to its largest value (all
        ranks). ``track``: called whenever the lag state moved, before the pressure is assembled
        (the obstacle's Obstacle.track)."""
        if self._p_lag_form is None:
            self._p_lag_form = fem.form(self._p_lag)
        if track is not None:
            track()
        p_old = self._assemble(self._p_lag_form, "p")
        self.u_lag.x.array[:] = u.x.array
        self.d_lag.value = d
        if self.base is not None:              # this pass was solved from the current state
            self.base.capture()
        if track is not None:
            track()
        p_new = self._assemble(self._p_lag_form, "p")
        scale = max(np.abs(p_new).max(), 1e-300)
        return comm.allreduce(float(np.abs(p_new - p_old).max()) / scale, op=MPI.MAX)

    def save(self) -> dict:
        """The history at a converged increment, for a checkpoint."""
        out = dict(d_n=np.array(self.d_n.value), d_lag=np.array(self.d_lag.value),
                   u_lag=("V", self.u_lag.x.array))
        if self.e_n is not None:
            out["e_n"] = (self.e_n.function_space, self.e_n.x.array)
        return out

    def load(self, state: dict) -> None:
        """Back to a saved history (:meth:`save`)."""
        self.d_n.value, self.d_lag.value = state["d_n"], state["d_lag"]
        self.u_lag.x.array[:] = state["u_lag"]
        if "e_n" in state:
            self.e_n.x.array[:] = state["e_n"]

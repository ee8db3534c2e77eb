"""Items that load or support a body: prescribed displacements, pressures, tractions, body forces.

Each follows the item protocol of mechanics/items.py (contact items too, contact/item.py): a factor
ramped by the steps scales its reference value (a pressure, a vector, a displacement field), and
``attach`` builds its residual term and Dirichlet conditions from the model's context. Signs: the
residual is R = f_int - f_ext, so loads contribute -(their virtual work).
"""
from __future__ import annotations

import numpy as np
import ufl
from dolfinx import fem
from petsc4py import PETSc

from .mechanics.items import Item, ItemError
from .mechanics.items import finite as _finite

from .checks import choice, text

__all__ = ["BodyForce", "Displacement", "Fixed", "Item", "ItemError", "PointLoad", "Pressure", "Traction"]


def _vector(name: str, value) -> np.ndarray:
    """``value`` as 2 (2D) or 3 (3D) finite numbers; ItemError naming ``name`` otherwise."""
    n = 3 if isinstance(value, (list, tuple, np.ndarray)) and np.size(value) == 3 else 2
    return _finite(name, value, (n,))


def _dimension(item, what: str, value, ctx) -> None:
    """ItemError unless the vector ``value`` has one entry per displacement component of the
    model (2, or 3 in 3D)."""
    if value is not None and np.size(value) != ctx.kin.dim:
        raise ItemError(f"{item}: {what} = {tuple(np.ravel(value))} has {np.size(value)} components, the "
                        f"body's displacement {ctx.kin.dim}: give {ctx.kin.dim} numbers")


def _boundary(boundary) -> None:
    """ItemError unless ``boundary`` is a boundary's name."""
    why = text("boundary", boundary, "the name of a tagged boundary, e.g. 'left'")
    if why:
        raise ItemError(why)


class Displacement(Item):
    """Prescribed displacement on a tagged boundary: u = factor * value (a vector, or a number for
    one component), or u = field(x, factor) (x the (3, N) reference points; returns (2, N), in 3D
    (3, N), or (N,) for one component). ``component``: 0 (x or r), 1 (y or z), 2 (z, 3D only), or
    None (all)."""

    kind = "support"

    def __init__(self, boundary: str, value=None, component: int | None = None, field=None):
        super().__init__(boundary)
        _boundary(boundary)
        if choice("component", component, (None, 0, 1, 2)):
            raise ItemError(f"component = {component!r}: use 0 (x), 1 (y), 2 (z, 3D) or None (all)")
        if field is not None and not callable(field):
            raise ItemError(f"boundary {boundary!r}: field = {field!r}: give a function field(x, factor)")
        if value is not None and field is not None:
            raise ItemError(f"boundary {boundary!r}: give a value or a field, not both")
        self.boundary, self.component, self.field = boundary, component, field
        what = f"displacement of {boundary!r}"
        self.value = None if value is None else (
            _finite(what, value) if component is not None else _vector(what, value))

    def attach(self, ctx):
        V, fdim = ctx.V, ctx.mesh.topology.dim - 1
        if self.component is not None and self.component >= ctx.kin.dim:
            raise ItemError(f"{self}: component = {self.component} in a 2D body: use 0 (x), 1 (y) or None")
        if self.component is None:
            _dimension(self, "value", self.value, ctx)
        facets = ctx.facets(self.boundary)
        if self.field is not None:
            if self.component is None:
                self._g = fem.Function(V)
                dofs = fem.locate_dofs_topological(V, fdim, facets)
                self.bcs = [fem.dirichletbc(self._g, dofs)]
            else:
                Vc = V.sub(self.component).collapse()[0]
                self._g = fem.Function(Vc)
                dofs = fem.locate_dofs_topological((V.sub(self.component), Vc), fdim, facets)
                self.bcs = [fem.dirichletbc(self._g, dofs, V.sub(self.component))]
                dofs = dofs[0]
        elif self.component is None:
            self._c = fem.Constant(ctx.mesh, PETSc.ScalarType((0.0,) * ctx.kin.dim))
            dofs = fem.locate_dofs_topological(V, fdim, facets)
            self.bcs = [fem.dirichletbc(self._c, dofs, V)]
        else:
            self._c = fem.Constant(ctx.mesh, PETSc.ScalarType(0.0))
            dofs = fem.locate_dofs_topological(V.sub(self.component), fdim, facets)
            self.bcs = [fem.dirichletbc(self._c, dofs, V.sub(self.component))]
        # the constrained entries of the (unrolled) vectors that this rank owns: a released
        # support's force acts there
        bs, n = V.dofmap.index_map_bs, V.dofmap.index_map.size_local
        dofs = np.asarray(dofs, dtype=np.int64)
        if self.component is None:
            dofs = (bs * dofs[:, None] + np.arange(bs)).ravel()
        self._dofs = np.sort(dofs[dofs // bs < n]).astype(np.int32)
        self._size = ctx.u.x.array.size
        return None

    def reset(self) -> None:
        super().reset()
        self._released: np.ndarray | None = None      # the support's force once a step released it

    @property
    def released(self) -> bool:
        return self._released is not None

    def release(self, residual: np.ndarray) -> None:
        """Take the support away at the start of a step (:class:`job.Step` ``release``): its
        Dirichlet conditions go, and the force it exerted becomes a dead nodal force scaled by the
        factor, set to 1 here (the body stays in equilibrium) and ramped by the step, to 0 unless
        the step says otherwise. ``residual``: this rank's entries of the residual R = f_int - f_ext
        at the converged state, without Dirichlet conditions (at a constrained dof, the force the
        support exerts). A released support stays released."""
        self._released = np.asarray(residual, dtype=float)[self._dofs].copy()
        self.bcs = []
        self.set_factor(1.0)

    def nodal(self):
        if self._released is None:
            return None
        return self._dofs, self.factor * self._released

    def _apply(self, factor):
        if self._released is not None:
            return                         # the factor scales the released force (nodal)
        if self.field is not None:
            self._g.interpolate(lambda x: self.field(x, factor))
            self._g.x.scatter_forward()
        elif self.value is not None:
            self._c.value = factor * self.value

    def save_state(self) -> dict:
        state = super().save_state()
        if self._released is not None:                # a field on the nodes (any partition)
            full = np.zeros(self._size)
            full[self._dofs] = self._released
            state["released"] = ("V", full)
        return state

    def load_state(self, state: dict) -> None:
        if "released" in state:
            self._released = np.asarray(state["released"], dtype=float).ravel()[self._dofs].copy()
            self.bcs = []
        super().load_state(state)


class Fixed(Displacement):
    """u = 0 (or u[component] = 0) on a tagged boundary."""

    def __init__(self, boundary: str, component: int | None = None):
        super().__init__(boundary, None, component)


class Pressure(Item):
    """Follower pressure ``p`` (times the factor) on a tagged boundary: it pushes into the body, normal
    to the current face (Nanson: t da = -p J F^-T N dA), the stress update's F (under linear
    kinematics, ``small_strain``, F = I: a dead pressure on the reference normal). Per unit reference
    thickness in plane stress; on faces in 3D."""

    def __init__(self, boundary: str, p: float):
        super().__init__(boundary)
        _boundary(boundary)
        self.boundary, self.p = boundary, float(_finite(f"pressure on {boundary!r}", p))

    def attach(self, ctx):
        self._c = fem.Constant(ctx.mesh, PETSc.ScalarType(0.0))
        N = ufl.FacetNormal(ctx.mesh)
        F = ctx.update.F(ctx.u)
        cof = ufl.det(F) * ufl.inv(F).T
        if ctx.kin.solid:       # cof F (quadratic in Grad u) N . v: degree 2 k on a flat face
            ds = ctx.ds(self.boundary, {"quadrature_degree": 2 * ctx.degree})
            return self._c * ufl.dot(cof * N, ctx.v) * ds
        v3 = ufl.as_vector([ctx.v[0], ctx.v[1], 0.0])
        return -(-self._c * ufl.dot(cof * ufl.as_vector([N[0], N[1], 0.0]), v3) * ctx.weight
                 * ctx.ds(self.boundary))

    def _apply(self, factor):
        self._c.value = factor * self.p


class Traction(Item):
    """Dead traction ``vector`` (times the factor; 2 components, 3 in 3D) per unit reference area of a
    tagged boundary."""

    def __init__(self, boundary: str, vector):
        super().__init__(boundary)
        _boundary(boundary)
        self.boundary, self.traction = boundary, _vector(f"traction on {boundary!r}", vector)

    def attach(self, ctx):
        _dimension(self, "vector", self.traction, ctx)
        self._c = fem.Constant(ctx.mesh, PETSc.ScalarType((0.0,) * ctx.kin.dim))
        return -(ufl.dot(self._c, ctx.v) * ctx.weight * ctx.ds(self.boundary))

    def _apply(self, factor):
        self._c.value = factor * self.traction


class BodyForce(Item):
    """Dead force ``vector`` (times the factor) per unit reference volume, e.g. gravity (0, -rho g), in
    3D (0, 0, -rho g)."""

    def __init__(self, vector, name: str = "body_force"):
        super().__init__(name)
        if text("name", name):
            raise ItemError(text("name", name))
        self.force = _vector("body force", vector)

    def attach(self, ctx):
        _dimension(self, "vector", self.force, ctx)
        self._c = fem.Constant(ctx.mesh, PETSc.ScalarType((0.0,) * ctx.kin.dim))
        dx = ufl.dx(domain=ctx.mesh, metadata={"quadrature_degree": 2 * ctx.degree + 1})
        return -(ufl.dot(self._c, ctx.v) * ctx.weight * dx)

    def _apply(self, factor):
        self._c.value = factor * self.force


class PointLoad(Item):
    """Dead force ``vector`` (times the factor) at the mesh node at ``point``: per unit thickness in
    plane models (a line load through the thickness), a ring load's total in axisymmetry (pass the
    total; it acts at the node's radius); in 3D a force at the node (point and vector of 3)."""

    def __init__(self, point, vector, name: str = "point_load"):
        super().__init__(name)
        if text("name", name):
            raise ItemError(text("name", name))
        self.point = _vector("point of the load", point)
        self.force = _vector("point load", vector)

    def attach(self, ctx):
        from mpi4py import MPI
        _dimension(self, "point", self.point, ctx)
        _dimension(self, "vector", self.force, ctx)
        dim = ctx.kin.dim
        X = ctx.V.tabulate_dof_coordinates()
        n = ctx.V.dofmap.index_map.size_local
        d = np.linalg.norm(X[:n, :dim] - self.point, axis=1) if n else np.array([np.inf])
        best, owner = ctx.mesh.comm.allreduce((float(d.min()), ctx.mesh.comm.rank), op=MPI.MINLOC)
        size = ctx.mesh.comm.allreduce(float(np.ptp(X[:n, :dim], axis=0).max()) if n else 0.0, op=MPI.MAX)
        if best > 1e-8 * max(size, 1.0):
            raise ItemError(f"no mesh node at {tuple(self.point)} for the point load (nearest at "
                            f"{best:.3g}): put a node there")
        bs = ctx.V.dofmap.index_map_bs
        node = int(np.argmin(d)) if ctx.mesh.comm.rank == owner else None
        self._dofs = np.array([], dtype=np.int32) if node is None else bs * node + np.arange(bs)
        return None

    def nodal(self):
        k = len(self.force)
        return self._dofs, np.broadcast_to(self.factor * self.force, (len(self._dofs) // k, k)).ravel()

"""Quadrature spaces: state storage, evaluation of UFL expressions at the points, output averages.

One quadrature degree per model is used for every quadrature element, for the points handed to
``fem.Expression`` and for the metadata of every ``dx`` touching a quadrature function: a ``dx``
whose degree differs from the quadrature element's would evaluate the function at points it does not
hold. The quadrature dofmap is the identity, so arrays are laid out cell by cell (local cells, then
ghosts), then point by point, then component by component.
"""
from __future__ import annotations

import basix
import numpy as np
import ufl
from dolfinx import fem

from .. import compat

_CELLS = {name: getattr(basix.CellType, name) for name in ("triangle", "quadrilateral", "tetrahedron",
                                                             "hexahedron")}


class QuadratureRule:
    """The quadrature points of a mesh and the spaces living on them."""

    def __init__(self, mesh, degree: int):
        self.mesh = mesh
        self.degree = degree
        self.points, self.weights = basix.make_quadrature(_CELLS[compat.cell_name(mesh)], degree)
        imap = mesh.topology.index_map(mesh.topology.dim)
        self.num_cells_local = imap.size_local
        self.cells = np.arange(imap.size_local + imap.num_ghosts, dtype=np.int32)
        self.npts = len(self.weights)
        self.dx = ufl.dx(domain=mesh, metadata={"quadrature_degree": degree,
                                                "quadrature_scheme": "default"})
        self._spaces: dict[tuple, object] = {}

    @property
    def size(self) -> int:
        """Number of quadrature points on this rank, ghost cells included."""
        return len(self.cells) * self.npts

    def space(self, shape: tuple = ()):
        """Quadrature space of scalars (), vectors (n,) or tensors (n, m) (cached)."""
        if shape not in self._spaces:
            self._spaces[shape] = compat.quadrature_space(self.mesh, self.degree, shape)
        return self._spaces[shape]

    def function(self, shape: tuple = (), name: str = "q", value=None) -> fem.Function:
        """A quadrature function, optionally filled with a constant value (scalar or array of shape)."""
        f = fem.Function(self.space(shape), name=name)
        if value is not None:
            f.x.array[:] = np.tile(np.asarray(value, dtype=float).ravel(), self.size)
        return f

    def view(self, f: fem.Function) -> np.ndarray:
        """The values of a quadrature function as an array ``(points, *shape)`` sharing its memory."""
        shape = f.ufl_shape
        return f.x.array.reshape((self.size,) + tuple(shape))

    def expression(self, expr):
        """Compile a UFL expression for evaluation at the quadrature points (once per model)."""
        return compat.expression(expr, self.points)

    def evaluate(self, expression) -> np.ndarray:
        """Values at every point of every local and ghost cell, shape (points, value_size)."""
        return compat.evaluate(expression, self.mesh, self.cells).reshape(self.size, -1)

    def cell_average(self, values: np.ndarray) -> np.ndarray:
        """Cell averages of per-point values (points, ...) -> (cells, ...): the integral over each cell
        (of the mesh as it is, curved cells too: the weights times ``|det J|`` at the points) divided by
        its area."""
        if getattr(self, "_average_weights", None) is None:
            detJ = ufl.JacobianDeterminant(self.mesh)
            w = self.weights * np.abs(self.evaluate(self.expression(detJ)).reshape(-1, self.npts))
            self._average_weights = w / w.sum(axis=1, keepdims=True)
        v = values.reshape((len(self.cells), self.npts) + values.shape[1:])
        return np.einsum("cq,cq...->c...", self._average_weights, v)


class CellInterpolator:
    """Cell-wise least-squares fit of quadrature-point values by a discontinuous Lagrange field.

    Used where quadrature data must be seen on facets (dolfinx cannot evaluate quadrature functions
    there): with DG1 and the 3-point rule of degree 2 on triangles (the 4-point rule on tetrahedra) the
    fit interpolates the point values exactly.
    """

    def __init__(self, rule: QuadratureRule, V_dg):
        k = compat.element_degree(V_dg)
        B = compat.lagrange_tabulate(compat.cell_name(rule.mesh), k, rule.points)  # (points, dofs)
        BW = B.T * rule.weights
        self.proj = np.linalg.solve(BW @ B, BW)                      # (dofs, points)
        self.dofs = compat.cell_dofs(V_dg, len(rule.cells))
        self.rule = rule

    def __call__(self, values: np.ndarray, f: fem.Function) -> None:
        """Fit ``values`` (points, components) into the DG function ``f``."""
        r = self.rule
        comps = values.reshape(r.size, -1).shape[1]
        v = values.reshape(len(r.cells), r.npts, comps)
        f.x.array.reshape(-1, comps)[self.dofs] = np.einsum("dp,cpk->cdk", self.proj, v)

"""The contact boundary's nodes and the nodal fields of pressure and shear on it.

The fields ``pressure`` and ``shear`` (per unit current area) hold nodal values on the boundary
(zero elsewhere): lumped projections of the quadrature values with the linear hat functions
(weights >= 0, so the pressure never goes below zero), interpolated onto the boundary field space
(the displacement's degree). A smoothed field: its support reaches one node past the contact zone.
Filled on demand: every read gets the current values, and nothing is recomputed while nothing they
depend on changed.
"""
from __future__ import annotations

from dataclasses import dataclass

import basix
import numpy as np
import ufl
from dolfinx import fem

from .. import compat
from .obstacles import ContactError
from .tracking import Dependencies


@dataclass
class BoundaryNodes:
    """The contact boundary's nodes that this rank owns: ``nodes`` in the numbering of the
    displacement's blocked dofs, ``X`` their reference coordinates (n, 2), in 3D (n, 3)."""

    nodes: np.ndarray
    X: np.ndarray

    @classmethod
    def of(cls, ctx, boundary: str) -> "BoundaryNodes":
        """The owned nodes of the tagged boundary ``boundary`` of the model's context ``ctx``."""
        V = ctx.V
        dofs = fem.locate_dofs_topological(V.sub(0), ctx.mesh.topology.dim - 1, ctx.facets(boundary))
        nodes = np.unique(dofs // V.dofmap.index_map_bs)          # unrolled indices of V
        nodes = nodes[nodes < V.dofmap.index_map.size_local]       # owned nodes only
        return cls(nodes, V.tabulate_dof_coordinates()[nodes, :ctx.mesh.topology.dim])


class BoundaryFields:
    """The nodal fields ``pressure`` and ``shear`` of one contact boundary.

    ``p_cur``, ``q_cur``: the pressure and the tangential traction per unit current area (UFL; q_cur
    None without friction; in 3D the tangential traction vector, whose magnitude the field
    ``shear`` holds); ``ds``: the contact boundary's measure; ``nodes``: its
    :class:`BoundaryNodes`.
    """

    def __init__(self, ctx, boundary: str, p_cur, q_cur, ds, nodes: BoundaryNodes, comm):
        msh, fdim = ctx.mesh, ctx.mesh.topology.dim - 1
        self.comm, self.dim = comm, fdim + 1
        S = compat.function_space(msh, "Lagrange", ctx.degree)
        # pressure and shear are projected with linear weights (non-negative hat functions), so a
        # pressure that the law keeps >= 0 stays >= 0 at the nodes; then interpolated onto S
        S1 = compat.function_space(msh, "Lagrange", 1)
        phi1 = ufl.TestFunction(S1)
        self._ufl = {"p": p_cur * phi1 * ds}
        if q_cur is not None:
            q = ufl.sqrt(ufl.dot(q_cur, q_cur)) if len(q_cur.ufl_shape) else q_cur
            self._ufl["q"] = q * phi1 * ds
        self._forms: dict = {}
        self.pressure = fem.Function(S, name="contact_pressure")
        self.shear = fem.Function(S, name="contact_shear")
        self.p1_field = fem.Function(S1)
        mass1 = fem.form(phi1 * ds)
        self._vec1 = compat.create_vector(mass1)
        self._lumped1 = self._assemble(mass1)
        facets = ctx.facets(boundary)
        sdofs = fem.locate_dofs_topological(S, fdim, facets)
        self.sdofs = sdofs[sdofs < S.dofmap.index_map.size_local]
        self._off = np.ones(S.dofmap.index_map.size_local + S.dofmap.index_map.num_ghosts, dtype=bool)
        self._off[sdofs] = False                     # dofs away from the contact boundary
        # the boundary field's dof at each of the boundary's nodes (same points, matched by position
        # among the boundary's dofs, ghosts included)
        XS = np.round(S.tabulate_dof_coordinates()[sdofs, :self.dim], 12).tolist()
        key = {tuple(x): int(d) for x, d in zip(XS, sdofs)}
        self.node_sdof = np.array([key.get(tuple(x), -1) for x in np.round(nodes.X, 12).tolist()],
                                  dtype=np.int64)
        s1 = fem.locate_dofs_topological(S1, fdim, facets)
        self._s1dofs = s1[s1 < S1.dofmap.index_map.size_local]
        self.p1_to_s = p1_interpolation(S, S1, ctx.degree)
        self._depends = Dependencies(comm, list(self._ufl.values()))

    def _assemble(self, form) -> np.ndarray:
        """Owned entries of an assembled linear form on the P1 space."""
        compat.assemble_vector(self._vec1, form)
        return self._vec1.array.copy()

    def update(self) -> None:
        """Contact pressure and tangential traction (per current area) as boundary fields: lumped
        projections with the linear hat functions (weights >= 0: the pressure never goes below
        zero) onto the boundary's vertices, interpolated onto the boundary field space. Recomputed
        only when something they depend on changed. Collective."""
        if not self._depends.stale():
            return
        m, b, g = self._lumped1, self._s1dofs, self.p1_field
        for name in self._ufl:
            f = self.pressure if name == "p" else self.shear
            if name not in self._forms:
                self._forms[name] = fem.form(self._ufl[name])
            vals = self._assemble(self._forms[name])
            g.x.array[:] = 0.0
            g.x.array[b] = vals[b] / m[b]
            g.x.scatter_forward()
            if self.p1_to_s is None:
                f.interpolate(g)
            else:
                dofs, ea, eb = self.p1_to_s
                f.x.array[dofs] = 0.5 * (g.x.array[ea] + g.x.array[eb])
            f.x.array[self._off] = 0.0                # the interpolation reaches into the cells
            f.x.scatter_forward()
        self._depends.mark()

    def field(self, name: str):
        """The boundary field ``"pressure"`` or ``"shear"``, current (collective)."""
        if name not in ("pressure", "shear"):
            raise ContactError(f"contact field {name!r} is unknown: choose 'pressure' or 'shear'")
        self.update()
        return self.pressure if name == "pressure" else self.shear

    def boundary_values(self, f) -> tuple[np.ndarray, np.ndarray]:
        """(reference coordinates, values) of a boundary field (a Function or its name, ``"pressure"``
        or ``"shear"``) at every node of the contact boundary, gathered on all ranks."""
        if isinstance(f, str):
            f = self.field(f)
        elif f is self.pressure or f is self.shear:
            self.update()
        X = f.function_space.tabulate_dof_coordinates()[self.sdofs, :self.dim]
        return (np.concatenate(self.comm.allgather(X)),
                np.concatenate(self.comm.allgather(f.x.array[self.sdofs])))


def p1_interpolation(S, S1, degree: int):
    """(dofs of S, the two P1 dofs whose mean is their value) for the interpolation of a P1
    field into the boundary fields' space S (P1 or P2: a vertex takes its value, an edge's
    midpoint the mean of the edge's ends; triangles, quadrilaterals and tetrahedra, whose boundary
    nodes are all vertices or edge midpoints), in numpy: dolfinx's interpolation between two spaces
    cost as much as the rest of the output. None for other degrees and for hexahedra (dolfinx
    interpolates there: a Q2 face's centre is the mean of four vertices)."""
    cell = compat.cell_name(S.mesh)
    if degree not in (1, 2) or cell == "hexahedron":
        return None
    imap = S.mesh.topology.index_map(S.mesh.topology.dim)
    n = imap.size_local + imap.num_ghosts
    cs, c1 = compat.cell_dofs(S, n), compat.cell_dofs(S1, n)
    # the cell's dofs: its vertices, then (P2) its edges, each in the reference cell's order
    # (basix's, e.g. the triangle's edges opposite vertices 0, 1 and 2, the quadrilateral's 0-1,
    # 0-2, 1-3, 2-3); a quadrilateral's P2 centre is no boundary node and is left out
    vertices, edges = basix.topology(getattr(basix.CellType, cell))[:2]
    ends = [(v[0], v[0]) for v in vertices] + ([tuple(e) for e in edges] if degree == 2 else [])
    dofs = np.concatenate([cs[:, k] for k in range(len(ends))])
    a = np.concatenate([c1[:, i] for i, _ in ends])
    b = np.concatenate([c1[:, j] for _, j in ends])
    return dofs, a, b

"""The contact boundary's pressure profile: pressure, shear and gap sampled at the facet quadrature
points (four Gauss points per facet, the points where the residual evaluates the contact law),
with their reference and current coordinates and the arc length along the boundary, sorted along
the boundary and the same on every rank (zones.ContactProfile); the zones and the peak pressure
follow from it (zones.py).

dolfinx evaluates expressions in cells, not on facets: the facet normal of the contact terms is
rebuilt from the cell's Jacobian and the reference normal of the facet (a Constant set before each
evaluation), so that the sampled pressure is the one the residual sees.
"""
from __future__ import annotations

import numpy as np
import ufl
from dolfinx import fem
from petsc4py import PETSc

from .. import compat
from ..mechanics.ufl_dag import unique_nodes
from .tracking import Dependencies
from .zones import ContactProfile, Zone, chain_facets, gauss_points, peak_of, zones_of

# the reference cells' facets: (first vertex, second vertex, outward normal), dolfinx's numbering
_FACETS = {
    "triangle": (((1, 0), (0, 1), (1, 1)), ((0, 0), (0, 1), (-1, 0)), ((0, 0), (1, 0), (0, -1))),
    "quadrilateral": (((0, 0), (1, 0), (0, -1)), ((0, 0), (0, 1), (-1, 0)), ((1, 0), (1, 1), (1, 0)),
                      ((0, 1), (1, 1), (0, 1))),
}
# the reference 3D cells in basix's numbering (dolfinx's: a cell's facets and their vertices come in
# this order; tests/test_radial.py checks the tables against basix): the vertices, the edges (pairs
# of vertices) and the faces (their vertices, outward normal)
_CELLS_3D = {
    "tetrahedron": (((0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1)),
                    ((2, 3), (1, 3), (1, 2), (0, 3), (0, 2), (0, 1)),
                    (((1, 2, 3), (1, 1, 1)), ((0, 2, 3), (-1, 0, 0)), ((0, 1, 3), (0, -1, 0)),
                     ((0, 1, 2), (0, 0, -1)))),
    "hexahedron": (((0, 0, 0), (1, 0, 0), (0, 1, 0), (1, 1, 0), (0, 0, 1), (1, 0, 1), (0, 1, 1), (1, 1, 1)),
                   ((0, 1), (0, 2), (0, 4), (1, 3), (1, 5), (2, 3), (2, 6), (3, 7), (4, 5), (4, 6), (5, 7),
                    (6, 7)),
                   (((0, 1, 2, 3), (0, 0, -1)), ((0, 1, 4, 5), (0, -1, 0)), ((0, 2, 4, 6), (-1, 0, 0)),
                    ((1, 3, 5, 7), (1, 0, 0)), ((2, 3, 6, 7), (0, 1, 0)), ((4, 5, 6, 7), (0, 0, 1)))),
}


def columns(dim: int) -> dict:
    """Where the profile expression puts each quantity (a body of dimension ``dim``): the reference
    and current coordinates ``X``, ``x`` and the obstacle's normal ``n`` (lists of ``dim`` columns),
    the pressure ``p``, the tangential traction ``q`` (in 3D its magnitude) and the ``gap``."""
    return {"X": list(range(dim)), "x": list(range(dim, 2 * dim)), "p": 2 * dim, "q": 2 * dim + 1,
            "gap": 2 * dim + 2, "n": list(range(2 * dim + 3, 3 * dim + 3)), "size": 3 * dim + 3}


class FacetProfile:
    """The pressure profile of one contact boundary, its zones and its peak, recomputed when
    something they depend on changed.

    ``p_cur``, ``q_cur``: the pressure and tangential traction per unit current area (UFL, on the
    facets: they hold the facet normal ``N``; q_cur None without friction); ``facets``: the
    boundary's facets; ``u``: the displacement; ``geometric``: False under linear kinematics, which
    measures lengths on the reference.
    """

    NPOINTS = 4                # Gauss points per facet: the contact terms' rule (FACET_DEGREE = 7)

    def __init__(self, ctx, obstacle, u, p_cur, q_cur, N, facets, comm):
        self.mesh, self.comm = ctx.mesh, comm
        self.dim = dim = self.mesh.topology.dim
        self._C = columns(dim)
        self._owned_facets(facets)
        segments, normals = self._segments(ctx)
        t = np.concatenate([[0.0], gauss_points(self.NPOINTS), [1.0]])
        pts = [np.array(a) + t[:, None] * (np.array(b) - np.array(a)) for a, b in segments]
        self._npts, self._nseg = len(t), len(segments)
        self._points = np.vstack(pts).astype(np.float64)
        self._normals = [np.array(nr, dtype=float) / np.linalg.norm(nr) for nr in normals]
        self._nref = fem.Constant(self.mesh, PETSc.ScalarType((0.0,) * dim))
        K = ufl.JacobianInverse(self.mesh)
        Nk = ufl.dot(K.T, self._nref)
        Nk = Nk / ufl.sqrt(ufl.dot(Nk, Nk))
        x = ctx.x + u
        p = ufl.replace(p_cur, {N: Nk})
        q = ufl.replace(q_cur, {N: Nk}) if q_cur is not None else 0.0 * p
        q = ufl.sqrt(ufl.dot(q, q)) if dim == 3 and q_cur is not None else q
        n_o = obstacle.normal(x)
        self._expr_ufl = ufl.as_vector([*(ctx.x[i] for i in range(dim)), *(x[i] for i in range(dim)), p, q,
                                        obstacle.gap(x), *(n_o[i] for i in range(dim))])
        self._expr = None
        self._order = None
        # linear kinematics (an update whose ``geometric`` is False) measures lengths on the reference
        self._geometric = bool(getattr(ctx.update, "geometric", True))
        self._depends = Dependencies(comm, [self._expr_ufl], ignore=[self._nref])
        self._profile = None

    def _owned_facets(self, facets) -> None:
        """The boundary's facets whose cell this rank owns (each is integrated there), their cells
        and their local numbers in those cells."""
        msh = self.mesh
        tdim = msh.topology.dim
        msh.topology.create_connectivity(tdim - 1, tdim)
        msh.topology.create_connectivity(tdim, tdim - 1)
        fc, cf = msh.topology.connectivity(tdim - 1, tdim), msh.topology.connectivity(tdim, tdim - 1)
        n_owned = msh.topology.index_map(tdim).size_local
        facets = np.asarray(facets, dtype=np.int64)
        cells = fc.array[fc.offsets[facets]]            # a boundary facet has one cell
        keep = cells < n_owned                           # integrated by the rank owning its cell
        self._pfacets, self._pcells = facets[keep], cells[keep].astype(np.int32)
        per = cf.offsets[1] - cf.offsets[0]
        cell_facets = cf.array.reshape(-1, per)
        self._local = np.argmax(cell_facets[self._pcells] == self._pfacets[:, None], axis=1)

    def _segments(self, ctx) -> tuple[list, list]:
        """The segments of the reference cell that the profile samples, (first point, second point)
        each, and the reference cell's outward facet normals; ``self._segment`` (set here): the
        segment each of the rank's facets samples. In 2D the facets themselves (3D: radial.py)."""
        ref = _FACETS[compat.cell_name(self.mesh)]
        self._segment = self._local
        return [(a, b) for a, b, _ in ref], [nr for _, _, nr in ref]

    def _evaluate(self) -> np.ndarray:
        """The profile's columns at the six points (end, four Gauss points, end) of every sampled
        segment (2D: every facet of the boundary), (segments, 6, columns), in the order of the
        ranks' facets, on every rank."""
        if self._expr is None:
            self._expr = compat.expression(unique_nodes(self._expr_ufl), self._points)
        nc, npt = self._C["size"], self._npts
        local = np.zeros((len(self._pfacets), npt, nc))
        for k, nr in enumerate(self._normals):
            sel = np.flatnonzero(self._local == k)
            if sel.size == 0:
                continue
            self._nref.value = nr
            vals = compat.evaluate(self._expr, self.mesh, self._pcells[sel]).reshape(sel.size, self._nseg, npt, nc)
            local[sel] = vals[np.arange(sel.size), self._segment[sel]]
        return np.concatenate(self.comm.allgather(local))

    def profile(self) -> ContactProfile:
        """The pressure, shear and gap at the quadrature points of the contact boundary, sorted along
        it (:class:`zones.ContactProfile`; the same on every rank). Collective."""
        self._refresh()
        return self._profile

    def _refresh(self) -> None:
        """The profile, its zones and peak anew, if anything they depend on changed. Collective."""
        if not self._depends.stale():
            return
        D = self._evaluate()
        C = self._C
        if self._order is None:
            self._order = self._chain(D)
        order, flipped, piece = self._order
        D = D[order]
        D[flipped] = D[flipped, ::-1]
        S_all, s_all, ends = self._arc_lengths(D, piece)
        g = slice(1, self._npts - 1)                  # the Gauss points
        G = D[:, g].reshape(-1, D.shape[2])
        self._profile = ContactProfile(
            X=G[:, C["X"]].copy(), x=G[:, C["x"]].copy(), S=S_all[:, g].ravel(),
            s=s_all[:, g].ravel(), p=G[:, C["p"]].copy(), q=G[:, C["q"]].copy(), gap=G[:, C["gap"]].copy(),
            normal=G[:, C["n"]].copy(), piece=np.repeat(piece, self._npts - 2))
        self._ends = ends
        self._zones = zones_of(self._profile, ends)
        self._peak = peak_of(self._profile, ends, self._npts - 2)
        self._depends.mark()

    def _chain(self, D: np.ndarray) -> tuple:
        """The sampled segments ``D`` joined end to end by their reference end points (zones.chain_facets)."""
        X = self._C["X"]
        return chain_facets(D[:, 0, X], D[:, -1, X])

    def _arc_lengths(self, D: np.ndarray, piece: np.ndarray) -> tuple:
        """(reference and current arc length at every sampled point (facets, points), and each
        piece's end points ((x_start, s_start), (x_end, s_end))) of the sorted samples ``D``; a
        piece goes on from where the one before it ended."""
        C = self._C
        ends, S_all, s_all = [], np.zeros(D.shape[:2]), np.zeros(D.shape[:2])
        S0 = s0 = 0.0
        ref, cur = C["X"], (C["x"] if self._geometric else C["X"])
        for k in range(int(piece.max()) + 1 if piece.size else 0):
            rows = np.flatnonzero(piece == k)
            for col, out, base in ((ref, S_all, S0), (cur, s_all, s0)):
                P = D[rows][:, :, col].reshape(-1, len(col))
                seg = np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(P, axis=0), axis=1))]
                out[rows] = (base + seg).reshape(len(rows), -1)
            xs = D[rows[0], 0, C["x"]], D[rows[-1], -1, C["x"]]
            ends.append(((xs[0], s_all[rows[0], 0]), (xs[1], s_all[rows[-1], -1])))
            S0, s0 = S_all[rows[-1], -1], s_all[rows[-1], -1]
        return S_all, s_all, ends

    def zones(self) -> list[Zone]:
        """The connected parts of the contact set, with their edges (zones.py). Collective."""
        self._refresh()
        return self._zones

    def extent(self) -> float:
        """Current length of the contact set: the sum of its zones' lengths (arc length between
        their edges). Collective."""
        return float(sum(z.length for z in self.zones()))

    def zone_edges(self, axis: int = 0) -> tuple[float, float]:
        """Smallest and largest current coordinate ``axis`` of the contact set's edges (NaN, NaN
        without contact). Collective."""
        zs = self.zones()
        if not zs:
            return np.nan, np.nan
        v = [z.start[axis] for z in zs] + [z.end[axis] for z in zs]
        return float(min(v)), float(max(v))

    def peak_pressure(self) -> float:
        """The peak contact pressure per current area (zones.peak_of; 0 without contact). Collective."""
        self._refresh()
        return self._peak

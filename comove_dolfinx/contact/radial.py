"""The contact radius of a 3D body: the pressure profile along a meridian of the contact boundary
and the edge of the contact set along it.

A meridian is the section of the contact boundary, in the reference configuration, by the
half-plane that an axis (through ``origin`` along ``axis``) bounds on the side of ``direction``.
Its segments are the edges of the boundary's facets (triangles of tetrahedra, quadrilaterals of
hexahedra) that lie in the half-plane, both vertices within 1e-8 of the mesh's extent of it: the
meridian must run along edges of the mesh, as a symmetry plane's border of the boundary does (the
bottom face's edge on y = 0 of ``plate_quarter``, the meridian of ``sphere_octant`` on x = 0). Each
edge is sampled as profile.py samples a 2D facet: at its ends and its four Gauss points, the
pressure per current area evaluated in its facet's cell with the facet's reference normal (the
pressure the residual sees); the samples are gathered on every rank and joined along the meridian
(zones.chain_facets, on the coordinates in the half-plane), and the contact set's zones along it
follow as in 2D (zones.zones_of: an edge where the straight line fitted to p^2 at the last points
in contact reaches zero; a zone that reaches the meridian's end ends there). The contact radius is
the largest distance from the axis of the zones' edges, in current coordinates (under linear
kinematics too), and 0 without contact; where the contact set is a disc about the axis, its radius.

An edge of two facets of the boundary (a meridian across the boundary, not along its border)
takes the mean of the two facets' samples (the same on any partition: the sum of two numbers does
not depend on their order). A meridian that meets no facet's edge, or in whose half-plane a facet
lies, is refused (ContactError).
"""
from __future__ import annotations

import numpy as np
from mpi4py import MPI

from .. import compat
from .obstacles import ContactError
from .profile import _CELLS_3D, FacetProfile
from .zones import chain_facets

TOL = 1e-8                 # a vertex in the half-plane: within TOL times the mesh's extent of it


def frame(origin, direction, axis) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(origin, axis, the unit vector of the half-plane square to the axis towards ``direction``,
    the half-plane's unit normal) of checked inputs (checks.meridian_error)."""
    o, a, d = (np.asarray(v, dtype=float) for v in (origin, axis, direction))
    a = a / np.linalg.norm(a)
    e = d - (d @ a) * a
    e = e / np.linalg.norm(e)
    return o, a, e, np.cross(a, e)


def _describe(origin, direction, axis) -> str:
    return (f"the meridian from the axis through {tuple(map(float, origin))} along {tuple(map(float, axis))} "
            f"towards {tuple(map(float, direction))}")


class MeridianProfile(FacetProfile):
    """The pressure profile along a meridian of a 3D contact boundary (module docstring), its zones
    and the contact radius. Its first arguments are FacetProfile's; ``origin``, ``direction``,
    ``axis``: the meridian's half-plane (checked: checks.meridian_error). Collective."""

    def __init__(self, ctx, obstacle, u, p_cur, q_cur, N, facets, comm, origin, direction, axis):
        self.origin, self.axis, self.across, self.normal = frame(origin, direction, axis)
        self._what = _describe(origin, direction, axis)
        super().__init__(ctx, obstacle, u, p_cur, q_cur, N, facets, comm)

    def _segments(self, ctx) -> tuple[list, list]:
        """The reference cell's edges and face normals; keeps the rank's facets that have an edge in
        the half-plane (``self._segment``: that edge). ContactError if no facet has one or a facet
        lies in the half-plane."""
        vertices, edges, faces = _CELLS_3D[compat.cell_name(self.mesh)]
        X = self._vertices(ctx, vertices)
        on = self._in_half_plane(X)
        segment = np.full(len(self._pfacets), -1, dtype=np.int64)
        flat = [i for i, k in enumerate(self._local) if on[i, list(faces[k][0])].all()]
        if self.comm.allreduce(bool(flat), op=MPI.LOR):
            raise ContactError(f"a facet of the contact boundary lies in the half-plane of {self._what}: "
                               "give a half-plane across the boundary, along its edges")
        for i, k in enumerate(self._local):
            face = faces[k][0]
            hits = [j for j, (a, b) in enumerate(edges) if a in face and b in face and on[i, a] and on[i, b]]
            segment[i] = hits[0] if hits else -1
        keep = segment >= 0
        self._pfacets, self._pcells, self._local = self._pfacets[keep], self._pcells[keep], self._local[keep]
        self._segment = segment[keep]
        if not self.comm.allreduce(int(keep.sum()), op=MPI.SUM):
            raise ContactError(f"no facet of the contact boundary has an edge on {self._what}: give a "
                               "half-plane that runs along edges of the boundary's mesh (a symmetry plane's)")
        self._merge = None
        return ([(vertices[a], vertices[b]) for a, b in edges], [nr for _, nr in faces])

    def _vertices(self, ctx, vertices) -> np.ndarray:
        """The reference coordinates of the vertices of the cells of the rank's facets, (facets,
        vertices, 3)."""
        if not len(self._pcells):
            return np.zeros((0, len(vertices), 3))
        expr = compat.expression(ctx.x, np.array(vertices, dtype=np.float64))
        return compat.evaluate(expr, self.mesh, self._pcells).reshape(len(self._pcells), len(vertices), 3)

    def _in_half_plane(self, X: np.ndarray) -> np.ndarray:
        """Which of the points ``X`` (..., 3) lie in the meridian's half-plane."""
        g = self.mesh.geometry.x
        extent = self.comm.allreduce(float(np.ptp(g, axis=0).max()) if len(g) else 0.0, op=MPI.MAX)
        tol = TOL * max(extent, 1e-300)
        d = X - self.origin
        return (np.abs(d @ self.normal) <= tol) & (d @ self.across >= -tol)

    def _evaluate(self) -> np.ndarray:
        """The samples of every edge (FacetProfile._evaluate), one row per edge: the mean of its
        facets' rows, each turned to run from its end with the smaller reference coordinates."""
        D = super()._evaluate()
        if self._merge is None:
            self._merge = same_edges(D[:, 0, self._C["X"]], D[:, -1, self._C["X"]])
        flipped, groups = self._merge
        D[flipped] = D[flipped, ::-1]
        return np.array([D[g].mean(axis=0) for g in groups]).reshape(-1, *D.shape[1:])

    def _chain(self, D: np.ndarray) -> tuple:
        """The sampled edges joined end to end by their reference coordinates in the half-plane."""
        X = self._C["X"]
        plane = np.array([self.across, self.axis]).T
        return chain_facets((D[:, 0, X] - self.origin) @ plane, (D[:, -1, X] - self.origin) @ plane)

    def radius(self) -> float:
        """The largest current distance from the axis of the contact set's edges along the meridian
        (0 without contact). Collective."""
        zs = self.zones()
        if not zs:
            return 0.0
        d = np.array([z.start for z in zs] + [z.end for z in zs]) - self.origin
        return float(np.linalg.norm(d - np.outer(d @ self.axis, self.axis), axis=1).max())


def same_edges(A: np.ndarray, B: np.ndarray) -> tuple[np.ndarray, list]:
    """Segments (end points A, B, (n, 3)) that are the same edge: (which run from their larger end
    point to the smaller, the groups of the same edge's rows in the order of their end points)."""
    scale = max(float(np.ptp(np.vstack([A, B]))) if len(A) else 0.0, 1e-300)
    key = lambda P: [tuple(r) for r in np.rint(P / scale * 1e9).astype(np.int64).tolist()]  # noqa: E731
    ka, kb = key(A), key(B)
    flipped = np.array([a > b for a, b in zip(ka, kb)], dtype=bool)
    groups: dict = {}
    for i, (a, b) in enumerate(zip(ka, kb)):
        groups.setdefault((min(a, b), max(a, b)), []).append(i)
    return flipped, [groups[k] for k in sorted(groups)]


class Meridians:
    """The meridians of one contact item's boundary that were asked for, each built on first use
    (``outputs.meridians``; the item's ``meridian`` and ``radius``). Collective."""

    def __init__(self, ctx, item, p_cur, q_cur, N):
        self._args = (ctx, item, p_cur, q_cur, N)
        self._built: dict = {}

    def meridian(self, origin=(0.0, 0.0, 0.0), direction=(1.0, 0.0, 0.0), axis=(0.0, 0.0, 1.0)) -> MeridianProfile:
        """The pressure profile along the meridian (``profile()``, ``zones()``, ``radius()``)."""
        from ..checks import meridian_error
        ctx, item, p_cur, q_cur, N = self._args
        if ctx.mesh.topology.dim != 3:
            raise ContactError("the contact radius is a 3D result, the body is 2D: ask for the contact "
                               "length (ContactLength)")
        why = meridian_error(origin, direction, axis)
        if why is not None:
            raise ContactError(why)
        key = tuple(float(v) for v in (*np.ravel(origin), *np.ravel(direction), *np.ravel(axis)))
        if key not in self._built:
            self._built[key] = MeridianProfile(ctx, item.obstacle, item.u, p_cur, q_cur, N,
                                               ctx.facets(item.boundary), item.comm, origin, direction, axis)
        return self._built[key]

    def radius(self, origin=(0.0, 0.0, 0.0), direction=(1.0, 0.0, 0.0), axis=(0.0, 0.0, 1.0)) -> float:
        """The contact radius along the meridian (MeridianProfile.radius)."""
        return self.meridian(origin, direction, axis).radius()

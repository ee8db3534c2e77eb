"""The geometry of a triangulated surface in NumPy: the closest point of the surface to given points,
the signed distance to it and the unit normal there, for the rigid :class:`Surface` obstacle
(surface.py; docs/theory.md section 6.1).

The triangles' vertex order orients the surface: the normal of a triangle (a, b, c) is
(b - a) x (c - a), normalised, and points to the body's side. For a point x with the closest
point p of the surface (the nearest point of the nearest triangle):

* p inside a triangle: the normal n is the triangle's, and the gap g = (x - p) . n is the signed
  distance to the triangle's plane;
* p on an edge or at a vertex: ``n = s (x - p) / |x - p|``, s = +1 or -1 the side of x, told by
  the sign of ``(x - p) . m`` with m the edge's or vertex's pseudo-normal (the sum of its
  triangles' normals; at a vertex each weighted by its angle there), so that
  ``g = (x - p) . n = s |x - p|``.

g is thus the signed distance to the surface, continuous, and n its gradient: a convex edge or
vertex acts as if rounded with radius 0 (the levels g = c > 0 are rounded about it). At p on an
edge with x on the surface (``|x - p| = 0``) n is the edge's pseudo-normal. For a closed surface that
does not cross itself the side is exact (the angle-weighted pseudo-normal tells inside from
outside); an open surface's edges on its border are treated like those of a single triangle.

The search: a k-d tree of the triangles' centroids (scipy.spatial.cKDTree). The nearest centroid,
at r0 from x, bounds the distance to the surface; a triangle whose closest point is nearer lies
within r0 + R_max of x, R_max the largest distance of a triangle's vertex from its centroid, so the
triangles with centroids in that ball are the candidates, each measured exactly.
"""
from __future__ import annotations

import numpy as np

FACE, EDGE, VERTEX = 0, 1, 2


def _unit(v: np.ndarray) -> np.ndarray:
    n = np.linalg.norm(v, axis=-1, keepdims=True)
    return v / np.where(n > 0.0, n, 1.0)


class TriangleSurface:
    """The surface of the triangles ``triangles`` (M, 3) of vertex indices into ``points`` (N, 3),
    oriented by their vertex order (the module docstring). ``error`` is the exception type of
    unusable input (its message names the value and the fix)."""

    def __init__(self, points, triangles, error=ValueError):
        from scipy.spatial import cKDTree
        self.points = np.asarray(points, dtype=float)
        self.triangles = np.asarray(triangles, dtype=np.int64)
        self._check(error)
        a, b, c = (self.points[self.triangles[:, k]] for k in range(3))
        cross = np.cross(b - a, c - a)
        self.face_normals = _unit(cross)
        self.areas = 0.5 * np.linalg.norm(cross, axis=1)
        centroids = (a + b + c) / 3.0
        self.r_max = float(max(np.linalg.norm(v - centroids, axis=1).max() for v in (a, b, c)))
        self.tree = cKDTree(centroids)
        self._edges(error)
        self._vertex_normals(a, b, c)

    def _check(self, error) -> None:
        p, t = self.points, self.triangles
        if p.ndim != 2 or p.shape[1] != 3 or len(p) < 3 or not np.all(np.isfinite(p)):
            raise error(f"surface points of shape {p.shape}: give (N, 3) finite coordinates, N >= 3")
        if t.ndim != 2 or t.shape[1] != 3 or len(t) < 1 or t.min() < 0 or t.max() >= len(p):
            raise error(f"surface triangles of shape {t.shape}: give (M, 3) indices of the points, "
                        f"from 0 to {len(p) - 1}")

    def _edges(self, error) -> None:
        """The edges (their vertex pairs), each triangle's three (a-b, b-c, c-a) as edge numbers, and
        each edge's pseudo-normal; ``error`` if two triangles cross an edge in the same direction
        (their orientations disagree) or more than two share it."""
        t = self.triangles
        directed = np.stack([t[:, [0, 1]], t[:, [1, 2]], t[:, [2, 0]]], axis=1).reshape(-1, 2)
        key = np.sort(directed, axis=1)
        self.edges, inverse, counts = np.unique(key, axis=0, return_inverse=True, return_counts=True)
        inverse = inverse.ravel()
        if counts.max() > 2:
            k = int(np.argmax(counts > 2))
            raise error(f"the surface's edge between points {self.edges[k].tolist()} has {counts[k]} "
                        "triangles: give a surface with at most two triangles at each edge")
        forward = directed[:, 0] < directed[:, 1]
        same = np.zeros(len(self.edges), dtype=int)
        np.add.at(same, inverse, np.where(forward, 1, -1))
        bad = (counts == 2) & (same != 0)
        if bad.any():
            k = int(np.argmax(bad))
            raise error(f"the surface's triangles at the edge between points {self.edges[k].tolist()} are "
                        "oriented oppositely: give all the triangles one orientation (the same side "
                        "counter-clockwise)")
        self.tri_edges = inverse.reshape(-1, 3)
        self.closed = bool(np.all(counts == 2))
        normals = np.zeros((len(self.edges), 3))
        np.add.at(normals, inverse, np.repeat(self.face_normals, 3, axis=0))
        self.edge_normals = _unit(normals)

    def _vertex_normals(self, a, b, c) -> None:
        """Each vertex's pseudo-normal: its triangles' normals weighted by their angles there."""
        normals = np.zeros_like(self.points)
        for k, (p, q, r) in enumerate(((a, b, c), (b, c, a), (c, a, b))):
            u, v = _unit(q - p), _unit(r - p)
            angle = np.arccos(np.clip(np.einsum("ij,ij->i", u, v), -1.0, 1.0))
            np.add.at(normals, self.triangles[:, k], angle[:, None] * self.face_normals)
        self.vertex_normals = _unit(normals)

    def signed_volume(self) -> float:
        """The volume enclosed by a closed surface, > 0 when its normals point outwards."""
        a, b, c = (self.points[self.triangles[:, k]] for k in range(3))
        return float(np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6.0)

    def flipped(self) -> "TriangleSurface":
        """The same surface with the other orientation (its normals reversed)."""
        return TriangleSurface(self.points, self.triangles[:, ::-1])

    def closest(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """For the points x (n, 3): the closest points p (n, 3) of the surface, the unit normals n
        (n, 3) there and the signed distances g (n,), g = (x - p) . n (the module docstring)."""
        x = np.asarray(x, dtype=float).reshape(-1, 3)
        if len(x) == 0:
            return np.zeros((0, 3)), np.zeros((0, 3)), np.zeros(0)
        point, tri = self._candidates(x)
        p, kind, which, d2 = closest_on_triangles(x[point], *(self.points[self.triangles[tri, k]] for k in range(3)))
        best = _first_minimum(point, d2, len(x))
        p, kind, which, tri = p[best], kind[best], which[best], tri[best]
        pseudo = self.face_normals[tri]
        on_edge, at_vertex = kind == EDGE, kind == VERTEX
        pseudo[on_edge] = self.edge_normals[self.tri_edges[tri[on_edge], which[on_edge]]]
        pseudo[at_vertex] = self.vertex_normals[self.triangles[tri[at_vertex], which[at_vertex]]]
        rel = x - p
        dist = np.linalg.norm(rel, axis=1)
        side = np.where(np.einsum("ij,ij->i", rel, pseudo) < 0.0, -1.0, 1.0)
        scale = max(float(np.ptp(self.points, axis=0).max()), 1e-300)
        radial = (kind != FACE) & (dist > 1e-12 * scale)
        n = pseudo
        n[radial] = side[radial, None] * rel[radial] / dist[radial, None]
        g = np.where(kind == FACE, np.einsum("ij,ij->i", rel, n), side * dist)
        return p, n, g

    def _candidates(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(point, triangle) index pairs: for each point the triangles that may hold its closest
        point (the module docstring's ball)."""
        r0, _ = self.tree.query(x)
        balls = self.tree.query_ball_point(x, r0 * (1.0 + 1e-12) + self.r_max * (1.0 + 1e-9))
        counts = np.fromiter((len(b) for b in balls), dtype=np.int64, count=len(x))
        tri = np.fromiter((j for b in balls for j in b), dtype=np.int64, count=int(counts.sum()))
        return np.repeat(np.arange(len(x)), counts), tri


def _first_minimum(group: np.ndarray, value: np.ndarray, n: int) -> np.ndarray:
    """For each group 0..n-1 (``group`` sorted ascending, every group present), the index of its
    smallest ``value`` (the first such if several)."""
    order = np.lexsort((np.arange(len(value)), value, group))
    starts = np.searchsorted(group[order], np.arange(n))
    return order[starts]


def closest_on_triangles(x, a, b, c):
    """The closest point of the triangle (a, b, c) to x, row by row (all (m, 3)): (p, kind, which,
    ``|x - p|^2``) with kind FACE, EDGE or VERTEX and ``which`` the edge (0: a-b, 1: b-c, 2: c-a) or
    vertex (0: a, 1: b, 2: c) it lies on."""
    e1, e2, d = b - a, c - a, x - a
    d11, d12, d22 = (np.einsum("ij,ij->i", u, v) for u, v in ((e1, e1), (e1, e2), (e2, e2)))
    b1, b2 = np.einsum("ij,ij->i", d, e1), np.einsum("ij,ij->i", d, e2)
    det = d11 * d22 - d12 * d12
    ok = det > 1e-14 * (d11 * d22)
    safe = np.where(ok, det, 1.0)
    s, t = (d22 * b1 - d12 * b2) / safe, (d11 * b2 - d12 * b1) / safe
    inside = ok & (s >= 0.0) & (t >= 0.0) & (s + t <= 1.0)
    p = a + s[:, None] * e1 + t[:, None] * e2
    kind = np.full(len(x), FACE)
    which = np.zeros(len(x), dtype=np.int64)
    best = np.full(len(x), np.inf)
    for k, (p0, p1) in enumerate(((a, b), (b, c), (c, a))):
        e = p1 - p0
        L2 = np.einsum("ij,ij->i", e, e)
        tau = np.clip(np.einsum("ij,ij->i", x - p0, e) / np.where(L2 > 0, L2, 1.0), 0.0, 1.0)
        q = p0 + tau[:, None] * e
        dq = np.einsum("ij,ij->i", x - q, x - q)
        take = ~inside & (dq < best)
        best = np.where(take, dq, best)
        p[take] = q[take]
        kind[take] = np.where((tau[take] > 0.0) & (tau[take] < 1.0), EDGE, VERTEX)
        which[take] = np.where(tau[take] >= 1.0, (k + 1) % 3, k)
    rel = x - p
    return p, kind, which, np.einsum("ij,ij->i", rel, rel)


def read_gmsh(path, surface, size, error) -> tuple[np.ndarray, np.ndarray]:
    """(points (N, 3), triangles (M, 3)) of the surfaces ``surface`` (a physical group's name or a
    list of surface tags) of the Gmsh file ``path`` (an existing .geo, .brep, .step or .msh file).
    A geometry is meshed into triangles here, of about ``size`` (None: the file's own sizes); a
    .msh file's triangles are taken as they are. Each surface's triangles are oriented as Gmsh
    orients that surface. Unusable input raises ``error`` (the exception type) in one line. Gmsh is
    started and finalised here."""
    from ..geometry import gmsh_session
    with gmsh_session.opened(path, "surface", error) as gmsh:
        tags = _surface_tags(gmsh, path, surface, error)
        if not str(path).lower().endswith(".msh"):
            if size is not None:
                gmsh.option.setNumber("Mesh.MeshSizeMax", size)
                gmsh.option.setNumber("Mesh.MeshSizeMin", size)
            gmsh.model.mesh.generate(2)
        node_tags, coords, _ = gmsh.model.mesh.getNodes()
        index = np.full(int(node_tags.max()) + 1, -1, dtype=np.int64)
        index[node_tags.astype(np.int64)] = np.arange(len(node_tags))
        triangles = []
        for tag in tags:
            types, _, nodes = gmsh.model.mesh.getElements(2, tag)
            for kind, conn in zip(types, nodes):
                if kind != 2:                     # 3-node triangles only
                    raise error(f"surface file {path}: surface {tag} has elements of Gmsh type {kind}: "
                                "give a surface meshed into 3-node triangles")
                triangles.append(index[np.asarray(conn, dtype=np.int64).reshape(-1, 3)])
    if not triangles:
        raise error(f"surface file {path}: the surfaces {surface!r} have no triangles: mesh them (or give a "
                    "geometry file, which is meshed here)")
    triangles = np.concatenate(triangles)
    used, triangles = np.unique(triangles, return_inverse=True)
    return np.reshape(coords, (-1, 3))[used], triangles.reshape(-1, 3)


def _surface_tags(gmsh, path, surface, error) -> list[int]:
    """The tags of the surfaces named by ``surface`` (a physical group's name or a list of tags)."""
    if isinstance(surface, str):
        groups = {gmsh.model.getPhysicalName(2, t): t for _, t in gmsh.model.getPhysicalGroups(2)}
        if surface not in groups:
            raise error(f"surface file {path}: no physical surface named {surface!r}: give one of the "
                        f"file's named surfaces ({', '.join(sorted(groups)) or 'none'})")
        return [int(t) for t in gmsh.model.getEntitiesForPhysicalGroup(2, groups[surface])]
    known = {t for _, t in gmsh.model.getEntities(2)}
    try:
        tags = [int(t) for t in surface]
    except (TypeError, ValueError):
        raise error(f"surface = {surface!r}: give the name of a physical surface or a list of surface tags "
                    f"(the file's are {sorted(known)})") from None
    if not tags or any(t not in known for t in tags):
        raise error(f"surface file {path}: surface tags {tags}: give tags of the file's surfaces {sorted(known)}")
    return tags

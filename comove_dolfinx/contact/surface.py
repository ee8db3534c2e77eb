"""A rigid 3D obstacle of any shape: a triangulated surface, from arrays of points and triangles or
from a surface of a Gmsh geometry (a punch or a die as drawn in CAD).

A triangulated surface is no UFL expression: its closest point to a boundary point is found in
NumPy (trimesh.py) and enters the forms as coefficient fields. For each position x = X + w that
the contact terms ask about (the current one, X + u, and friction's lag state, X + u_lag), the
obstacle keeps two quadratic vector fields: p, the closest point of the surface to each node of
the contact boundary, and n, the unit normal there (the signed distance's gradient; trimesh.py).
Between the nodes they are interpolated, and::

    g = (x - p) . n / |n|,        n_o = n / |n|,

so g is the signed distance at the nodes, and between them the distance to the interpolated
tangent planes. The fields are computed anew whenever their position or the obstacle's
displacement changed (:meth:`Surface.track`, with tracking.py's Dependencies): the contact item
calls it before each assembly of the model's forms and of its results.

The Jacobian holds p and n fixed (they are coefficients): it is exact where the boundary's nodes
have their closest points on one flat face (p moves in the face, square to n, and n is constant),
and only approximate where they lie on edges or vertices, or on different faces (the derivative
of n there is left out). docs/theory.md section 6.1 says more.
"""
from __future__ import annotations

import pathlib

import numpy as np
import ufl
from dolfinx import fem

from .. import compat
from ..checks import number
from . import trimesh
from .obstacles import ContactError, Obstacle
from .tracking import Dependencies, terminals


class _Tracked:
    """The closest-point fields of one position x = X + w (w a displacement Function, linear or
    quadratic) against the obstacle moved by ``d`` (a Constant): p and n, quadratic (so that
    the chord between the nodes of a linear body does not cut the surface's curvature; w is
    interpolated exactly onto their nodes), and what they depend on."""

    def __init__(self, x, d):
        funcs, _ = terminals([x])
        if len(funcs) != 1:
            raise ContactError(f"a Surface's position must be X + w for one displacement w; got {len(funcs)} "
                               "functions in it")
        self.x, self.d, self.w = x, d, funcs[0]
        msh = self.w.function_space.mesh
        W = compat.function_space(msh, "Lagrange", 2, (3,))
        self.p, self.n = fem.Function(W, name="closest_point"), fem.Function(W, name="surface_normal")
        self._w2 = fem.Function(W)
        self.depends = Dependencies(msh.comm, [x, d])
        self.X = W.tabulate_dof_coordinates()[:, :3]
        self._nodes = None

    def nodes(self, facets: np.ndarray | None) -> np.ndarray:
        """The owned nodes of the fields' space on ``facets`` (local facet indices; None: every
        owned node)."""
        if self._nodes is None:
            W = self.p.function_space
            owned = W.dofmap.index_map.size_local
            if facets is None:
                self._nodes = np.arange(owned)
            else:
                dofs = fem.locate_dofs_topological(W.sub(0), W.mesh.topology.dim - 1, facets)
                nodes = np.unique(dofs // W.dofmap.index_map_bs)
                self._nodes = nodes[nodes < owned]
        return self._nodes

    def update(self, surface, facets: np.ndarray | None) -> None:
        """Recompute p and n at the owned nodes on ``facets`` if the position or the displacement
        changed since the last time. Collective."""
        if not self.depends.stale():
            return
        nodes = self.nodes(facets)
        d = np.asarray(self.d.value, dtype=float)
        self._w2.interpolate(self.w)
        x = self.X[nodes] + self._w2.x.array.reshape(-1, 3)[nodes]
        p, n, _ = surface.closest(x - d)
        for field, values in ((self.p, p + d), (self.n, n)):
            field.x.array.reshape(-1, 3)[nodes] = values
            field.x.scatter_forward()
        self.depends.mark()


class Surface(Obstacle):
    """A rigid triangulated surface (3D): the triangles ``triangles`` (M, 3) of vertex indices into
    ``points`` (N, 3), the body on the side that their vertex order turns counter-clockwise about
    (the normal (b - a) x (c - a) of a triangle (a, b, c) points to the body; ``flip`` turns it
    round); ``motion`` a 3-vector or a callable, as for the other obstacles.

    The gap is the signed distance to the surface at the contact boundary's nodes, the normal its
    gradient (a triangle's normal on its face, the direction from the closest point at an edge or
    vertex, which act as rounded with radius 0), both interpolated between the nodes (the module
    docstring). On a flat part the gap is the plane's exactly and the Jacobian exact; across edges
    the Jacobian leaves out the normal's turning (Newton converges more slowly there, not to
    another solution). Every rank holds the whole surface and computes the closest points of its
    own nodes: the answers do not depend on the number of ranks.
    """

    def __init__(self, points, triangles, motion=None, flip: bool = False):
        super().__init__(motion, 3)
        if not isinstance(flip, bool):
            raise ContactError(f"flip = {flip!r}: give True (turn the surface's normals round) or False")
        self.surface = trimesh.TriangleSurface(points, triangles, ContactError)
        if flip:
            self.surface = self.surface.flipped()
        self._tracked: dict = {}
        self._facets = None

    @classmethod
    def from_gmsh(cls, path, surface, size: float | None = None, motion=None, flip: bool = False) -> "Surface":
        """The surfaces ``surface`` (the name of a physical group of surfaces, or a list of surface
        tags) of a Gmsh file (``.geo``, ``.brep``, ``.step``: meshed here into triangles of about
        ``size``, None: the file's own mesh sizes; ``.msh``: its triangles). The triangles are
        oriented as Gmsh orients each surface, except a closed surface (each edge between two
        triangles), whose normals are turned outwards: the body outside it. ``flip`` turns the
        normals round (the body inside a closed surface). The triangles deviate from a smooth
        surface of curvature radius R by up to about size^2 / (8 R). Gmsh is started and finalised
        here: call it outside a gmsh session of your own."""
        path = pathlib.Path(path)
        if not path.is_file():
            raise ContactError(f"surface file {path}: no such file: give the path of a .geo, .brep, .step "
                               "or .msh file")
        if size is not None and number("size", size, gt=0):
            raise ContactError(f"size = {size!r}: give the triangles' size, a finite number > 0 (or None)")
        points, triangles = trimesh.read_gmsh(path, surface, None if size is None else float(size), ContactError)
        shape = trimesh.TriangleSurface(points, triangles, ContactError)
        if shape.closed and shape.signed_volume() < 0.0:
            triangles = triangles[:, ::-1]
        return cls(points, triangles, motion, flip)

    # -- the fields -----------------------------------------------------------------------------
    def on_boundary(self, facets: np.ndarray) -> None:
        """Compute the closest points on these facets (local indices of a contact boundary's; without
        a call, at every node)."""
        old = np.zeros(0, dtype=np.int32) if self._facets is None else self._facets
        self._facets = np.union1d(old, facets).astype(np.int32)
        for t in self._tracked.values():
            t._nodes = None

    def _fields(self, x, d) -> _Tracked:
        d = self.d if d is None else d
        key = (id(x), id(d))
        if key not in self._tracked:
            self._tracked[key] = _Tracked(x, d)
        return self._tracked[key]

    def track(self) -> None:
        """Bring the closest points of every position asked about to the current state (each only if
        its displacement or the obstacle's changed). Collective."""
        for t in self._tracked.values():
            t.update(self.surface, self._facets)

    # -- the obstacle's interface -------------------------------------------------------------------
    def gap(self, x, d=None):
        t = self._fields(x, d)
        return ufl.dot(x - t.p, t.n) / ufl.sqrt(ufl.dot(t.n, t.n))

    def normal(self, x, d=None):
        t = self._fields(x, d)
        return t.n / ufl.sqrt(ufl.dot(t.n, t.n))

    def gap_np(self, x, d):
        return self.surface.closest(np.asarray(x, dtype=float) - d)[2]

"""Rigid obstacles: a plane, a circle (cylinder), a profile with rounded corners in 2D; a plane, a
sphere and a cylinder in 3D; each can move.

An obstacle gives, for the current position x = X + u of a boundary point, the signed gap g (>= 0 when
apart, < 0 when penetrating) and the unit normal n_o pointing from the obstacle to the body's side
(docs/theory.md section 6.1), in UFL (``gap``, ``normal``) and in NumPy (``gap_np``). It moves rigidly by
``motion`` times its contact item's factor (a vector), or along ``motion(factor)`` (a callable).
Its dimension ``dim`` (2 or 3) follows the vectors it is given: a plane through a point (x, y) is a 2D
obstacle, through (x, y, z) a 3D one; a contact item refuses an obstacle of the other dimension than
its body's.
"""
from __future__ import annotations

import math

import numpy as np
import ufl
from dolfinx import fem
from petsc4py import PETSc

from ..checks import is_number, number


class ContactError(ValueError):
    """Unusable contact input (the message names the value and the fix)."""


def _vector(name: str, value, size: int = 2) -> np.ndarray:
    """``value`` as a float array of ``size`` finite numbers, else ContactError naming ``name``."""
    flat = np.ravel(np.asarray(value, dtype=object))
    ok = len(flat) == size and all(is_number(v) for v in flat)
    a = np.asarray(value, dtype=float) if ok else np.zeros(0)
    if a.shape != (size,) or not np.all(np.isfinite(a)):
        raise ContactError(f"{name} = {value!r}: give {size} finite numbers")
    return a


def _dimension(name: str, value) -> int:
    """2 or 3: how many numbers the point ``value`` has (ContactError otherwise)."""
    n = len(np.ravel(np.asarray(value, dtype=object)))
    if n not in (2, 3):
        raise ContactError(f"{name} = {value!r}: give 2 finite numbers (a 2D body) or 3 (a 3D body)")
    return n


class Obstacle:
    """A rigid obstacle, fixed or translated rigidly by motion (see the module docstring); ``dim``
    its dimension (2 or 3)."""

    dim = 2

    def __init__(self, motion=None, dim: int = 2):
        self.dim = dim
        if motion is not None and not callable(motion):
            motion = _vector("motion", motion, dim)
        self.motion = motion
        self.d = None          # its current displacement (a Constant, once bound to a mesh)

    def displacement(self, factor: float) -> np.ndarray:
        """Rigid displacement of the obstacle at its item's factor."""
        if self.motion is None:
            return np.zeros(self.dim)
        if callable(self.motion):
            return _vector("motion(factor)", self.motion(factor), self.dim)
        return factor * self.motion

    def bind(self, mesh) -> None:
        if self.d is None:
            self.d = fem.Constant(mesh, PETSc.ScalarType((0.0,) * self.dim))

    def set(self, factor: float) -> None:
        self.d.value = self.displacement(factor)

    # UFL (current position x; d the obstacle's displacement, default the current one) and NumPy
    # (positions (N, 2), displacement d)
    def gap(self, x, d=None):  # pragma: no cover - interface
        raise NotImplementedError

    def normal(self, x, d=None):  # pragma: no cover - interface
        raise NotImplementedError

    def gap_np(self, x: np.ndarray, d: np.ndarray) -> np.ndarray:  # pragma: no cover - interface
        raise NotImplementedError


class Plane(Obstacle):
    """The rigid half-plane (2D) or half-space (3D) {(x - point) . normal <= 0}; ``normal`` points
    towards the body. Two numbers each make a 2D obstacle, three a 3D one."""

    def __init__(self, point, normal, motion=None):
        dim = _dimension("the plane's point", point)
        super().__init__(motion, dim)
        self.point = _vector("the plane's point", point, dim)
        n = _vector("the plane's normal", normal, dim)
        if np.linalg.norm(n) == 0:
            raise ContactError("the plane's normal must not be zero")
        self.n = n / np.linalg.norm(n)

    def gap(self, x, d=None):
        d = self.d if d is None else d
        return ufl.dot(x - ufl.as_vector(self.point) - d, ufl.as_vector(self.n))

    def normal(self, x, d=None):
        return ufl.as_vector(self.n)

    def gap_np(self, x, d):
        return (x - self.point - d) @ self.n


class _Round(Obstacle):
    """An obstacle whose surface is at the distance ``radius`` from a centre or an axis, the body
    outside: the gap is the length of x's offset ``_rel`` from it minus the radius, the normal
    that offset's direction."""

    def gap(self, x, d=None):
        r = self._rel(x, d)
        return ufl.sqrt(ufl.dot(r, r)) - self.radius

    def normal(self, x, d=None):
        r = self._rel(x, d)
        return r / ufl.sqrt(ufl.dot(r, r))


class _Ball(_Round):
    """A rigid disc (2D) or ball (3D) of radius ``radius`` about ``center``; the body is outside it."""

    def _rel(self, x, d):
        return x - ufl.as_vector(self.center) - (self.d if d is None else d)

    def gap_np(self, x, d):
        return np.linalg.norm(x - self.center - d, axis=1) - self.radius


class Circle(_Ball):
    """A rigid disc (cylinder) of radius ``radius``; the body is outside it. 2D only (``center``
    (x, y)); in 3D :class:`Sphere` and :class:`Cylinder`."""

    def __init__(self, center, radius, motion=None):
        if len(np.ravel(np.asarray(center, dtype=object))) == 3:
            raise ContactError(f"the circle's center = {center!r}: a Circle is 2D; for a 3D body give "
                               "Sphere(centre, radius) or Cylinder(point, axis, radius)")
        super().__init__(motion)
        self.center = _vector("the circle's center", center)
        if number("radius", radius, gt=0):
            raise ContactError(f"radius = {radius!r}: the obstacle's radius must be a finite number > 0")
        self.radius = float(radius)


class Sphere(_Ball):
    """A rigid ball of radius ``radius`` about ``centre`` (x, y, z); the body is outside it (3D)."""

    def __init__(self, centre, radius, motion=None):
        super().__init__(motion, 3)
        self.center = _vector("the sphere's centre", centre, 3)
        if number("radius", radius, gt=0):
            raise ContactError(f"radius = {radius!r}: the sphere's radius must be a finite number > 0")
        self.radius = float(radius)


class Profile(Obstacle):
    """A rigid profile with rounded corners: the points within ``radius`` of the polyline ``points``
    (a chain of capsules), the body outside. A flat punch of width w with edges rounded to r is the
    segment of length w - 2r at the punch's face, offset by r; a single point gives a circle.

    The gap is the distance to the polyline minus the radius (the nearest segment wins), the normal
    points from the polyline's nearest point to x: both are continuous across the corners, where
    the profile is an arc of the radius (docs/theory.md section 6.1).
    """

    def __init__(self, points, radius: float, motion=None):
        super().__init__(motion)
        flat = np.ravel(np.asarray(points, dtype=object))
        ok = len(flat) % 2 == 0 and all(is_number(v) for v in flat)
        pts = np.asarray(points, dtype=float).reshape(-1, 2) if ok else np.zeros((0, 2))
        if len(pts) < 1 or not np.all(np.isfinite(pts)):
            raise ContactError(f"points = {points!r}: give a polyline of finite (x, y) points")
        if number("radius", radius, gt=0):
            raise ContactError(f"radius = {radius!r}: the corners' radius must be a finite number > 0")
        self.points, self.radius = pts, float(radius)
        self.segments = [(pts[i], pts[i + 1]) for i in range(len(pts) - 1)] or [(pts[0], pts[0])]

    @classmethod
    def from_gmsh(cls, path, curve, radius: float, spacing: float | None = None, motion=None) -> "Profile":
        """The profile of the curves of a Gmsh geometry (a ``.geo`` script, ``.brep`` or ``.step``
        file): ``curve`` is the name of a physical group of curves, or a list of curve tags, whose
        curves join end to end (each is turned as needed to continue the chain). Every curve is
        sampled at about ``spacing`` (default ``radius``) along its length, so a smooth curve of
        curvature radius R is followed to within spacing^2 / (8 R); ``radius`` rounds the profile's
        corners (as in the constructor). Gmsh is started and finalised here: call it outside a gmsh
        session of your own."""
        import pathlib
        path = pathlib.Path(path)
        if not path.is_file():
            raise ContactError(f"profile file {path}: no such file: give the path of a .geo, .brep or .step file")
        if number("radius", radius, gt=0):
            raise ContactError(f"radius = {radius!r}: the corners' radius must be a finite number > 0")
        spacing = radius if spacing is None else spacing
        if number("spacing", spacing, gt=0):
            raise ContactError(f"spacing = {spacing!r}: give a finite number > 0")
        spacing = float(spacing)
        from ..geometry import gmsh_session
        gmsh = gmsh_session.gmsh
        gmsh_session.start()
        try:
            try:
                gmsh.open(str(path))
            except Exception as err:                  # noqa: BLE001 - gmsh raises plain Exception
                raise ContactError(f"profile file {path}: gmsh cannot read it ({err})") from None
            if isinstance(curve, str):
                groups = {gmsh.model.getPhysicalName(1, t): t for _, t in gmsh.model.getPhysicalGroups(1)}
                if curve not in groups:
                    raise ContactError(f"profile file {path}: no physical curve named {curve!r}; the named "
                                       f"curves are {', '.join(sorted(groups)) or 'none'}")
                tags = list(gmsh.model.getEntitiesForPhysicalGroup(1, groups[curve]))
            else:
                tags = [int(t) for t in curve]
                known = {t for _, t in gmsh.model.getEntities(1)}
                if not tags or any(t not in known for t in tags):
                    raise ContactError(f"profile file {path}: curve tags {tags}: the file's curves are "
                                       f"{sorted(known)}")
            pieces = []
            for tag in tags:
                lo, hi = (float(v[0]) for v in gmsh.model.getParametrizationBounds(1, tag))
                fine = np.reshape(gmsh.model.getValue(1, tag, np.linspace(lo, hi, 401)), (-1, 3))[:, :2]
                length = float(np.linalg.norm(np.diff(fine, axis=0), axis=1).sum())
                n = max(int(math.ceil(length / spacing)), 1)
                pieces.append(np.reshape(gmsh.model.getValue(1, tag, np.linspace(lo, hi, n + 1)), (-1, 3))[:, :2])
        finally:
            gmsh_session.stop()
        return cls(_chain(pieces, path), radius, motion)

    def _nearest(self, x, d):
        """Nearest point of the polyline to x (UFL): the segments' nearest points, the closest kept,
        chosen pairwise in a balanced tree (a chain of choices, each referring to the one before,
        makes the differentiated form grow exponentially with the segments; the tree keeps its depth
        at log2 of their number)."""
        d = self.d if d is None else d
        cands = []
        for a, b in self.segments:
            a_, ab = ufl.as_vector(a) + d, b - a
            L2 = float(ab @ ab)
            if L2 > 0.0:
                s = ufl.dot(x - a_, ufl.as_vector(ab)) / L2
                s = ufl.min_value(ufl.max_value(s, 0.0), 1.0)
                c = a_ + s * ufl.as_vector(ab)
            else:
                c = a_
            r = x - c
            cands.append((c, ufl.dot(r, r)))
        while len(cands) > 1:
            merged = []
            for (c1, d1), (c2, d2) in zip(cands[0::2], cands[1::2]):
                closer = ufl.lt(d2, d1)
                merged.append((ufl.as_vector([ufl.conditional(closer, c2[i], c1[i]) for i in range(2)]),
                               ufl.conditional(closer, d2, d1)))
            if len(cands) % 2:
                merged.append(cands[-1])
            cands = merged
        return cands[0]

    def gap(self, x, d=None):
        _, d2 = self._nearest(x, d)
        return ufl.sqrt(d2) - self.radius

    def normal(self, x, d=None):
        c, d2 = self._nearest(x, d)
        return (x - c) / ufl.sqrt(d2)

    def gap_np(self, x, d):
        dist = np.full(len(x), np.inf)
        for a, b in self.segments:
            ab = b - a
            L2 = float(ab @ ab)
            s = np.clip((x - a - d) @ ab / L2, 0.0, 1.0) if L2 > 0 else np.zeros(len(x))
            dist = np.minimum(dist, np.linalg.norm(x - a - d - s[:, None] * ab, axis=1))
        return dist - self.radius


class Cylinder(_Round):
    """A rigid cylinder of radius ``radius`` about the axis through ``point`` along ``axis`` (3-vectors,
    the axis need not be of unit length); the body is outside it (3D). The gap is the distance
    from the axis minus the radius, the normal points from the axis to x, square to it."""

    def __init__(self, point, axis, radius, motion=None):
        super().__init__(motion, 3)
        self.point = _vector("the cylinder's point on the axis", point, 3)
        a = _vector("the cylinder's axis", axis, 3)
        if np.linalg.norm(a) == 0:
            raise ContactError("the cylinder's axis must not be zero: give its direction, e.g. (0, 1, 0)")
        self.axis = a / np.linalg.norm(a)
        if number("radius", radius, gt=0):
            raise ContactError(f"radius = {radius!r}: the cylinder's radius must be a finite number > 0")
        self.radius = float(radius)

    def _rel(self, x, d):
        """x's offset from the axis, square to it (UFL)."""
        r = x - ufl.as_vector(self.point) - (self.d if d is None else d)
        a = ufl.as_vector(self.axis)
        return r - ufl.dot(r, a) * a

    def gap_np(self, x, d):
        r = x - self.point - d
        r = r - np.outer(r @ self.axis, self.axis)
        return np.linalg.norm(r, axis=1) - self.radius


def _chain(pieces: list[np.ndarray], path) -> np.ndarray:
    """The sampled curves joined end to end into one polyline (a curve is reversed to continue the
    chain; the first is turned to meet the second)."""
    scale = max(float(np.ptp(np.concatenate(pieces), axis=0).max()), 1.0)
    tol = 1e-8 * scale
    line = pieces[0]
    if len(pieces) > 1 and min(np.linalg.norm(line[0] - pieces[1][[0, -1]], axis=1)) < tol:
        line = line[::-1]
    for k, p in enumerate(pieces[1:], 2):
        if np.linalg.norm(p[-1] - line[-1]) < tol:
            p = p[::-1]
        if np.linalg.norm(p[0] - line[-1]) >= tol:
            raise ContactError(f"profile file {path}: curve {k} of the chain does not start where curve "
                               f"{k - 1} ends: list the curves in order along the profile")
        line = np.vstack([line, p[1:]])
    return line

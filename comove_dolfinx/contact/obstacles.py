"""Rigid obstacles: a plane, a circle (cylinder), a profile with rounded corners in 2D; a plane, a
sphere and a cylinder in 3D (and a profile extruded or revolved: swept.py; a triangulated surface:
surface.py); each can move.

An obstacle gives, for the current position x = X + u of a boundary point, the signed gap g (>= 0 when
apart, < 0 when penetrating) and the unit normal n_o pointing from the obstacle to the body's side
(docs/theory.md section 6.1), in UFL (``gap``, ``normal``) and in NumPy (``gap_np``). It moves rigidly by
``motion`` times its contact item's factor (a vector), or along ``motion(factor)`` (a callable).
Its dimension ``dim`` (2 or 3) follows the vectors it is given: a plane through a point (x, y) is a 2D
obstacle, through (x, y, z) a 3D one; a contact item refuses an obstacle of the other dimension than
its body's.
"""
from __future__ import annotations

import numpy as np
import ufl
from dolfinx import fem
from petsc4py import PETSc

from ..checks import is_number, number
from . import polyline


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

    # an obstacle whose gap is not a UFL expression (Surface) computes fields for the boundary's
    # nodes: it is told the nodes and asked to bring its fields up to date before each assembly
    def on_boundary(self, facets) -> None:
        """The local indices of a contact boundary's facets (nothing to do here)."""

    def track(self) -> None:
        """Bring fields computed outside UFL to the current state (nothing to do here)."""

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
    the profile is an arc of the radius (docs/theory.md section 6.1). A 2D obstacle; in 3D it
    makes :class:`Extruded` and :class:`Revolved` bodies.
    """

    def __init__(self, points, radius: float, motion=None):
        super().__init__(motion)
        pts = polyline.polyline_points(points, ContactError)
        if number("radius", radius, gt=0):
            raise ContactError(f"radius = {radius!r}: the corners' radius must be a finite number > 0")
        self.points, self.radius = pts, float(radius)
        self.segments = polyline.segments_of(pts)

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
        return cls(polyline.read_gmsh(path, curve, float(spacing), ContactError), radius, motion)

    def _nearest(self, x, d):
        """Nearest point of the polyline to x and the squared distance to it (UFL; polyline.nearest)."""
        return polyline.nearest(self.segments, x, self.d if d is None else d)

    def gap(self, x, d=None):
        _, d2 = self._nearest(x, d)
        return ufl.sqrt(d2) - self.radius

    def normal(self, x, d=None):
        c, d2 = self._nearest(x, d)
        return (x - c) / ufl.sqrt(d2)

    def gap_np(self, x, d):
        return polyline.distance_np(self.segments, x, d) - self.radius


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

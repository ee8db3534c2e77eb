"""Rigid obstacles: a plane, a circle (cylinder), a profile with rounded corners; each can move.

An obstacle gives, for the current position x = X + u of a boundary point, the signed gap g (>= 0 when
apart, < 0 when penetrating) and the unit normal n_o pointing from the obstacle to the body's side
(docs/theory.md section 6.1), in UFL (``gap``, ``normal``) and in NumPy (``gap_np``). It moves rigidly by
``motion`` times its contact item's factor (a vector), or along ``motion(factor)`` (a callable).
"""
from __future__ import annotations

import math

import numpy as np
import ufl
from dolfinx import fem
from petsc4py import PETSc


class ContactError(ValueError):
    """Unusable contact input (the message names the value and the fix)."""


def _vector(name: str, value, size: int = 2) -> np.ndarray:
    a = np.asarray(value, dtype=float)
    if a.shape != (size,) or not np.all(np.isfinite(a)):
        raise ContactError(f"{name} = {value!r}: give {size} finite numbers")
    return a


class Obstacle:
    """A rigid obstacle, fixed or translated rigidly by motion (see the module docstring)."""

    def __init__(self, motion=None):
        if motion is not None and not callable(motion):
            motion = _vector("motion", motion)
        self.motion = motion
        self.d = None          # its current displacement (a Constant, once bound to a mesh)

    def displacement(self, factor: float) -> np.ndarray:
        """Rigid displacement of the obstacle at its item's factor."""
        if self.motion is None:
            return np.zeros(2)
        if callable(self.motion):
            return _vector("motion(factor)", self.motion(factor))
        return factor * self.motion

    def bind(self, mesh) -> None:
        if self.d is None:
            self.d = fem.Constant(mesh, PETSc.ScalarType((0.0, 0.0)))

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
    """The rigid half-plane {(x - point) . normal <= 0}; ``normal`` points towards the body."""

    def __init__(self, point, normal, motion=None):
        super().__init__(motion)
        self.point = _vector("the plane's point", point)
        n = _vector("the plane's normal", normal)
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


class Circle(Obstacle):
    """A rigid disc (cylinder) of radius ``radius``; the body is outside it."""

    def __init__(self, center, radius, motion=None):
        super().__init__(motion)
        self.center = _vector("the circle's center", center)
        if not (math.isfinite(radius) and radius > 0):
            raise ContactError(f"radius = {radius}: the obstacle's radius must be a finite number > 0")
        self.radius = float(radius)

    def _rel(self, x, d):
        return x - ufl.as_vector(self.center) - (self.d if d is None else d)

    def gap(self, x, d=None):
        r = self._rel(x, d)
        return ufl.sqrt(ufl.dot(r, r)) - self.radius

    def normal(self, x, d=None):
        r = self._rel(x, d)
        return r / ufl.sqrt(ufl.dot(r, r))

    def gap_np(self, x, d):
        return np.linalg.norm(x - self.center - d, axis=1) - self.radius


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
        pts = np.asarray(points, dtype=float).reshape(-1, 2)
        if len(pts) < 1 or not np.all(np.isfinite(pts)):
            raise ContactError(f"points = {points!r}: give a polyline of finite (x, y) points")
        if not (math.isfinite(radius) and radius > 0):
            raise ContactError(f"radius = {radius}: the corners' radius must be a finite number > 0")
        self.points, self.radius = pts, float(radius)
        self.segments = [(pts[i], pts[i + 1]) for i in range(len(pts) - 1)] or [(pts[0], pts[0])]

    def _nearest(self, x, d):
        """Nearest point of the polyline to x (UFL): the segments' nearest points, the closest kept."""
        d = self.d if d is None else d
        best, best_d2 = None, None
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
            d2 = ufl.dot(r, r)
            if best is None:
                best, best_d2 = c, d2
            else:
                closer = ufl.lt(d2, best_d2)
                best = ufl.as_vector([ufl.conditional(closer, c[i], best[i]) for i in range(2)])
                best_d2 = ufl.conditional(closer, d2, best_d2)
        return best, best_d2

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

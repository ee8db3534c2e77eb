"""Rigid 3D obstacles swept from a 2D :class:`Profile` (a polyline with rounded corners, from points
or from a Gmsh geometry's curves): extruded along a straight axis (a prismatic punch or die) or
revolved about one (an axisymmetric punch or die).

Both map the current point x to 2D coordinates q of the profile's plane and take the profile's
gap there (polyline.nearest, the same UFL as the 2D obstacle's); the normal is the profile's 2D
normal mapped back to 3D (docs/theory.md section 6.1):

* extruded: q = ((x - o) . u, (x - o) . v), u and v the directions of the profile's x and y;
  n_o = n_x u + n_y v, square to the axis u x v;
* revolved: q = (r, z), z = (x - o) . a the position along the axis a, r the distance from it;
  n_o = n_r e_r + n_z a, e_r the unit vector from the axis to x. The distance to the revolved
  polyline is the distance in x's meridian half-plane, so the profile lies in r >= 0.
"""
from __future__ import annotations

import numpy as np
import ufl

from . import polyline
from .obstacles import ContactError, Obstacle, Profile, _vector

# r is regularised as sqrt(r^2 + (EPS L)^2), L the profile's size: off the axis it equals r in
# floating point (exactly from r > L / 10, to round-off from r > 1e-8 L), on the axis it is
# differentiable (its gradient there is 0)
EPS = 1e-9


def _profile(name: str, profile) -> Profile:
    """The 2D profile a 3D obstacle is made from; ContactError in one line otherwise."""
    if not isinstance(profile, Profile):
        raise ContactError(f"profile = {profile!r}: give a Profile: cm.Profile(points, radius) or "
                           f"cm.Profile.from_gmsh(path, curve, radius) (the {name}'s section)")
    if profile.motion is not None:
        raise ContactError(f"the {name}'s profile has a motion: give motion=(dx, dy, dz) to the {name} "
                           "instead (the profile's 2D motion does not apply)")
    return profile


def _direction(name: str, value) -> np.ndarray:
    """``value`` as a unit 3-vector; ContactError naming ``name`` if it is not one or zero."""
    a = _vector(name, value, 3)
    if np.linalg.norm(a) == 0:
        raise ContactError(f"{name} = {value!r} must not be zero: give a direction, e.g. (0, 0, 1)")
    return a / np.linalg.norm(a)


class _Swept(Obstacle):
    """A 3D obstacle whose gap is its 2D ``profile``'s gap at 2D coordinates ``_plane(x, d)`` of the
    current point (UFL: the coordinates and the two 3D directions their increases point along)."""

    def __init__(self, profile, origin, motion, name):
        super().__init__(motion, 3)
        self.profile = _profile(name, profile)
        self.origin = _vector(f"the {name}'s origin", origin, 3)
        self.radius = self.profile.radius

    def _rel(self, x, d):
        return x - ufl.as_vector(self.origin) - (self.d if d is None else d)

    def gap(self, x, d=None):
        q, _ = self._plane(x, d)
        _, d2 = polyline.nearest(self.profile.segments, q)
        return ufl.sqrt(d2) - self.radius

    def normal(self, x, d=None):
        q, (e1, e2) = self._plane(x, d)
        c, d2 = polyline.nearest(self.profile.segments, q)
        n = (q - c) / ufl.sqrt(d2)
        return n[0] * e1 + n[1] * e2

    def gap_np(self, x, d):
        q = self._plane_np(np.asarray(x, dtype=float) - self.origin - d)
        return polyline.distance_np(self.profile.segments, q, np.zeros(2)) - self.radius


class Extruded(_Swept):
    """A rigid prism: the 2D ``profile`` (a :class:`Profile`: the points within its radius of its
    polyline) extruded without end along the axis u x v, the body outside it (3D). The profile's
    x runs along ``u``, its y along ``v`` (3-vectors, not parallel; v is made square to u), its
    origin at ``origin``. The default draws the profile in the (x, z) plane and extrudes it along
    y. The gap of x is the profile's gap of x's projection onto its plane; ``motion`` a 3-vector
    or a callable, as for the other obstacles."""

    def __init__(self, profile, u=(1.0, 0.0, 0.0), v=(0.0, 0.0, 1.0), origin=(0.0, 0.0, 0.0), motion=None):
        super().__init__(profile, origin, motion, "Extruded")
        self.u = _direction("the profile's x direction u", u)
        w = _direction("the profile's y direction v", v)
        w = w - (w @ self.u) * self.u
        if np.linalg.norm(w) < 1e-8:
            raise ContactError(f"v = {v!r} is parallel to u = {u!r}: give the profile's y direction across "
                               "its x direction")
        self.v = w / np.linalg.norm(w)
        self.axis = np.cross(self.u, self.v)

    def _plane(self, x, d):
        r = self._rel(x, d)
        u, v = ufl.as_vector(self.u), ufl.as_vector(self.v)
        return ufl.as_vector([ufl.dot(r, u), ufl.dot(r, v)]), (u, v)

    def _plane_np(self, r):
        return np.c_[r @ self.u, r @ self.v]


class Revolved(_Swept):
    """A rigid body of revolution: the 2D ``profile`` (a :class:`Profile`) turned about the axis
    through ``origin`` along ``axis`` (3-vectors; the axis need not be of unit length), the body
    outside it (3D). The profile's x is the distance r from the axis (its points have x >= 0),
    its y the position z along the axis from ``origin``: a single point (R, 0) of radius rho
    gives a torus, a segment from (R, z1) to (R, z2) a cylinder of radius R + rho with rounded
    ends, the point (0, 0) a sphere. The gap of x is the profile's gap of (r, z); the normal
    has a component n_r along the unit vector from the axis to x. On the axis, where that vector
    is undefined, r is regularised by 1e-9 of the profile's size (a change of the gap below
    round-off elsewhere); the gap is differentiable there when the profile's nearest point to the
    point of the axis lies on the axis (a rounded tip, a flat face across the axis), not when it
    lies off it (the centre of a ring, where the gap has a conical peak)."""

    def __init__(self, profile, axis=(0.0, 0.0, 1.0), origin=(0.0, 0.0, 0.0), motion=None):
        super().__init__(profile, origin, motion, "Revolved")
        self.axis = _direction("the axis", axis)
        pts = self.profile.points
        if np.any(pts[:, 0] < 0):
            k = int(np.argmax(pts[:, 0] < 0))
            raise ContactError(f"the revolved profile's point ({pts[k][0]:g}, {pts[k][1]:g}) has x < 0: its x is the "
                               "distance from the axis, give points with x >= 0")
        size = float(np.abs(pts).max()) + self.radius
        self._eps2 = (EPS * size) ** 2

    def _plane(self, x, d):
        rel = self._rel(x, d)
        a = ufl.as_vector(self.axis)
        z = ufl.dot(rel, a)
        p = rel - z * a
        r = ufl.sqrt(ufl.dot(p, p) + self._eps2)
        return ufl.as_vector([r, z]), (p / r, a)

    def _plane_np(self, rel):
        z = rel @ self.axis
        p = rel - np.outer(z, self.axis)
        return np.c_[np.sqrt(np.einsum("ij,ij->i", p, p) + self._eps2), z]

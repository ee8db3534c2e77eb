"""The plane geometry of a polyline, shared by the rigid profiles: a 2D :class:`Profile` and the
3D bodies made from one (:class:`Extruded`, :class:`Revolved`), which evaluate it at 2D coordinates
of the current point (docs/theory.md section 6.1).

* ``nearest``: the polyline's nearest point to a 2D point q and the squared distance to it, in UFL
  (the choice between segments made in a balanced tree, so that its derivatives stay small);
* ``distance_np``: the distance to the polyline in NumPy;
* ``polyline_points`` checks the points, ``read_gmsh`` samples the curves of a Gmsh geometry.
"""
from __future__ import annotations

import math

import numpy as np
import ufl

from ..checks import is_number


def polyline_points(points, error) -> np.ndarray:
    """``points`` as a float array (N, 2), N >= 1, of finite numbers; else ``error`` (the exception
    type) naming them."""
    flat = np.ravel(np.asarray(points, dtype=object))
    ok = len(flat) % 2 == 0 and all(is_number(v) for v in flat)
    pts = np.asarray(points, dtype=float).reshape(-1, 2) if ok else np.zeros((0, 2))
    if len(pts) < 1 or not np.all(np.isfinite(pts)):
        raise error(f"points = {points!r}: give a polyline of finite (x, y) points")
    return pts


def segments_of(pts: np.ndarray) -> list:
    """The segments (a, b) of the polyline ``pts``; a single point is a segment of length 0."""
    return [(pts[i], pts[i + 1]) for i in range(len(pts) - 1)] or [(pts[0], pts[0])]


def nearest(segments: list, q, shift=None):
    """The nearest point c of the polyline (its points moved by ``shift``, a UFL 2-vector, if given)
    to the 2D point q (UFL), and the squared distance ``|q - c|^2`` (UFL).

    Each segment's nearest point is q's projection clamped to the segment; the closest is kept,
    chosen pairwise in a balanced tree: a chain of choices, each referring to the one before,
    makes the differentiated form grow exponentially with the segments, the tree keeps its depth
    at log2 of their number."""
    cands = []
    for a, b in segments:
        a_, ab = (ufl.as_vector(a) + shift if shift is not None else ufl.as_vector(a)), b - a
        L2 = float(ab @ ab)
        if L2 > 0.0:
            s = ufl.dot(q - a_, ufl.as_vector(ab)) / L2
            s = ufl.min_value(ufl.max_value(s, 0.0), 1.0)
            c = a_ + s * ufl.as_vector(ab)
        else:
            c = a_
        r = q - c
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


def distance_np(segments: list, q: np.ndarray, shift: np.ndarray) -> np.ndarray:
    """The distance of the points ``q`` (N, 2) to the polyline moved by ``shift`` (2,)."""
    dist = np.full(len(q), np.inf)
    for a, b in segments:
        ab = b - a
        L2 = float(ab @ ab)
        s = np.clip((q - a - shift) @ ab / L2, 0.0, 1.0) if L2 > 0 else np.zeros(len(q))
        dist = np.minimum(dist, np.linalg.norm(q - a - shift - s[:, None] * ab, axis=1))
    return dist


def read_gmsh(path, curve, spacing: float, error) -> np.ndarray:
    """The polyline (N, 2) of the curves ``curve`` (a physical group's name or a list of curve
    tags) of the Gmsh geometry ``path`` (an existing file), each sampled at about ``spacing``
    along its length and joined end to end; unusable input raises ``error`` (the exception type)
    in one line. Gmsh is started and finalised here."""
    from ..geometry import gmsh_session
    with gmsh_session.opened(path, "profile", error) as gmsh:
        if isinstance(curve, str):
            groups = {gmsh.model.getPhysicalName(1, t): t for _, t in gmsh.model.getPhysicalGroups(1)}
            if curve not in groups:
                raise error(f"profile file {path}: no physical curve named {curve!r}; the named "
                            f"curves are {', '.join(sorted(groups)) or 'none'}")
            tags = list(gmsh.model.getEntitiesForPhysicalGroup(1, groups[curve]))
        else:
            tags = [int(t) for t in curve]
            known = {t for _, t in gmsh.model.getEntities(1)}
            if not tags or any(t not in known for t in tags):
                raise error(f"profile file {path}: curve tags {tags}: the file's curves are {sorted(known)}")
        pieces = []
        for tag in tags:
            lo, hi = (float(v[0]) for v in gmsh.model.getParametrizationBounds(1, tag))
            fine = np.reshape(gmsh.model.getValue(1, tag, np.linspace(lo, hi, 401)), (-1, 3))[:, :2]
            length = float(np.linalg.norm(np.diff(fine, axis=0), axis=1).sum())
            n = max(int(math.ceil(length / spacing)), 1)
            pieces.append(np.reshape(gmsh.model.getValue(1, tag, np.linspace(lo, hi, n + 1)), (-1, 3))[:, :2])
    return chain(pieces, path, error)


def chain(pieces: list[np.ndarray], path, error) -> np.ndarray:
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
            raise error(f"profile file {path}: curve {k} of the chain does not start where curve "
                        f"{k - 1} ends: list the curves in order along the profile")
        line = np.vstack([line, p[1:]])
    return line

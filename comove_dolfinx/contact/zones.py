"""The contact zones and the peak pressure of a sampled pressure profile (NumPy only).

A :class:`ContactProfile` holds the pressure, shear and gap at the facet quadrature points of a
contact boundary, sorted along it (profile.py samples it). From it:

* The zones: the runs of consecutive profile points with p > 0 (a stiff penalty, gamma0 = 1000, can
  leave single points without pressure inside a zone: the discrete solution opens there). A run that
  reaches the end of the boundary ends at the boundary's end point (a symmetry line, say); elsewhere
  its edge lies between the last point in contact and the first one out, where the pressure reaches
  zero. Near the edge of a smooth contact p^2 falls linearly with the distance to the edge
  (p ~ sqrt(a - x), Hertz's solution and every smooth edge alike), while the discrete pressure
  oscillates from point to point; so a straight line is fitted by least squares to p^2 at the last
  eight points in contact (two facets) and the edge put where it reaches zero, kept between the two
  points (half-way when p^2 does not fall there, e.g. at a sharp corner). The estimate's own error is
  thus below the points' spacing (a quarter to a third of an element); the discrete solution's zone
  differs from the exact one by about as much (docs/api.md, "Contact results", against Hertz).
* The peak pressure: a parabola fitted by least squares to the pressures of the facet with the
  largest mean pressure and its two neighbours, at its largest value there (the discrete pressure
  oscillates by a few per cent from point to point where the penalty is stiff; the fit follows the
  profile's curvature, a facet's mean would not).

:func:`chain_facets` orders the boundary's facets along it.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np


def gauss_points(n: int) -> np.ndarray:
    """The n Gauss-Legendre points on [0, 1] (the facet rule of a degree 2n - 1 integral)."""
    return 0.5 * (np.polynomial.legendre.leggauss(n)[0] + 1.0)


@dataclass
class ContactProfile:
    """The contact boundary's quadrature points, sorted along the boundary (numpy arrays, n points).

    Attributes
    ----------
    X, x : (n, 2)
        Reference and current coordinates.
    S, s : (n,)
        Reference and current arc length from the start of the boundary (a boundary of several
        pieces: one after the other, without a gap); under linear kinematics (``small_strain``)
        s is the reference one, as every length there.
    p, q : (n,)
        Contact pressure (>= 0) and tangential traction along t_o, per unit current area.
    gap : (n,)
        The gap to the obstacle (negative: penetration).
    normal : (n, 2)
        The obstacle's normal n_o at the point (towards the body): the traction is p n_o + q t_o.
    piece : (n,)
        Which connected piece of the boundary the point lies on (0, 1, ...).

    The boundary starts at its end point with the smallest x (then y) in the reference configuration.
    """

    X: np.ndarray
    x: np.ndarray
    S: np.ndarray
    s: np.ndarray
    p: np.ndarray
    q: np.ndarray
    gap: np.ndarray
    normal: np.ndarray
    piece: np.ndarray


@dataclass
class Zone:
    """One connected part of the contact set: its edges (current coordinates and arc length)."""

    start: np.ndarray          # current coordinates of the edge at the smaller arc length
    end: np.ndarray
    s_start: float
    s_end: float

    @property
    def length(self) -> float:
        return self.s_end - self.s_start


EDGE_POINTS = 8            # points in contact that the edge's fit takes (two facets' worth)


def edge_fraction(d_in: np.ndarray, p_in: np.ndarray, d_out: float) -> float:
    """Where the pressure reaches zero between the last point in contact and the first one out, as
    a fraction of their distance ``d_out`` (0: at the point in contact). ``d_in``, ``p_in``: the
    points in contact nearest the edge, their distances from the last one (0 for it, > 0 into the
    zone) and pressures. Near the edge of a smooth contact p^2 falls linearly towards the edge, so a
    straight line fitted to p^2 by least squares gives the edge where it reaches zero, kept within
    [0, 1]; half-way when the fit does not fall towards the edge or there is one point only."""
    d_in, p_in = np.asarray(d_in, float), np.asarray(p_in, float)
    if d_in.size < 2 or not d_out > 0.0 or np.ptp(d_in) <= 0.0:
        return 0.5
    slope, value = np.polyfit(-d_in, p_in ** 2, 1)           # p^2 = value + slope t, t towards the edge
    if not slope < 0.0:
        return 0.5
    return float(min(max(-value / slope / d_out, 0.0), 1.0))


def zones_of(prof: ContactProfile, ends: list) -> list[Zone]:
    """The contact zones of a profile (runs of points with p > 0 within a piece): ``ends`` gives
    each piece's end points as ((x_start, s_start), (x_end, s_end)), current coordinates and arc
    length."""
    out = []
    for k, ((x0, s0), (x1, s1)) in enumerate(ends):
        idx = np.flatnonzero(prof.piece == k)
        if idx.size == 0:
            continue
        on = prof.p[idx] > 0.0
        if not on.any():
            continue
        d = np.diff(on.astype(np.int8))
        starts = list(np.flatnonzero(d == 1) + 1)
        stops = list(np.flatnonzero(d == -1))
        if on[0]:
            starts.insert(0, 0)
        if on[-1]:
            stops.append(len(on) - 1)
        for a, b in zip(starts, stops):
            run = idx[a:b + 1]
            if a == 0:
                xa, sa = np.asarray(x0, float), float(s0)
            else:
                xa, sa = _edge(prof, run[:EDGE_POINTS], idx[a - 1])
            if b == len(on) - 1:
                xb, sb = np.asarray(x1, float), float(s1)
            else:
                xb, sb = _edge(prof, run[::-1][:EDGE_POINTS], idx[b + 1])
            out.append(Zone(xa, xb, sa, sb))
    return out


def _edge(prof: ContactProfile, inside: np.ndarray, i_out: int) -> tuple[np.ndarray, float]:
    """The edge between ``inside[0]``, the last point in contact (``inside``: it and the ones
    before it), and the first point out ``i_out``."""
    s, i_in = prof.s, inside[0]
    t = edge_fraction(np.abs(s[inside] - s[i_in]), prof.p[inside], abs(s[i_out] - s[i_in]))
    return (prof.x[i_in] + t * (prof.x[i_out] - prof.x[i_in]), float(s[i_in] + t * (s[i_out] - s[i_in])))


def peak_of(prof: ContactProfile, ends: list, npoints: int) -> float:
    """The peak pressure of a profile (``npoints`` points per facet): a parabola fitted by least
    squares to the pressures in contact on the facet of the largest mean pressure and its two
    neighbours, at its largest value within them (or at the end of the boundary they reach); the
    largest pressure when fewer than three points are in contact there. 0 without contact."""
    p = prof.p
    if not (p > 0).any():
        return 0.0
    w = np.polynomial.legendre.leggauss(npoints)[1] / 2.0
    means = (p.reshape(-1, npoints) * w).sum(axis=1)
    k = int(np.argmax(means))
    piece = prof.piece[::npoints]
    facets = [f for f in (k - 1, k, k + 1) if 0 <= f < len(means) and piece[f] == piece[k]]
    pts = (np.array(facets)[:, None] * npoints + np.arange(npoints)).ravel()
    pts = pts[p[pts] > 0]
    if pts.size < 3:
        return float(p.max())
    s = prof.s[pts]
    c2, c1, c0 = np.polyfit(s, p[pts], 2)
    at = [s.min(), s.max()]
    if c2 < 0 and s.min() <= -c1 / (2 * c2) <= s.max():
        at.append(-c1 / (2 * c2))
    (_, s_start), (_, s_end) = ends[piece[k]]
    first, last = np.flatnonzero(piece == piece[k])[[0, -1]]
    if facets[0] == first:
        at.append(s_start)
    if facets[-1] == last:
        at.append(s_end)
    return float(max(c0 + c1 * v + c2 * v * v for v in at))


def chain_facets(A: np.ndarray, B: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Facets (end points A, B, (n, 2)) joined end to end: (order, flipped, piece) with ``order``
    the facets along the boundary, ``flipped`` where a facet runs from B to A, ``piece`` the
    connected piece of each. A piece starts at its free end with the smallest (x, y) (a closed one
    at its smallest point, towards its smaller neighbour). Deterministic: the same on every rank."""
    n = len(A)
    scale = max(float(np.ptp(np.vstack([A, B]))), 1e-300)
    key = lambda P: [tuple(r) for r in np.rint(P / scale * 1e9).astype(np.int64).tolist()]  # noqa: E731
    ka, kb = key(A), key(B)
    at: dict = {}
    for f in range(n):
        at.setdefault(ka[f], []).append(f)
        at.setdefault(kb[f], []).append(f)
    used = np.zeros(n, dtype=bool)
    order, flipped, piece = [], [], []
    while not used.all():
        free = [k for f in np.flatnonzero(~used) for k in (ka[f], kb[f])
                if sum(not used[g] for g in at[k]) == 1]
        start = min(free) if free else min(k for f in np.flatnonzero(~used) for k in (ka[f], kb[f]))
        cands = [f for f in at[start] if not used[f]]
        f = min(cands, key=lambda g: kb[g] if ka[g] == start else ka[g])
        k, pc = start, (piece[-1] + 1 if piece else 0)
        while True:
            flip = ka[f] != k
            used[f] = True
            order.append(f), flipped.append(flip), piece.append(pc)
            k = ka[f] if flip else kb[f]
            nxt = [g for g in at[k] if not used[g]]
            if not nxt:
                break
            f = nxt[0]
    return np.array(order, dtype=np.int64), np.array(flipped, dtype=bool), np.array(piece, dtype=np.int64)

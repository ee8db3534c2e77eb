"""The material laws of :mod:`comove_dolfinx.mechanics.materials` written in UFL, for facet integrals.

Quadrature-point state cannot be seen on facets (dolfinx evaluates no quadrature function there), so
a term on the boundary that needs the stress of an elastic-plastic body (Nitsche contact) evaluates
the constitutive update itself, at the facet's points, as a UFL function of the displacement: the
trial stress of the stress update, the plastic state of the last converged increment carried by a
cell-wise fit, and the return map below. UFL then differentiates it, so the boundary term's Jacobian
is exact (the derivative of the conditional branches is the consistent tangent).

The functions mirror their NumPy counterparts step for step (same branches, same segment search of
the hardening table), and the tests check them against each other. Stresses are 3x3 UFL tensors
(index 2 out of plane, or the hoop direction in axisymmetry); in plane stress their zz entries are 0.
``elastic`` is any object with E, nu and mu, numbers or UFL values (the model passes Constants);
``hardening`` is a :class:`Hardening` or a :class:`Table` of UFL values (the model's Constants, so that
a new table of the same length does not compile new code).

The radial return is also compiled into the stress evaluation at the quadrature points
(:func:`j2_return_points`, plane strain and axisymmetry): one generated kernel gives the stress and the
plastic strain at every point, as NumPy's return_maps.j2_return_points does in several passes over the
arrays; the Jacobian applies the return's derivative D = d sigma / d sigma_trial from that state
(:func:`j2_tangent_times`), so that no evaluation of the stress computes or stores D
(docs/performance.md).
"""
from __future__ import annotations

import ufl

from .material_data import Hardening

# floor under squared norms whose square root is taken (its branch is never the selected one there)
_TINY = 1e-300


#: unrolled Newton steps on the plastic strain increment where the hardening has a saturation term:
#: from the segment's start they rise monotonically to the root (the residual is convex there) and
#: converge quadratically, the faster the smaller dsigma delta is against 3 mu (the necking bar's law,
#: 4.5 GPa against 240: round-off in 3 steps, delta dp from 0.2 to 50); 8 leave a margin. NumPy's
#: return (Hardening.solve_dp) iterates to round-off instead, which the tests compare with this one
NEWTON_STEPS = 8


class Table:
    """A hardening table's segments (start strains, start stresses, slopes) as sequences of UFL
    values, read by the functions here as they read Hardening.segments; ``dsigma`` and ``delta``
    (UFL values, or None without one) its saturation term, as Hardening's."""

    def __init__(self, strain, stress, slope, dsigma=None, delta=None):
        self.segments = (list(strain), list(stress), list(slope))
        self.smooth = dsigma is not None
        self.dsigma, self.delta = dsigma, delta

    @classmethod
    def of(cls, hardening: Hardening) -> "Table":
        """The table of a :class:`Hardening`, as numbers."""
        extra = dict(dsigma=hardening.dsigma, delta=hardening.delta) if hardening.smooth else {}
        return cls(*hardening.segments, **extra)


def _saturation(hardening, p):
    """(term, slope) of the hardening's saturation term at p; only called where it has one."""
    e = ufl.exp(-hardening.delta * p)
    return hardening.dsigma * (1.0 - e), hardening.dsigma * hardening.delta * e


def _with_saturation(hardening, value, p, which: int):
    """``value`` plus the saturation term (which = 0) or its slope (1) at p, or ``value`` itself
    where there is none (tables compile to the same code as without the term)."""
    return value + _saturation(hardening, p)[which] if hardening.smooth else value


def _segment(hardening: Hardening, holds):
    """(start strain, start stress, slope) of the first segment k with ``holds(k)`` (a UFL
    condition), or of the last segment: the values are selected first and the arithmetic done once
    (the generated code would otherwise evaluate every segment's formula at every point)."""
    p0, s0, h = hardening.segments
    a, b, c = p0[-1], s0[-1], h[-1]
    for k in reversed(range(len(p0) - 1)):
        cond = holds(k)
        a, b, c = (ufl.conditional(cond, p0[k], a), ufl.conditional(cond, s0[k], b),
                   ufl.conditional(cond, h[k], c))
    return a, b, c


def sigma_y(hardening: Hardening, p):
    """Yield stress at equivalent plastic strain p (piecewise linear, its tail slope beyond, plus
    the saturation term)."""
    p0 = hardening.segments[0]
    a, b, c = _segment(hardening, lambda k: ufl.lt(p, p0[k + 1]))
    return _with_saturation(hardening, b + c * (p - a), p, 0)


def slope(hardening: Hardening, p):
    """Slope of the segment holding p (right-continuous at the table's points), plus the saturation
    term's."""
    p0 = hardening.segments[0]
    return _with_saturation(hardening, _segment(hardening, lambda k: ufl.lt(p, p0[k + 1]))[2], p, 1)


def _solve_dp(hardening: Hardening, q, pn, three_mu):
    """Root dp of q - 3 mu dp - sigma_y(p_n + dp) = 0: the first segment whose end already makes
    the residual negative holds it (as Hardening.solve_dp); with a saturation term,
    :data:`NEWTON_STEPS` Newton steps from the segment's start."""
    p0, s0, _ = hardening.segments
    a, b, c = _segment(hardening, lambda k: ufl.And(
        ufl.lt(pn, p0[k + 1]),
        ufl.lt(q - three_mu * (p0[k + 1] - pn) - _with_saturation(hardening, s0[k + 1], p0[k + 1], 0), 0.0)))
    start = ufl.max_value(pn, a)
    if not hardening.smooth:
        g = q - three_mu * (start - pn) - (b + c * (start - a))
        return start - pn + g / (three_mu + c)
    dp = start - pn
    for _ in range(NEWTON_STEPS):
        v, dv = _saturation(hardening, pn + dp)
        dp = dp + (q - three_mu * dp - (b + c * (pn + dp - a)) - v) / (three_mu + c + dv)
    return dp


def _deviator_points(sig):
    """(deviator, equivalent stress) of a stress 4-vector (xx, yy, zz, xy) or 6-vector (xx, yy, zz,
    xy, yz, xz; 3D), the shears counted twice in s:s."""
    m = (sig[0] + sig[1] + sig[2]) / 3.0
    if sig.ufl_shape == (6,):
        s = ufl.as_vector([sig[0] - m, sig[1] - m, sig[2] - m, sig[3], sig[4], sig[5]])
        ss = s[0] ** 2 + s[1] ** 2 + s[2] ** 2 + 2.0 * (s[3] ** 2 + s[4] ** 2 + s[5] ** 2)
        return s, ufl.sqrt(ufl.max_value(1.5 * ss, _TINY))
    s = ufl.as_vector([sig[0] - m, sig[1] - m, sig[2] - m, sig[3]])
    q = ufl.sqrt(ufl.max_value(1.5 * (s[0] ** 2 + s[1] ** 2 + s[2] ** 2 + 2.0 * s[3] ** 2), _TINY))
    return s, q


def _deviator_dot(n, x, b):
    """(dev x, b (n : x)) of stored vectors (4 or 6 entries; n deviatoric), as
    :func:`j2_tangent_times` applies them."""
    tr_x = (x[0] + x[1] + x[2]) / 3.0
    if x.ufl_shape == (6,):
        dev_x = ufl.as_vector([x[0] - tr_x, x[1] - tr_x, x[2] - tr_x, x[3], x[4], x[5]])
        nx = n[0] * x[0] + n[1] * x[1] + n[2] * x[2] + 2.0 * (n[3] * x[3] + n[4] * x[4] + n[5] * x[5])
        return dev_x, b * nx
    dev_x = ufl.as_vector([x[0] - tr_x, x[1] - tr_x, x[2] - tr_x, x[3]])
    return dev_x, b * (n[0] * x[0] + n[1] * x[1] + n[2] * x[2] + 2.0 * n[3] * x[3])


def j2_return(sig_tr, p_n, elastic, hardening: Hardening):
    """Radial return of J2 plasticity with isotropic hardening (plane strain, axisymmetry)."""
    s = ufl.dev(sig_tr)
    q = ufl.sqrt(ufl.max_value(1.5 * ufl.inner(s, s), _TINY))
    three_mu = 3.0 * elastic.mu
    dp = _solve_dp(hardening, q, p_n, three_mu)
    return ufl.conditional(ufl.gt(q, sigma_y(hardening, p_n)), sig_tr - three_mu * dp / q * s, sig_tr)


def j2_return_points(sig_tr, p_n, elastic, hardening: Hardening):
    """The radial return of return_maps.j2_return_points in UFL, on 4-vectors (xx, yy, zz, xy): (stress,
    plastic strain). Its derivative D = d sigma / d sigma_tr is not evaluated here: the Jacobian applies
    it from the stored state (:func:`j2_tangent_times`). Plane strain, axisymmetry and 3D (6-vectors
    xx, yy, zz, xy, yz, xz)."""
    s, q = _deviator_points(sig_tr)
    three_mu = 3.0 * elastic.mu
    dp = _solve_dp(hardening, q, p_n, three_mu)
    # one switch, 1 where the point yields: each conditional of its own would evaluate the yield
    # test again in the generated code
    y = ufl.conditional(ufl.gt(q, sigma_y(hardening, p_n)), 1.0, 0.0)
    return sig_tr - y * three_mu * dp / q * s, p_n + y * dp


def j2_tangent_times(sig, p, p_n, x, elastic, hardening: Hardening):
    """D x, D = d sigma / d sigma_tr of the radial return (as in :func:`j2_return_points`), from the
    state the return left at the point: the stress sig (4-vector), its plastic strain p and p_n of
    the last converged increment. A point yields in the increment where p > p_n; there dp = p - p_n,
    n = dev(sig) / q with q the equivalent stress of sig (the trial stress's direction: the return is
    radial), the trial's q_tr = q + 3 mu dp, and H the slope of the segment holding p (right-
    continuous, as the segment Hardening.solve_dp finds). Elsewhere D x = x (also where dp is below
    the round-off of p_n: within round-off of the yield switch, where either tangent is one of its
    sides). The Jacobian thus needs no stored D, only the stress and plastic strain that the return
    stores anyway (plane strain and axisymmetry; docs/theory.md section 4.1)."""
    s, q = _deviator_points(sig)
    three_mu = 3.0 * elastic.mu
    dp = p - p_n
    ratio = dp / (q + three_mu * dp)                    # dp / q_tr
    theta = 1.0 - three_mu * ratio
    c = 1.5 * three_mu * (1.0 / (three_mu + slope(hardening, p)) - ratio)
    n = s / q
    # D x = x + y ((theta - 1) dev x - c (n : x) n), y = 1 where the point yields: the scalars that
    # do not depend on x first, since the Jacobian's kernel applies this to each direction of x
    y = ufl.conditional(ufl.gt(p, p_n), 1.0, 0.0)
    a, b = y * (theta - 1.0), y * c
    dev_x, nWx = _deviator_dot(n, x, b)
    return x + a * dev_x - nWx * n


def j2_return_plane_stress(sig_tr, p_n, elastic, hardening: Hardening, newton_steps: int = 12):
    """Plane-stress J2 return (Simo and Taylor's scalar equation in dgamma, as materials._j2_plane_stress):
    the hardening segment in closed form, then ``newton_steps`` unrolled Newton steps on that segment
    from the same start (the function is smooth and monotone there: round-off in fewer than 8)."""
    E, nu, G = elastic.E, elastic.nu, elastic.mu
    c1, c2 = E / (3.0 * (1.0 - nu)), 2.0 * G
    a = sig_tr[0, 0] + sig_tr[1, 1]
    b = sig_tr[0, 0] - sig_tr[1, 1]
    t = sig_tr[0, 1]
    A = 0.25 * a ** 2
    B = 0.75 * b ** 2 + 3.0 * t ** 2
    q = ufl.sqrt(ufl.max_value(A + B, _TINY))
    y_n = sigma_y(hardening, p_n)
    p0, s0, h = hardening.segments
    # segment index = number of table points that the root lies beyond
    count = 0.0
    for pk, sk in zip(p0[1:], s0[1:]):
        sk = _with_saturation(hardening, sk, pk, 0)
        g = 1.5 * ufl.max_value(pk - p_n, 0.0) / sk
        seq = ufl.sqrt(A / (1.0 + c1 * g) ** 2 + B / (1.0 + c2 * g) ** 2)
        count = count + ufl.conditional(ufl.Or(ufl.le(pk, p_n), ufl.ge(seq, sk)), 1.0, 0.0)
    H, Y0 = h[-1], s0[-1] + h[-1] * (p_n - p0[-1])
    for k in reversed(range(len(p0) - 1)):
        below = ufl.lt(count, k + 0.5)
        H = ufl.conditional(below, h[k], H)
        Y0 = ufl.conditional(below, s0[k] + h[k] * (p_n - p0[k]), Y0)
    hi = (q / y_n - 1.0) / c1
    c = (c1 * A + c2 * B) / ufl.max_value(A + B, _TINY)
    den0 = c * Y0 + 2.0 / 3.0 * H * q
    g = ufl.min_value(ufl.max_value((q - Y0) / den0, 0.0), hi)
    for _ in range(newton_steps):
        f1, f2 = 1.0 / (1.0 + c1 * g), 1.0 / (1.0 + c2 * g)
        se = ufl.sqrt(A * f1 ** 2 + B * f2 ** 2)
        dse = -(c1 * A * f1 ** 3 + c2 * B * f2 ** 3) / se
        w = 1.0 - 2.0 / 3.0 * H * g
        phi, dphi = se * w - Y0, dse * w - 2.0 / 3.0 * H * se
        if hardening.smooth:
            v, dv = _saturation(hardening, p_n + 2.0 / 3.0 * g * se)
            phi, dphi = phi - v, dphi - 2.0 / 3.0 * dv * (se + g * dse)
        g = g - phi / dphi
    f1, f2 = 1.0 / (1.0 + c1 * g), 1.0 / (1.0 + c2 * g)
    xx = 0.5 * (a * f1 + b * f2)
    yy = 0.5 * (a * f1 - b * f2)
    sig = ufl.as_tensor([[xx, t * f2, 0.0], [t * f2, yy, 0.0], [0.0, 0.0, 0.0]])
    return ufl.conditional(ufl.gt(q, y_n), sig, sig_tr)


def plane_stress_thickness(sig, sig_tr, sig_rot, elastic):
    """Logarithmic thickness strain of a plane-stress increment (materials.plane_stress_thickness)."""
    E, nu = elastic.E, elastic.nu
    tr2 = lambda s: s[0, 0] + s[1, 1]         # noqa: E731
    return -nu / E * tr2(sig - sig_rot) - (1.0 - nu) / E * tr2(sig_tr - sig)

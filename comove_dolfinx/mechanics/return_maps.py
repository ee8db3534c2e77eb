"""Material laws at quadrature points: J2 return mapping and Chen Zhi-da's single-parameter law.

Storage convention
------------------
Stresses and strains are arrays of shape (N, 4): for each of N quadrature points the Cartesian components
(xx, yy, zz, xy) of the symmetric tensor. "zz" is the out-of-plane component; in axisymmetry (x = r, y = z)
it is the hoop component theta-theta. The shear is stored once, as the tensor component (eps_xy, not the
engineering strain 2 eps_xy). The double contraction of two stored tensors is therefore
a:b = a_xx b_xx + a_yy b_yy + a_zz b_zz + 2 a_xy b_xy.

Tangents D of shape (N, 4, 4) hold D[:, i, j] = d out_i / d in_j in the same convention: a perturbation of
in_xy changes the tensor components xy and yx together. In this convention D need not be a symmetric matrix.

Models: "plane_strain" and "axisymmetric" apply the three-dimensional law to the four components;
"plane_stress" keeps sigma_zz = 0 exactly, and the zz rows and columns of its tangents are zero.

Units: stresses in the units of E; strains are dimensionless; tension is positive. p is the equivalent
(von Mises) plastic strain, with sigma_eq dp = sigma : deps_p. Pure NumPy, vectorised over the points; the
material data (:class:`Elastic`, :class:`Hardening`) live in :mod:`comove_dolfinx.mechanics.material_data` and are
re-exported here.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from .material_data import (
    MODELS,
    ONE,
    PDEV,
    WEIGHT,
    Elastic,
    Hardening,
    MaterialError,
    as_points,
    check_model,
    check_plane_stress,
    ddot,
    deviator,
    von_mises,
)

__all__ = ["MODELS", "Elastic", "Hardening", "MaterialError", "PointsReturn", "chen_loading_surface", "deviator",
           "elastic_tangent", "full_tangent", "j2_return", "j2_return_points", "plane_stress_thickness", "von_mises"]


def j2_return(sig_tr: ArrayLike, p_n: ArrayLike, elastic: Elastic, hardening: Hardening,
              model: str) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Von Mises return mapping with isotropic hardening (backward Euler, docs/theory.md section 4.1-4.3).

    Parameters
    ----------
    sig_tr : array_like, (N, 4)
        Trial (elastic predictor) stress; for "plane_stress" its zz column must be 0 (predictor with C_ps).
    p_n : array_like, (N,)
        Equivalent plastic strain at the start of the increment.
    elastic, hardening
        Material data.
    model : str
        "plane_strain", "axisymmetric" (radial return on the four components) or "plane_stress"
        (Simo-Taylor return with sigma_zz = 0, generalised to the piecewise-linear table).

    Returns
    -------
    sig : (N, 4)
        Stress at the end of the increment.
    p : (N,)
        Equivalent plastic strain.
    D : (N, 4, 4)
        d sig / d sig_tr of the discrete map (identity at elastic points; zz row and column zero in plane
        stress). The tangent d sig / d eps is D times the elastic stiffness of the model.
    deps_p : (N, 4)
        Plastic strain increment (tensor components; deps_p zz = -(xx + yy)).
    """
    check_model(model)
    sig_tr = as_points(sig_tr, "sig_tr")
    if model == "plane_stress":
        check_plane_stress(sig_tr, "sig_tr")
    ret = j2_return_points(sig_tr, p_n, elastic, hardening, model)
    D = full_tangent(ret.index, ret.D, len(ret.p), model)
    deps_p = np.zeros_like(sig_tr)
    deps_p[ret.index] = ret.deps_p
    return ret.sig, ret.p, D, deps_p


def elastic_tangent(model: str) -> np.ndarray:
    """d sig / d sig_tr at a point that does not yield: the identity (zz row and column zero in plane
    stress)."""
    return np.diag([1.0, 1.0, 0.0, 1.0]) if model == "plane_stress" else np.eye(4)


def full_tangent(index: np.ndarray, D: np.ndarray, n: int, model: str) -> np.ndarray:
    """d sig / d sig_tr at all ``n`` points, (n, 4, 4), from its values ``D`` at the points ``index``
    that yield (elsewhere :func:`elastic_tangent`)."""
    out = np.tile(elastic_tangent(model), (n, 1, 1))
    out[index] = D
    return out


_ONE_ONE_3 = np.outer(ONE, ONE) / 3.0
_BROADCAST_BELOW = 1000     # yielding points: the broadcast took 33 against 140 us at 300 points,
                            # 430 against 220 us at 3000 (NumPy 1.24)


@dataclass
class PointsReturn:
    """The return map at N points, its derivative and plastic strain stored only where they yield."""

    sig: np.ndarray          # (N, 4) stress
    p: np.ndarray            # (N,) equivalent plastic strain
    index: np.ndarray        # (k,) the points that yield
    D: np.ndarray | None     # (k, 4, 4) d sig / d sig_tr there (elsewhere elastic_tangent(model)), or
                             # None if not asked for
    deps_p: np.ndarray       # (k, 4) plastic strain increment there (elsewhere 0)


def j2_return_points(sig_tr: np.ndarray, p_n: ArrayLike, elastic: Elastic, hardening: Hardening,
                     model: str, tangent: bool = True) -> PointsReturn:
    """:func:`j2_return` without its checks, with the tangent and the plastic strain increment only at
    the points that yield (the model's stress evaluation calls it at every residual evaluation: most
    points are elastic, and a full (N, 4, 4) tangent per call costs more than the return itself).
    ``tangent`` False leaves D out (None) where the model can do without it: plane strain and
    axisymmetry, whose Jacobian applies D from the returned state (return_maps_ufl.j2_tangent_times)."""
    p_n = np.broadcast_to(np.asarray(p_n, dtype=float), sig_tr.shape[:1])
    if model == "plane_stress":
        return _j2_plane_stress(sig_tr, p_n, elastic, hardening)
    s = deviator(sig_tr)
    q = np.sqrt(1.5 * ddot(s, s))
    i = np.flatnonzero(q > hardening.sigma_y(p_n))
    sig, p = sig_tr.copy(), p_n.copy()
    if i.size == 0:
        return PointsReturn(sig, p, i, np.zeros((0, 4, 4)), np.zeros((0, 4)))
    three_mu = 3.0 * elastic.mu
    q_i, pn_i = q[i], p_n[i]
    dp, h = hardening.solve_dp(q_i, pn_i, three_mu)
    n = s[i] / q_i[:, None]
    ratio = dp / q_i
    sig[i] -= (three_mu * dp)[:, None] * n
    p[i] = pn_i + dp
    if not tangent:
        return PointsReturn(sig, p, i, None, 1.5 * dp[:, None] * n)
    theta = 1.0 - three_mu * ratio
    c = 1.5 * three_mu * (1.0 / (three_mu + h) - ratio)
    # D = 1/3 (1 x 1) + theta P_dev - c n (x) W n: broadcast over few points, entry by entry over
    # many (numpy is slow on short inner axes; both give the same bits)
    cn, wn = c[:, None] * n, WEIGHT * n
    if i.size < _BROADCAST_BELOW:
        D = _ONE_ONE_3 + theta[:, None, None] * PDEV
        D -= cn[:, :, None] * wn[:, None, :]
    else:
        D = np.empty((i.size, 4, 4))
        for a in range(4):
            for b in range(4):
                D[:, a, b] = ONE[a] * ONE[b] / 3.0 + theta * PDEV[a, b] - cn[:, a] * wn[:, b]
    return PointsReturn(sig, p, i, D, 1.5 * dp[:, None] * n)


def _plane_stress_segment(A, B, pn, c1, c2, hardening):
    """Index of the hardening segment that holds the plane-stress solution (closed-form test per point).

    The root lies beyond a table point (p_k, sigma_k) with p_k > p_n exactly when the equivalent stress at
    dgamma = 1.5 (p_k - p_n) / sigma_k is >= sigma_k: both sigma_eq(dgamma) (decreasing) and
    p(dgamma) = p_n + 2/3 dgamma sigma_eq(dgamma) (increasing) are monotone.
    """
    p0 = hardening.segments[0]
    seg = np.zeros(len(pn), dtype=int)
    for pk, sk in zip(p0[1:], hardening.sigma_y(p0[1:])):
        g = 1.5 * np.maximum(pk - pn, 0.0) / sk
        seq = np.sqrt(A / (1.0 + c1 * g) ** 2 + B / (1.0 + c2 * g) ** 2)
        seg += (pk <= pn) | (seq >= sk)
    return seg


def _j2_plane_stress(sig_tr, p_n, elastic, hardening):
    """Plane-stress return in the rotated basis (sum, difference, shear) of Simo and Taylor (1986).

    With deps_p = dgamma dev(sig) and sig = sig_tr - dgamma C_ps deps_p, the sum xx + yy scales by
    f1 = 1 / (1 + c1 dgamma), c1 = E / (3 (1 - nu)), and xx - yy and xy by f2 = 1 / (1 + 2 G dgamma), so
    sigma_eq^2 = A f1^2 + B f2^2 with A = (xx + yy)^2 / 4, B = 3 (xx - yy)^2 / 4 + 3 xy^2 of the trial
    stress, and dp = 2/3 dgamma sigma_eq. The segment of the table is found in closed form, then
    sigma_eq = sigma_y(p_n + dp) is solved by a bracketed Newton iteration on that (smooth) segment
    (:func:`_plane_stress_dgamma`); a saturation term V(p) of the hardening enters as
    phi(g) = sigma_eq (1 - 2/3 H g) - Y0 - V(p), still decreasing in g, since p grows with g. The
    stress and its derivative follow from dgamma (:func:`_plane_stress_state`).
    """
    E, nu, G = elastic.E, elastic.nu, elastic.mu
    c1, c2 = E / (3.0 * (1.0 - nu)), 2.0 * G
    sig, p = sig_tr.copy(), p_n.copy()
    a_all = sig_tr[:, 0] + sig_tr[:, 1]
    b_all = sig_tr[:, 0] - sig_tr[:, 1]
    A_all = 0.25 * a_all ** 2                               # sigma_eq^2 = A f1^2 + B f2^2
    B_all = 0.75 * b_all ** 2 + 3.0 * sig_tr[:, 3] ** 2
    q = np.sqrt(A_all + B_all)
    y_n = hardening.sigma_y(p_n)
    i = np.flatnonzero(q > y_n)
    if i.size == 0:
        return PointsReturn(sig, p, i, np.zeros((0, 4, 4)), np.zeros((0, 4)))
    a, b, t, A, B, q, y_n, pn = a_all[i], b_all[i], sig_tr[i, 3], A_all[i], B_all[i], q[i], y_n[i], p_n[i]
    p0, s0, h0 = hardening.segments
    seg = _plane_stress_segment(A, B, pn, c1, c2, hardening)
    H = h0[seg]
    Y0 = s0[seg] + H * (pn - p0[seg])      # the segment's straight line evaluated at p_n
    g = _plane_stress_dgamma(A, B, q, y_n, pn, H, Y0, c1, c2, hardening)
    out, p_i, Di = _plane_stress_state(a, b, t, A, B, pn, H, g, c1, c2, hardening)
    sig[i] = out
    p[i] = p_i
    return PointsReturn(sig, p, i, Di, g[:, None] * deviator(out))


def _plane_stress_dgamma(A, B, q, y_n, pn, H, Y0, c1, c2, hardening):
    """dgamma of the yielding points: the root of phi(g) = sigma_eq(g) (1 - 2/3 H g) - Y0 (- V(p)
    with a saturation term), strictly decreasing, bracketed by [0, (q / sigma_y(p_n) - 1) / c1];
    Newton's step where it stays inside the bracket, bisection where not, each point until its step
    is below round-off (RuntimeError after 200 iterations)."""
    # phi(g) = sigma_eq(g) (1 - 2/3 H g) - Y0, strictly decreasing, root bracketed by [0, g_hi]
    lo, hi = np.zeros_like(q), (q / y_n - 1.0) / c1
    c = (c1 * A + c2 * B) / (A + B)
    den0 = c * Y0 + 2.0 / 3.0 * H * q                        # start: all modes scaled by 1 / (1 + c g)
    g = np.clip(np.where(den0 > 0.0, (q - Y0) / np.where(den0 > 0.0, den0, 1.0), 0.5 * hi), 0.0, hi)
    act = np.arange(len(q))
    for _ in range(200):
        ga, Aa, Ba, Ha = g[act], A[act], B[act], H[act]
        f1, f2 = 1.0 / (1.0 + c1 * ga), 1.0 / (1.0 + c2 * ga)
        se = np.sqrt(Aa * f1 ** 2 + Ba * f2 ** 2)
        dse = -(c1 * Aa * f1 ** 3 + c2 * Ba * f2 ** 3) / se
        phi = se * (1.0 - 2.0 / 3.0 * Ha * ga) - Y0[act]
        dphi = dse * (1.0 - 2.0 / 3.0 * Ha * ga) - 2.0 / 3.0 * Ha * se
        if hardening.smooth:
            v, dv = hardening.saturation_term(pn[act] + 2.0 / 3.0 * ga * se)
            phi = phi - v
            dphi = dphi - 2.0 / 3.0 * dv * (se + ga * dse)
        lo[act] = np.where(phi > 0.0, ga, lo[act])
        hi[act] = np.where(phi < 0.0, ga, hi[act])
        new = ga - phi / dphi
        out = ~((new > lo[act]) & (new < hi[act]))
        new = np.where(phi == 0.0, ga, np.where(out, 0.5 * (lo[act] + hi[act]), new))
        g[act] = new
        act = act[np.abs(new - ga) > 1e-13 * new + 1e-15 / c1]     # relative, or round-off of c1 g
        if act.size == 0:
            return g
    raise RuntimeError("plane-stress return mapping did not converge")


def _plane_stress_state(a, b, t, A, B, pn, H, g, c1, c2, hardening):
    """The yielding points' state at dgamma ``g``: the stress (k, 4) from the trial's sum ``a``,
    difference ``b`` and shear ``t``, the plastic strain p (k,), and d sig / d sig_tr (k, 4, 4)."""
    f1, f2 = 1.0 / (1.0 + c1 * g), 1.0 / (1.0 + c2 * g)
    se = np.sqrt(A * f1 ** 2 + B * f2 ** 2)
    dse = -(c1 * A * f1 ** 3 + c2 * B * f2 ** 3) / se
    w = 1.0 - 2.0 / 3.0 * H * g
    dphi = dse * w - 2.0 / 3.0 * H * se
    if hardening.smooth:                  # d phi / d se at fixed g, and phi', with V(p)
        dv = hardening.saturation_term(pn + 2.0 / 3.0 * g * se)[1]
        w = w - 2.0 / 3.0 * dv * g
        dphi = dphi - 2.0 / 3.0 * dv * (se + g * dse)
    out = np.zeros((len(g), 4))
    out[:, 0] = 0.5 * (a * f1 + b * f2)
    out[:, 1] = 0.5 * (a * f1 - b * f2)
    out[:, 3] = t * f2
    # D = M(g) + (d sig / d g) (x) (d g / d sig_tr), d g / d sig_tr = -(d phi / d sig_tr) / phi'
    Di = np.zeros((len(g), 4, 4))
    Di[:, 0, 0] = Di[:, 1, 1] = 0.5 * (f1 + f2)
    Di[:, 0, 1] = Di[:, 1, 0] = 0.5 * (f1 - f2)
    Di[:, 3, 3] = f2
    da, db, dt = -c1 * a * f1 ** 2, -c2 * b * f2 ** 2, -c2 * t * f2 ** 2
    dsig_dg = np.stack([0.5 * (da + db), 0.5 * (da - db), np.zeros_like(g), dt], axis=1)
    dA = np.stack([0.5 * a, 0.5 * a, np.zeros_like(g), np.zeros_like(g)], axis=1)
    dB = np.stack([1.5 * b, -1.5 * b, np.zeros_like(g), 6.0 * t], axis=1)
    dphi_dsig = (w / (2.0 * se))[:, None] * (f1[:, None] ** 2 * dA + f2[:, None] ** 2 * dB)
    Di += dsig_dg[:, :, None] * (-dphi_dsig / dphi[:, None])[:, None, :]
    return out, pn + 2.0 / 3.0 * g * se, Di


def chen_loading_surface(elastic: Elastic, hardening: Hardening) -> Hardening:
    """The loading surface sigma_eq = Y(p) of Chen Zhi-da's single-parameter law (docs/theory.md 4.4).

    On plastic loading the rate law s_dot = 2G [e_dot - beta (s:e_dot) s / (s:s)] moves the equivalent
    stress and the plastic strain (sigma_eq p_dot = s : eps_dot^p) in the ratio

        d sigma_eq / dp = 3G (1 - beta) / beta = 3G E_t / (3G - E_t),   beta = 1 - E_t / (3G),

    E_t = E H / (E + H) the uniaxial tangent of the table slope H. Holding the stress on this surface
    (the consistency condition) and taking the flow direction at the end of the increment is the implicit
    integration of the law: J2's radial return on Y. H is constant on each segment of the table, so Y is
    piecewise linear on the table's strains; it equals the table when E = 3G (nu = 0.5) and lies below it
    for nu < 0.5 (the compressibility difference of the two laws).
    """
    p0, s0, h = hardening.segments
    three_g = 3.0 * elastic.mu
    e_t = elastic.E * h / (elastic.E + h)
    h_c = three_g * e_t / (three_g - e_t)                 # > 0 where H > 0, since E_t < E < 3G
    stress = s0[0] + np.concatenate([[0.0], np.cumsum(h_c[:-1] * np.diff(p0))])
    return Hardening(tuple(p0), tuple(stress), tail_slope=float(h_c[-1]))


def plane_stress_thickness(sig: np.ndarray, sig_tr: np.ndarray, sig_rot: np.ndarray, index: np.ndarray,
                           D: np.ndarray, elastic: Elastic) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Thickness strain of a plane-stress increment and its derivatives (any law with sigma_zz = 0).

    Both laws of this module end with sig = sig_tr - C_ps deps_p on the in-plane components, with a
    deviatoric (volume-preserving) plastic strain increment; so deps_p = C_ps^-1 (sig_tr - sig) in plane
    and deps_p_zz = -(deps_p_xx + deps_p_yy) = -(1 - nu)/E tr2(sig_tr - sig), tr2 = xx + yy. Adding the
    elastic part -nu/E tr2(sig - sig_rot), the logarithmic thickness strain of the increment is

        ezz = -nu/E tr2(sig - sig_rot) - (1 - nu)/E tr2(sig_tr - sig),

    and F22 = F22_n exp(ezz). Its derivatives follow from D = d sig / d sig_tr (the return maps of this
    module depend on sig_rot only through sig_tr), given at the points ``index`` that yield (elsewhere
    the elastic ``elastic_tangent("plane_stress")``, as :class:`PointsReturn` holds it).

    Returns
    -------
    ezz : (N,)
    dezz_dtr, dezz_drot : (N, 4)
        d ezz / d sig_tr and d ezz / d sig_rot (zz entries zero).
    """
    E, nu = elastic.E, elastic.nu
    tr2 = lambda a: a[..., 0] + a[..., 1]          # noqa: E731
    ezz = -nu / E * tr2(sig - sig_rot) - (1.0 - nu) / E * tr2(sig_tr - sig)
    e = np.array([1.0, 1.0, 0.0, 0.0])
    rows = lambda M: M[:, 0, :] + M[:, 1, :]       # noqa: E731  d tr2(sig) / d input
    dtr = np.tile(-nu / E * e, (len(sig), 1))                      # rows of the elastic tangent: e
    dtr[index] = (1.0 - 2.0 * nu) / E * rows(D) - (1.0 - nu) / E * e
    drot = np.broadcast_to(nu / E * e, dtr.shape).copy()
    dtr[:, 2] = drot[:, 2] = 0.0
    return ezz, dtr, drot

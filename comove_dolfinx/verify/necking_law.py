"""The necking benchmark's bar and law (Simo 1988), and what follows from them in closed form.

The bar's dimensions, the elastic constants and the saturation hardening law (mm and GPa), the
default grid and increments of the case, the law as a piecewise-linear table for a code that takes
one (:func:`plastic_table`), and the straight bar's homogeneous response in uniaxial stress
(:func:`homogeneous`), exact for the S-R updates in equal increments. The case itself is
:mod:`comove_dolfinx.verify.necking`.
"""
from __future__ import annotations

import math

import numpy as np

# the benchmark, mm and GPa
R, LENGTH, REDUCTION = 6.413, 53.334, 0.018
E, NU = 206.9, 0.29
SIGMA0, H, DSIGMA, DELTA = 0.45, 0.12924, 0.265, 16.93
PULL = 7.0
N_R, N_Z, GRADING = 5, 40, 3.0   # the default mesh (P2 triangles on this grid)
N_INCREMENTS = 140


def yield_stress(p):
    """sigma_y(p) of the benchmark, GPa."""
    p = np.asarray(p, dtype=float)
    return SIGMA0 + H * p + DSIGMA * (1.0 - np.exp(-DELTA * p))


def plastic_table(tol: float = 1e-5, p_max: float = 3.0) -> tuple[np.ndarray, np.ndarray]:
    """The law sampled for a code that takes a piecewise-linear table: points p_k with
    (p_k+1 - p_k)^2 / 8 max|sigma_y''| <= tol on each interval (the bound of linear interpolation;
    sigma_y'' = -dsigma delta^2 exp(-delta p), largest at the interval's start), so that the table is
    within ``tol`` (GPa) of the law up to ``p_max``."""
    p = [0.0]
    while p[-1] < p_max:
        curvature = DSIGMA * DELTA ** 2 * math.exp(-DELTA * p[-1])
        p.append(min(p[-1] + math.sqrt(8.0 * tol / curvature), p_max))
    p = np.array(p)
    return p, yield_stress(p)


def uniaxial_state(eps):
    """Stress and plastic strain of monotonic uniaxial stress at the axial strain ``eps`` (the sum of
    the increments' strains): sigma = E eps while elastic, else sigma = sigma_y(p) with
    sigma / E + p = eps (Newton's iteration on p, monotone from p = 0)."""
    eps = np.asarray(eps, dtype=float)
    plastic = E * eps > SIGMA0
    p = np.zeros_like(eps)
    for _ in range(60):
        r = eps - yield_stress(p) / E - p
        p = np.where(plastic, p + r / (1.0 + (H + DSIGMA * DELTA * np.exp(-DELTA * p)) / E), 0.0)
    return np.where(plastic, yield_stress(p), E * eps), p


def homogeneous(u, radius: float = R, half_length: float = 0.5 * LENGTH, n_increments: int | None = None,
                update: str = "sr_log"):
    """Force and radius of a straight bar (no imperfection) stretched homogeneously by u on its half
    length, in uniaxial stress, as long as it stays homogeneous (until the neck forms).

    ``n_increments`` None: the limit of vanishing increments, logarithmic strains, eps_z = ln(1 + u / half_length)
    = sigma / E + p with sigma = sigma_y(p) once yielding, eps_r = -nu sigma / E - p / 2 and the force
    sigma pi r^2. A whole number: what the S-R update ``update`` gives exactly in ``n_increments`` equal
    increments of u (docs/theory.md 3.2: in coaxial stretching an increment's strain is e = r - 1 with
    "sr" and e = 2 (r - 1) / (r + 1) with "sr_log", r = lambda_k+1 / lambda_k its stretch ratio), with
    the same law; the return is radial (the stress stays uniaxial), so it is exact along the path, and
    the lateral strain of increment k is e_r = -nu dsigma_k / E - dp_k / 2, from which its radial
    stretch ratio follows by inverting that map. ``u`` then is the displacement at the increments (a
    multiple of the increment)."""
    if update not in ("sr", "sr_log"):
        raise ValueError(f"update = {update!r}: the discrete solution is written for sr and sr_log")
    u = np.asarray(u, dtype=float)
    if n_increments is None:
        sig, p = uniaxial_state(np.log1p(u / half_length))
        return sig * math.pi * (radius * np.exp(-NU * sig / E - 0.5 * p)) ** 2, radius * np.exp(-NU * sig / E - 0.5 * p)
    du = u.max() / n_increments if u.size else 0.0
    k = np.arange(n_increments + 1)
    lam = 1.0 + k * du / half_length
    r = lam[1:] / lam[:-1]
    eps = np.r_[0.0, np.cumsum(r - 1.0 if update == "sr" else 2.0 * (r - 1.0) / (r + 1.0))]
    sig, p = uniaxial_state(eps)
    e_r = -NU * np.diff(sig) / E - 0.5 * np.diff(p)
    ratio = 1.0 + e_r if update == "sr" else (1.0 + 0.5 * e_r) / (1.0 - 0.5 * e_r)
    lam_r = np.cumprod(np.r_[1.0, ratio])
    at = np.rint(u / du).astype(int) if du > 0 else np.zeros(u.shape, dtype=int)
    r_now = radius * lam_r[at]
    return sig[at] * math.pi * r_now ** 2, r_now

"""Material data and the tensor storage shared by the material laws of :mod:`comove_dolfinx.mechanics.materials`.

Stored tensors are arrays (N, 4) of the components (xx, yy, zz, xy): zz is out of plane (the hoop component
in axisymmetry) and the shear is the tensor component, so a:b = a_xx b_xx + a_yy b_yy + a_zz b_zz + 2 a_xy b_xy
(see :mod:`comove_dolfinx.mechanics.materials` for the full convention). Stresses are in the units of E, tension
positive; plastic strains are equivalent (von Mises) plastic strains. Pure NumPy, vectorised over points.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

MODELS = ("plane_strain", "axisymmetric", "plane_stress")

ONE = np.array([1.0, 1.0, 1.0, 0.0])      # the identity tensor as a 4-vector
WEIGHT = np.array([1.0, 1.0, 1.0, 2.0])   # a:b = sum(WEIGHT * a * b)
PDEV = np.eye(4) - np.outer(ONE, ONE) / 3.0   # deviatoric projector, d dev(a)_i / d a_j


class MaterialError(ValueError):
    """Invalid material data; the message names the bad value and how to fix it."""


def check_model(model: str) -> str:
    """Return ``model`` if it is one of :data:`MODELS`, else raise :class:`MaterialError`."""
    if model not in MODELS:
        raise MaterialError(f"model = {model!r} is not one of {', '.join(MODELS)}")
    return model


def as_points(a: ArrayLike, name: str) -> np.ndarray:
    """Copy ``a`` to a float array of shape (N, 4), raising ``ValueError`` for any other shape."""
    a = np.array(a, dtype=float, ndmin=2)
    if a.ndim != 2 or a.shape[1] != 4:
        raise ValueError(f"{name} has shape {a.shape}; expected (N, 4) = (xx, yy, zz, xy) per point")
    return a


def check_plane_stress(sig: np.ndarray, name: str) -> None:
    """Raise :class:`MaterialError` if the zz column of a plane-stress state is not (close to) zero."""
    scale = np.abs(sig).max(initial=0.0)
    bad = np.abs(sig[:, 2]) > 1e-10 * scale
    if np.any(bad):
        i = int(np.argmax(bad))
        raise MaterialError(f"plane_stress needs {name}[:, 2] (sigma_zz) = 0, found {sig[i, 2]!r} at point "
                            f"{i}: build the predictor with Elastic.stiffness('plane_stress')")


def ddot(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Double contraction a:b of stored tensors, shape (N,)."""
    return np.einsum("ni,ni->n", a * WEIGHT, b)


def deviator(sig: ArrayLike) -> np.ndarray:
    """Deviatoric part of stored tensors (N, 4); zz takes part in the trace."""
    sig = np.asarray(sig, dtype=float)
    mean = (sig[..., 0] + sig[..., 1] + sig[..., 2]) / 3.0
    out = sig.copy()
    for k in range(3):              # column by column: numpy is slow on short inner axes
        out[..., k] -= mean
    return out


def von_mises(sig: ArrayLike) -> np.ndarray:
    """Von Mises equivalent stress sqrt(3/2 s:s) of stored stresses (N, 4)."""
    s = deviator(sig)
    return np.sqrt(1.5 * np.sum(WEIGHT * s * s, axis=-1))


@dataclass(frozen=True)
class Elastic:
    """Isotropic linear elasticity.

    Parameters
    ----------
    E : float
        Young's modulus, > 0.
    nu : float
        Poisson's ratio, -1 < nu < 0.5.
    """

    E: float
    nu: float

    def __post_init__(self) -> None:
        for name in ("E", "nu"):
            value = getattr(self, name)
            scalar = isinstance(value, (int, float, np.integer, np.floating)) or (
                isinstance(value, np.ndarray) and value.shape == () and value.dtype.kind in "iuf")
            if isinstance(value, (bool, np.bool_)) or not scalar:
                raise MaterialError(f"{name} = {value!r}: give a finite number")
        E, nu = float(self.E), float(self.nu)
        if not np.isfinite(E) or E <= 0.0:
            raise MaterialError(f"E = {self.E!r} must be a finite number > 0 (Young's modulus)")
        if not np.isfinite(nu):
            raise MaterialError(f"nu = {self.nu!r} must be a finite number in (-1, 0.5)")
        if nu >= 0.5:
            raise MaterialError(f"nu = {self.nu!r} must be < 0.5 (incompressible is not supported; "
                                "use e.g. 0.499)")
        if nu <= -1.0:
            raise MaterialError(f"nu = {self.nu!r} must be > -1 (the bulk modulus would not be positive)")
        object.__setattr__(self, "E", E)
        object.__setattr__(self, "nu", nu)

    @property
    def mu(self) -> float:
        """Shear modulus G = E / (2 (1 + nu))."""
        return self.E / (2.0 * (1.0 + self.nu))

    @property
    def lmbda(self) -> float:
        """Lame's first parameter E nu / ((1 + nu)(1 - 2 nu))."""
        return self.E * self.nu / ((1.0 + self.nu) * (1.0 - 2.0 * self.nu))

    @property
    def kappa(self) -> float:
        """Bulk modulus E / (3 (1 - 2 nu))."""
        return self.E / (3.0 * (1.0 - 2.0 * self.nu))

    @property
    def lmbda_plane_stress(self) -> float:
        """Lame's first parameter of plane stress, 2 lmbda mu / (lmbda + 2 mu) = E nu / (1 - nu^2)."""
        return 2.0 * self.lmbda * self.mu / (self.lmbda + 2.0 * self.mu)

    def stiffness(self, model: str) -> np.ndarray:
        """Elastic stiffness (4, 4), d sigma / d eps in the storage convention.

        For "plane_stress" the zz row and column are zero and the in-plane block is the plane-stress
        stiffness C_ps; otherwise it is the 3D stiffness restricted to the four components.
        """
        if check_model(model) == "plane_stress":
            one = np.array([1.0, 1.0, 0.0, 0.0])
            return self.lmbda_plane_stress * np.outer(one, one) + 2.0 * self.mu * np.diag([1.0, 1.0, 0.0, 1.0])
        return self.lmbda * np.outer(ONE, ONE) + 2.0 * self.mu * np.eye(4)

    def compliance(self) -> np.ndarray:
        """3D compliance (4, 4), d eps / d sigma; for a plane-stress state (sigma_zz = 0) it also gives eps_zz."""
        return (1.0 + self.nu) / self.E * np.eye(4) - self.nu / self.E * np.outer(ONE, ONE)


@dataclass(frozen=True)
class Hardening:
    """Isotropic hardening: yield stress against equivalent plastic strain.

    sigma_y(p) = T(p) + dsigma (1 - exp(-delta p)): T piecewise linear through the table's points
    (its last segment continued with ``tail_slope``), plus an optional saturation (Voce) term, which
    :meth:`saturation` uses for sigma0 + H p + dsigma (1 - exp(-delta p)). The return maps solve
    the consistency equation with this curve exactly (a Newton iteration on the plastic strain
    increment where the saturation term is present) and differentiate the solution exactly.

    Parameters
    ----------
    strain : tuple of float
        Equivalent plastic strains p_k; strain[0] = 0, strictly increasing.
    stress : tuple of float
        Yield stresses sigma_k > 0 at p_k, non-decreasing (no softening).
    tail_slope : float, optional
        Slope d sigma_y / dp beyond the last point, >= 0; the default 0 keeps the curve flat there.
    dsigma, delta : float, optional
        Saturation term: the stress it adds at saturation (>= 0, in the units of the stresses) and
        its rate (>= 0, per unit plastic strain); the default 0 leaves the table alone.
    """

    strain: tuple[float, ...]
    stress: tuple[float, ...]
    tail_slope: float = 0.0
    dsigma: float = 0.0
    delta: float = 0.0

    def __post_init__(self) -> None:
        for name in ("strain", "stress"):
            values = np.ravel(np.asarray(getattr(self, name), dtype=object))
            if any(isinstance(v, (bool, np.bool_, str, bytes)) or not isinstance(v, (int, float, np.number))
                   for v in values):
                raise MaterialError(f"the hardening table's {name} = {getattr(self, name)!r}: give numbers")
        p = tuple(float(v) for v in np.atleast_1d(self.strain))
        s = tuple(float(v) for v in np.atleast_1d(self.stress))
        if len(p) != len(s):
            raise MaterialError(f"the hardening table has {len(p)} strains but {len(s)} stresses: "
                                "give one yield stress per plastic strain")
        if len(p) == 0:
            raise MaterialError("the hardening table is empty: give at least the initial yield stress at strain 0")
        if not (np.all(np.isfinite(p)) and np.all(np.isfinite(s)) and np.isfinite(self.tail_slope)):
            raise MaterialError(f"the hardening table must hold finite numbers: strain = {p}, stress = {s}")
        if p[0] != 0.0:
            raise MaterialError(f"strain[0] = {p[0]!r} must be 0: the table starts at the initial yield stress")
        for k in range(len(p)):
            if s[k] <= 0.0:
                raise MaterialError(f"stress[{k}] = {s[k]!r} must be > 0 (a yield stress)")
            if k and p[k] <= p[k - 1]:
                raise MaterialError(f"row {k}: strain[{k}] = {p[k]!r} is not greater than strain[{k - 1}] = "
                                    f"{p[k - 1]!r}; the plastic strains must increase strictly")
            if k and s[k] < s[k - 1]:
                raise MaterialError(f"row {k}: stress[{k}] = {s[k]!r} is less than stress[{k - 1}] = "
                                    f"{s[k - 1]!r}; softening is not supported: make the stresses non-decreasing")
        if self.tail_slope < 0.0:
            raise MaterialError(f"tail_slope = {self.tail_slope!r} must be >= 0 (softening is not supported)")
        for name in ("dsigma", "delta"):
            value = getattr(self, name)
            if isinstance(value, bool) or not (isinstance(value, (int, float, np.number)) and np.isfinite(value)):
                raise MaterialError(f"{name} = {value!r} must be a finite number >= 0 (the saturation term)")
            if value < 0.0:
                raise MaterialError(f"{name} = {value!r} must be >= 0: a negative saturation term softens, "
                                    "which is not supported")
            object.__setattr__(self, name, float(value))
        object.__setattr__(self, "strain", p)
        object.__setattr__(self, "stress", s)
        object.__setattr__(self, "tail_slope", float(self.tail_slope))
        # arrays for the vectorised functions; segment k starts at strain[k] and has slope _h[k]
        for name, arr in (("_p", np.array(p)), ("_s", np.array(s)),
                          ("_h", np.append(np.diff(s) / np.diff(p), float(self.tail_slope)))):
            arr.flags.writeable = False
            object.__setattr__(self, name, arr)

    @classmethod
    def linear(cls, sigma0: float, H: float) -> "Hardening":
        """Linear hardening sigma_y = sigma0 + H p without end."""
        return cls((0.0,), (sigma0,), tail_slope=H)

    @classmethod
    def perfect(cls, sigma0: float) -> "Hardening":
        """Perfect plasticity, sigma_y = sigma0."""
        return cls((0.0,), (sigma0,))

    @classmethod
    def saturation(cls, sigma0: float, H: float, dsigma: float, delta: float) -> "Hardening":
        """Linear and saturation (Voce) hardening, sigma_y = sigma0 + H p + dsigma (1 - exp(-delta p)).

        Parameters
        ----------
        sigma0 : float
            Initial yield stress, > 0.
        H : float
            Linear hardening modulus, >= 0.
        dsigma : float
            Stress added by the saturation term as p grows without end, >= 0.
        delta : float
            Saturation rate, >= 0 (the term reaches 1 - 1/e of dsigma at p = 1/delta).

        Simo (1988) uses it for the necking bar (0.45 + 0.12924 p + 0.265 (1 - exp(-16.93 p)) GPa).
        """
        for name, value in (("sigma0", sigma0), ("H", H), ("dsigma", dsigma), ("delta", delta)):
            if isinstance(value, bool) or not isinstance(value, (int, float, np.number)) \
                    or not np.isfinite(value):
                raise MaterialError(f"{name} = {value!r} must be a finite number (Hardening.saturation)")
            if value < 0.0 or (name == "sigma0" and value == 0.0):
                raise MaterialError(f"{name} = {value!r} must be {'> 0' if name == 'sigma0' else '>= 0'} "
                                    "(Hardening.saturation: no softening)")
        return cls((0.0,), (sigma0,), tail_slope=H, dsigma=dsigma, delta=delta)

    @property
    def smooth(self) -> bool:
        """True when the curve has a saturation term (the return maps then iterate)."""
        return self.dsigma > 0.0 and self.delta > 0.0

    def saturation_term(self, p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The saturation term dsigma (1 - exp(-delta p)) and its slope at p (zeros without one)."""
        if not self.smooth:
            return np.zeros_like(p), np.zeros_like(p)
        e = np.exp(-self.delta * p)
        return self.dsigma * (1.0 - e), self.dsigma * self.delta * e

    @property
    def segments(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Start strains, start stresses and slopes of the segments (the last one runs to infinity)."""
        return self._p, self._s, self._h

    def sigma_y(self, p: ArrayLike) -> np.ndarray:
        """Yield stress at equivalent plastic strain p (vectorised)."""
        p = np.asarray(p, dtype=float)
        out = np.interp(p, self._p, self._s) + self.tail_slope * np.maximum(p - self._p[-1], 0.0)
        return out + self.saturation_term(p)[0] if self.smooth else out

    def slope(self, p: ArrayLike) -> np.ndarray:
        """Slope d sigma_y / dp at p: the table's segment holding p (right-continuous at the points)
        plus the saturation term's slope (vectorised)."""
        p = np.asarray(p, dtype=float)
        k = np.searchsorted(self._p, p, side="right") - 1
        out = self._h[np.clip(k, 0, len(self._h) - 1)]
        return out + self.saturation_term(p)[1] if self.smooth else out

    def solve_dp(self, seq_tr: ArrayLike, p_n: ArrayLike, three_mu: float) -> tuple[np.ndarray, np.ndarray]:
        """Exact root dp of seq_tr - three_mu dp - sigma_y(p_n + dp) = 0 (docs/theory.md section 4.2).

        The residual is strictly decreasing in dp, so the root lies in the segment after the last table
        point at which the residual is still >= 0. A root exactly on a table point belongs to the
        segment that starts there. On the segment the residual is linear (solved at once) or, with a
        saturation term, convex: Newton's iteration from the segment's start then rises monotonically
        to the root, and runs until its step is below round-off.

        Parameters
        ----------
        seq_tr : array_like
            Trial equivalent stresses; only seq_tr > sigma_y(p_n) is meaningful (else dp <= 0 comes back).
        p_n : array_like
            Equivalent plastic strains at the start of the increment.
        three_mu : float
            Three times the shear modulus.

        Returns
        -------
        dp, H_active : ndarray
            The increment and the slope d sigma_y / dp at p_n + dp (of the segment holding it, plus
            the saturation term's).
        """
        seq, pn = np.broadcast_arrays(np.asarray(seq_tr, dtype=float), np.asarray(p_n, dtype=float))
        # the segment holding p_n, then one more for every later table point at which the residual is
        # still >= 0 (it decreases, so those points come first): one comparison of (points, table)
        k = np.maximum(np.searchsorted(self._p, pn, side="right") - 1, 0)
        if len(self._p) > 1:
            later = self._p[None, 1:] > pn[..., None]
            ahead = seq[..., None] - three_mu * (self._p[None, 1:] - pn[..., None]) - self._s[None, 1:]
            if self.smooth:
                ahead = ahead - self.saturation_term(self._p[1:])[0]
            k = k + np.count_nonzero(later & (ahead >= 0.0), axis=-1)
        p0, h_act = self._p[k], self._h[k]
        start = np.maximum(p0, pn)
        g = seq - three_mu * (start - pn) - (self._s[k] + h_act * (start - p0))
        if not self.smooth:
            return start - pn + g / (three_mu + h_act), h_act
        dp = start - pn
        for _ in range(self.NEWTON_MAX):
            v, dv = self.saturation_term(pn + dp)
            r = seq - three_mu * dp - (self._s[k] + h_act * (pn + dp - p0)) - v
            step = r / (three_mu + h_act + dv)
            dp = dp + step
            if np.all(np.abs(step) <= 1e-14 * (np.abs(dp) + seq / three_mu)):   # round-off of r
                break
        else:
            raise RuntimeError("the saturation law's return map did not converge (non-finite stress?)")
        return dp, h_act + self.saturation_term(pn + dp)[1]

    #: the largest number of Newton steps of :meth:`solve_dp` with a saturation term (monotone
    #: convergence, quadratic near the root: round-off in 3 steps for the necking bar's law)
    NEWTON_MAX = 60

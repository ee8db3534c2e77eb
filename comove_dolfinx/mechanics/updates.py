"""Stress updates by name, written in UFL as functions of the current displacement.

Every update returns the Cauchy stress at the end of the increment n -> n+1 as a UFL expression of
the displacement u (the "trial" stress, before any plastic correction), given the stored state of
increment n. The model evaluates it at the quadrature points, applies the material's return map if
there is one, and differentiates it with UFL for an exact Jacobian.

Names (docs/theory.md section 3)::

    sr_log        (default) the S-R update with the increment's strain measured logarithmically:
                  the same split and rotation as sr, C:dE with dE = 2 (I - (I + dS/2)^-1)
                  = ln(I + dS) + O(dS^3) in place of C:dS; the same limit as sr (the Jaumann rate),
                  reached at second order in coaxial stretching instead of first.
    sr            incremental S-R update (Chen's, as the paper writes it): dH = F F_n^-1 - I,
                  Chen's split dH -> (dS, dR), sigma = dR sigma_n dR^T + C:dS. Objective for rigid
                  increments; converges to the Jaumann rate as the increments shrink.
    hughes_winget mid-step dH = (F - F_n) F_mid^-1, dR = (I - dW/2)^-1 (I + dW/2),
                  sigma = dR sigma_n dR^T + C:sym(dH) (Jaumann integrator).
    polar         Green-Naghdi: the unrotated stress s^ = R^T sigma R (polar R of F) is stored and
                  advanced by C:(R_mid^T sym(dH) R_mid); sigma = R s^ R^T.
    svk           total-Lagrangian St Venant-Kirchhoff: S = lambda tr(E) I + 2 mu E, sigma = F S F^T / J.
    neo_hooke     total-Lagrangian compressible neo-Hookean: sigma = (mu (b - I) + lambda ln J I) / J.
    small_strain  linear kinematics: eps = sym Grad3 u (the hoop strain u_r / r in axisymmetry),
                  sigma = sigma_n + C:(eps - eps_n), nothing rotated; equilibrium, loads and contact
                  tractions on the reference configuration (its F is the identity, and the model
                  leaves out the geometric stiffness: geometric False).

Plane stress: the hypoelastic updates use the reduced Lame constant on the in-plane increment, so
sigma_zz = 0 identically; their thickness stretch is the exact integral of the elastic rate law,
d_zz = -lambda/(lambda + 2 mu) tr(d_plane)  =>  F_zz = J_plane^(-lambda/(lambda + 2 mu)).
The hyperelastic laws solve S_zz = 0 for F_zz (in closed form for St Venant-Kirchhoff, by a few unrolled
Newton steps, converged to round-off, for neo-Hookean).

3D (the model "solid"): every update takes the full 3x3 gradient; the S-R updates split the
increment with the general form of the decomposition (a rotation about an axis by an angle,
kinematics.sr_decomposition) and differentiate it in closed form
(kinematics.sr_decomposition_direction); the polar update's rotation comes from an unrolled Newton
iteration (kinematics.polar_rotation_3d). The 2D models keep the one-angle specialisations.

The elastic constants come as any object with ``mu``, ``lmbda`` and ``lmbda_plane_stress``: numbers
(material_data.Elastic) or UFL values (the model's ElasticConstants, so that the compiled code does not
depend on them).
"""
from __future__ import annotations

from dataclasses import dataclass

import ufl

from .kinematics import (
    PLANE_STRESS,
    Kinematics,
    embed,
    in_plane_angle,
    increment_gradient,
    polar_rotation_2d,
    polar_rotation_3d,
    sr_decomposition,
    sr_decomposition_direction,
    sr_decomposition_in_plane,
    to_tensor,
)


@dataclass
class UpdateExpr:
    """UFL expressions produced by an update for the increment n -> n+1."""

    sigma: object                 # 3x3 Cauchy stress (elastic trial stress for plastic materials)
    sigma_rot: object = None      # the old stress carried to n+1 by the update's rotation
    state_new: object = None      # 4-vector to store as the update's own state, if not sigma itself
    F22: object = None            # thickness stretch in plane stress, when the update fixes it


def hooke(dE, elastic, model: str):
    """Isotropic elastic law C:dE on a 3x3 tensor; plane stress uses the reduced lambda, zz -> 0."""
    if model == PLANE_STRESS:
        e2 = ufl.as_tensor([[dE[0, 0], dE[0, 1]], [dE[1, 0], dE[1, 1]]])
        s2 = elastic.lmbda_plane_stress * ufl.tr(e2) * ufl.Identity(2) + 2.0 * elastic.mu * e2
        return embed(s2, 0)
    return elastic.lmbda * ufl.tr(dE) * ufl.Identity(3) + 2.0 * elastic.mu * dE


class StressUpdate:
    """Base class: ``build`` returns the UpdateExpr of an increment."""

    name = ""
    incremental = True            # uses the stored stress of increment n
    rotates = True                # has a rotated old stress (can carry plasticity)
    geometric = True              # equilibrium on the current configuration (P = sigma cof F)

    def __init__(self, kin: Kinematics, elastic):
        self.kin = kin
        self.elastic = elastic
        self.volume = None        # F-bar: the model's volume.VolumeAverage (set before any build)

    def F(self, u):
        """Deformation gradient seen by the update (in plane stress the in-plane block suffices);
        the loads and contact outputs take the current configuration's normals and lengths from it."""
        return self.kin.F3(u, F22=1.0) if self.kin.model == PLANE_STRESS else self.kin.F3(u)

    def stress_F(self, u):
        """The deformation gradient the stress sees: :meth:`F`, or with F-bar (``volume``) its
        cell-averaged version (mechanics/volume.py)."""
        F = self.F(u)
        return F if self.volume is None else self.volume.modified_F(F, u)

    def dilatation(self, u):
        """The volume change that F-bar averages: det F."""
        return ufl.det(self.F(u))

    def thickness_stretch(self, u):
        """Plane stress: exact thickness stretch of the hypoelastic law, J_plane^(-l/(l+2m))."""
        if self.kin.model != PLANE_STRESS:
            return None
        e = self.elastic
        J2 = ufl.det(ufl.Identity(2) + ufl.grad(u))
        return J2 ** (-e.lmbda / (e.lmbda + 2.0 * e.mu))

    def build(self, u, u_n, state_n) -> UpdateExpr:  # pragma: no cover - interface
        raise NotImplementedError

    def directional(self, u, u_n, state_n, du, up: UpdateExpr, wrt=None) -> tuple:
        """(d sigma, d sigma_rot): the derivatives of ``up``'s trial stress and rotated old stress
        (``build``'s, at u) in the direction du, 3x3 and linear in du, for the Jacobian's material
        part (docs/theory.md section 5.4); d sigma_rot is None if the update has no rotated stress.
        ``wrt``: the coefficient du is a direction of (u by default; with F-bar also the mean
        dilatation theta). UFL's derivative here; an update may give them in closed form."""
        wrt = u if wrt is None else wrt
        dsig = ufl.derivative(up.sigma, wrt, du)
        drot = ufl.derivative(up.sigma_rot, wrt, du) if up.sigma_rot is not None else None
        return dsig, drot


class SRUpdate(StressUpdate):
    """Incremental S-R update (docs/theory.md section 3.2), as Chen's papers write it: the strain
    of the increment is the symmetric part dS of its split."""

    name = "sr"

    def strain(self, dS):
        """The increment's strain from the split's dS (3x3, block diagonal): dS itself."""
        return dS

    def strain_direction(self, dS, d_dS):
        """The derivative of :meth:`strain` at dS in the direction d_dS."""
        return d_dS

    def build(self, u, u_n, state_n):
        dH = increment_gradient(self.stress_F(u), self.stress_F(u_n))
        if self.kin.solid:                             # a rotation about an axis by an angle
            dS, dR, _ = sr_decomposition(dH)
        else:                                          # the 2D models' rotation: one angle
            dS, dR, _ = sr_decomposition_in_plane(dH)
        sig_rot = dR * to_tensor(state_n) * dR.T
        sig = sig_rot + hooke(self.strain(dS), self.elastic, self.kin.model)
        return UpdateExpr(sig, sig_rot, F22=self.thickness_stretch(u))

    def _directional_3d(self, u, u_n, state_n, du, up, wrt):
        """:meth:`directional` in 3D: the general split's closed-form derivative
        (kinematics.sr_decomposition_direction), d sigma_rot = dR s_n R^T + R s_n dR^T."""
        F, F_n = self.stress_F(u), self.stress_F(u_n)
        H = increment_gradient(F, F_n)
        G = ufl.derivative(F, wrt, du) * ufl.inv(F_n)
        S, R, _ = sr_decomposition(H)
        dS, dR = sr_decomposition_direction(H, G)
        s_n = to_tensor(state_n)
        a = dR * s_n * R.T
        drot = a + a.T
        return drot + hooke(self.strain_direction(S, dS), self.elastic, self.kin.model), drot

    def directional(self, u, u_n, state_n, du, up, wrt=None):
        """In closed form (docs/theory.md section 3.2): with G = d(dH) = dF F_n^-1, the angle's
        d theta = (G10 - G01) / (2 cos theta), d S = sym G + sin(theta) d theta diag(1, 1, 0) and
        d sigma_rot = d theta (Z sigma_rot - sigma_rot Z), Z the in-plane quarter turn."""
        wrt = u if wrt is None else wrt
        if self.kin.solid:
            return self._directional_3d(u, u_n, state_n, du, up, wrt)
        F, F_n = self.stress_F(u), self.stress_F(u_n)
        H = increment_gradient(F, F_n)
        G = ufl.derivative(F, wrt, du) * ufl.inv(F_n)
        w, c = in_plane_angle(H)
        dtheta = 0.5 * (G[1, 0] - G[0, 1]) / c
        shear = 0.5 * (G[0, 1] + G[1, 0])
        dS = ufl.as_tensor([[G[0, 0] + w * dtheta, shear, 0], [shear, G[1, 1] + w * dtheta, 0],
                            [0, 0, G[2, 2]]])
        s = up.sigma_rot
        a, b = s[0, 0] - s[1, 1], 2.0 * s[0, 1]
        drot = dtheta * ufl.as_tensor([[-b, a, 0], [a, b, 0], [0, 0, 0]])
        dS = self.strain_direction(sr_decomposition_in_plane(H)[0], dS)
        return drot + hooke(dS, self.elastic, self.kin.model), drot


def _half_step_inverse(dS):
    """(I + dS/2)^-1 of a 3x3 tensor that is block diagonal (an in-plane 2x2 block and zz), in
    closed form."""
    m00, m01, m11 = 1.0 + 0.5 * dS[0, 0], 0.5 * dS[0, 1], 1.0 + 0.5 * dS[1, 1]
    det = m00 * m11 - m01 * m01
    return ufl.as_tensor([[m11 / det, -m01 / det, 0], [-m01 / det, m00 / det, 0],
                          [0, 0, 1.0 / (1.0 + 0.5 * dS[2, 2])]])


class SRLogUpdate(SRUpdate):
    """The S-R update with the increment's strain measured logarithmically (docs/theory.md section
    3.2, "Logarithmic increments"): dE = 2 (I - M^-1), M = I + dS/2, which is ln(I + dS) to within
    dS^3 / 12 (the (1, 1) Pade approximant of the logarithm, applied to the symmetric dS: dE is
    symmetric and coaxial with dS), and dE = 0 for a rigid increment. Its derivative in a direction
    d_dS is M^-1 d_dS M^-1."""

    name = "sr_log"

    def _inverse(self, dS):
        """(I + dS/2)^-1: in closed form for the 2D models' block-diagonal dS, UFL's 3x3 inverse
        in 3D."""
        if self.kin.solid:
            return ufl.inv(ufl.Identity(3) + 0.5 * dS)
        return _half_step_inverse(dS)

    def strain(self, dS):
        return 2.0 * (ufl.Identity(3) - self._inverse(dS))

    def strain_direction(self, dS, d_dS):
        Minv = self._inverse(dS)
        return Minv * d_dS * Minv


def _mid_step(F, F_n):
    """Gradient of the increment with respect to the mid-step configuration."""
    F_mid = 0.5 * (F + F_n)
    return (F - F_n) * ufl.inv(F_mid), F_mid


class HughesWingetUpdate(StressUpdate):
    """Hughes-Winget (1980) incrementally objective Jaumann integrator."""

    name = "hughes_winget"

    def build(self, u, u_n, state_n):
        dH, _ = _mid_step(self.stress_F(u), self.stress_F(u_n))
        dW = ufl.skew(dH)
        Id = ufl.Identity(3)
        dR = ufl.inv(Id - 0.5 * dW) * (Id + 0.5 * dW)
        sig_rot = dR * to_tensor(state_n) * dR.T
        sig = sig_rot + hooke(ufl.sym(dH), self.elastic, self.kin.model)
        return UpdateExpr(sig, sig_rot, F22=self.thickness_stretch(u))


class PolarUpdate(StressUpdate):
    """Green-Naghdi rate through the polar rotation (Flanagan & Taylor 1987); stores s^ = R^T sigma R."""

    name = "polar"
    rotates = False

    def build(self, u, u_n, state_n):
        F, F_n = self.stress_F(u), self.stress_F(u_n)
        dH, F_mid = _mid_step(F, F_n)
        polar = polar_rotation_3d if self.kin.solid else polar_rotation_2d
        R_mid = polar(F_mid)
        de_hat = R_mid.T * ufl.sym(dH) * R_mid
        s_hat = to_tensor(state_n) + hooke(de_hat, self.elastic, self.kin.model)
        R = polar(F)
        return UpdateExpr(R * s_hat * R.T, state_new=self.kin.vec(s_hat), F22=self.thickness_stretch(u))


class SVKUpdate(StressUpdate):
    """Total-Lagrangian St Venant-Kirchhoff hyperelasticity."""

    name = "svk"
    incremental = False
    rotates = False

    def build(self, u, u_n, state_n):
        e = self.elastic
        F22 = None
        if self.kin.model == PLANE_STRESS:
            F2 = ufl.Identity(2) + ufl.grad(u)
            E2 = 0.5 * (F2.T * F2 - ufl.Identity(2))
            F22 = ufl.sqrt(1.0 - 2.0 * e.lmbda / (e.lmbda + 2.0 * e.mu) * ufl.tr(E2))
            F = embed(F2, F22)
        else:
            F = self.stress_F(u)
        E = 0.5 * (F.T * F - ufl.Identity(3))
        S = e.lmbda * ufl.tr(E) * ufl.Identity(3) + 2.0 * e.mu * E
        return UpdateExpr(F * S * F.T / ufl.det(F), F22=F22)


class NeoHookeUpdate(StressUpdate):
    """Total-Lagrangian compressible neo-Hookean: psi = mu/2 (I1 - 3) - mu ln J + lambda/2 (ln J)^2."""

    name = "neo_hooke"
    incremental = False
    rotates = False
    newton_steps = 4

    def build(self, u, u_n, state_n):
        e = self.elastic
        F22 = None
        if self.kin.model == PLANE_STRESS:
            # sigma_zz = 0: mu (F22^2 - 1) + lambda ln(J2 F22) = 0, solved for z = ln F22 from the
            # linearised guess; Newton converges quadratically (4 steps: round-off for |z| < 0.3).
            J2 = ufl.det(ufl.Identity(2) + ufl.grad(u))
            lnJ2 = ufl.ln(J2)
            z = -e.lmbda / (e.lmbda + 2.0 * e.mu) * lnJ2
            for _ in range(self.newton_steps):
                ez = ufl.exp(2.0 * z)
                z = z - (e.mu * (ez - 1.0) + e.lmbda * (lnJ2 + z)) / (2.0 * e.mu * ez + e.lmbda)
            F22 = ufl.exp(z)
            F = embed(ufl.Identity(2) + ufl.grad(u), F22)
        else:
            F = self.stress_F(u)
        J = ufl.det(F)
        b = F * F.T
        sig = (e.mu * (b - ufl.Identity(3)) + e.lmbda * ufl.ln(J) * ufl.Identity(3)) / J
        return UpdateExpr(sig, F22=F22)


class SmallStrainUpdate(StressUpdate):
    """Linear kinematics (docs/theory.md section 3.5): the strain eps = sym Grad3 u, the trial stress
    sigma_n + C:(eps(u) - eps(u_n)) with the old stress not rotated (sigma_rot = sigma_n), so that an
    elastic body has sigma = C:eps and a plastic one the small-strain return map. The geometry does
    not move: ``F`` is the identity, which the model reads as equilibrium on the reference
    configuration (``geometric`` False: P = sigma, no geometric stiffness), the follower pressure
    as a dead one on the reference normal, and the contact outputs as reference lengths. In plane
    stress the thickness strain, -lambda/(lambda + 2 mu) tr eps (elastic) or the return map's sum of
    increments (plastic), does not enter equilibrium."""

    name = "small_strain"
    geometric = False

    def F(self, u):
        return ufl.Identity(3)

    def strain(self, u):
        """eps = sym Grad3 u (3x3; zz: u_r / r in axisymmetry, 0 in the plane models)."""
        return ufl.sym(self.kin.grad3(u))

    def stress_strain(self, u):
        """The strain the stress sees: eps, or with B-bar (``volume``) its cell-averaged version."""
        eps = self.strain(u)
        return eps if self.volume is None else self.volume.modified_strain(eps, u)

    def dilatation(self, u):
        """The volume change that B-bar averages: tr eps."""
        return ufl.tr(self.strain(u))

    def build(self, u, u_n, state_n):
        sig_n = to_tensor(state_n)
        sig = sig_n + hooke(self.stress_strain(u) - self.stress_strain(u_n), self.elastic, self.kin.model)
        return UpdateExpr(sig, sig_n)

    def directional(self, u, u_n, state_n, du, up, wrt=None):
        """d sigma_tr = C:eps(du) (with B-bar: C:d eps_bar); the old stress does not move
        (d sigma_rot = 0)."""
        if self.volume is None:
            return hooke(self.strain(du), self.elastic, self.kin.model), ufl.zero(3, 3)
        d_eps = ufl.derivative(self.stress_strain(u), u if wrt is None else wrt, du)
        return hooke(d_eps, self.elastic, self.kin.model), ufl.zero(3, 3)


UPDATES = {cls.name: cls for cls in (SRLogUpdate, SRUpdate, HughesWingetUpdate, PolarUpdate, SVKUpdate,
                                     NeoHookeUpdate, SmallStrainUpdate)}


def make_update(name: str, kin: Kinematics, elastic) -> StressUpdate:
    """The update called ``name`` (ValueError listing the known names otherwise)."""
    try:
        return UPDATES[name](kin, elastic)
    except KeyError:
        raise ValueError(f"unknown stress update {name!r}: choose one of "
                         f"{', '.join(UPDATES)}") from None


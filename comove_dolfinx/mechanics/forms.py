"""The model's residual and exact Jacobian, as UFL and compiled forms.

Equilibrium is written on the reference mesh (the co-moving coordinates) with the nominal stress
P = J sigma F^-T = sigma cof F (docs/theory.md sections 1 and 5; kinematics.cofactor, a polynomial in F)::

    R(u; v) = int P : Grad3 v  w dX  + (the items' terms: loads, contact) = 0,

w = 2 pi r (axisymmetry) or the thickness b. The Jacobian is exact: the geometric part sigma d(cof F)
at fixed sigma, the material part d sigma cof F from the update's derivative of the trial stress (in
closed form for the S-R update, UFL's derivative for the others: StressUpdate.directional), mapped
by the return map's derivative D = d sigma / d sigma_trial (identity for elastic materials;
applied from the stored stress and plastic strain in plane strain and axisymmetry, stored by each
evaluation in plane stress), and in plane-stress plasticity the part of the thickness stretch,
dF22 = F22 (G_tr . d sigma_tr + G_rot . d sigma_rot). Under linear kinematics (the update
``small_strain``, whose ``geometric`` is False) P = sigma on the reference configuration and the
Jacobian has no geometric part (docs/theory.md section 3.5).

The items' terms come from their ``attach`` (mechanics/items.py); Nitsche's contact terms ask for
the stress on facets through :func:`facet_traction`.
"""
from __future__ import annotations

import numpy as np
import ufl
from dolfinx import fem
from petsc4py import PETSc
from ufl.algorithms import expand_derivatives

from .. import compat
from . import return_maps_ufl as rm_ufl
from .kinematics import PLANE_STRESS, cofactor, cofactor3, to_tensor
from .state import FacetBase


class Forms:
    """The residual and Jacobian of a model (mechanics/model.py) and its items, built and compiled
    once.

    Attributes
    ----------
    residual_ufl, residual_form, jacobian_form
        The residual R (UFL and compiled; the UFL's signature names the compiled code) and its
        Jacobian (compiled).
    F
        The deformation gradient (3 x 3) of the stress (the update's F under linear kinematics).
    update_terms
        The stress update's UFL of the increment (``update.build``): the trial stress and what
        comes with it, which the stress evaluation (evaluation.py) evaluates.
    table
        The plastic law's loading surface as Constants (:func:`surface_table`), or None.
    """

    def __init__(self, model, jit_options: dict | None = None):
        m, st = model, model.state
        self._jit = jit_options
        self.update_terms = m.update.build(m.u, m.u_n, st.sigma_n)
        self.F, cof, P = self._nominal_stress(m)
        internal = ufl.inner(P, m.kin.grad3(m.v)) * m.kin.weight() * m.rule.dx
        R, self._terms = self._attach_items(m, internal)
        self._internal, self._internal_form, self._terms_form = internal, None, None
        self.table = surface_table(m.mesh, m.plastic.surface) if m.plastic is not None else None
        jacobian = self._jacobian(m, cof, internal)
        self.residual_ufl = R
        self.residual_form = compat.form(R, jit_options)
        self.jacobian_form = compat.form(jacobian, jit_options)

    def _nominal_stress(self, m) -> tuple:
        """(F, cof F, P): the nominal stress P = sigma cof F of the stored stress (P = sigma and no
        cofactor under linear kinematics)."""
        st = m.state
        if not m.update.geometric:             # linear kinematics: P = sigma on the reference
            return m.update.F(m.u), None, to_tensor(st.sigma)
        F22 = st.F22 if st.F22 is not None else self.update_terms.F22
        F = m.kin.F3(m.u, F22) if m.kin.model == PLANE_STRESS else m.kin.F3(m.u)
        cof = cofactor3(F) if m.kin.solid else cofactor(F)         # J F^-T
        return F, cof, to_tensor(st.sigma) * cof

    @staticmethod
    def _attach_items(m, internal) -> tuple:
        """(the residual, the items' terms alone or None): every item attached to the model's
        context, its term added."""
        ctx = m.context()
        R, terms = internal, None
        for item in m.items:
            term = item.attach(ctx)
            if term is not None:
                R = R + term
                terms = term if terms is None else terms + term
        return R, terms

    def _material(self, m, direction, wrt=None) -> tuple:
        """(d sigma, d sigma_tr as a vector, d sigma_rot as a vector or None): the stress's
        derivative D d sigma_tr in ``direction`` of ``wrt`` (u by default; with F-bar the mean
        dilatation theta too)."""
        st, up = m.state, self.update_terms
        dsig_tr, dsig_rot = m.update.directional(m.u, m.u_n, st.sigma_n, direction, up, wrt)
        dsig_tr = m.kin.vec(dsig_tr)
        dsig = to_tensor(dsig_tr)
        if m.plastic is not None:
            dsig_rot = m.kin.vec(dsig_rot)
            Dx = m.plastic.tangent_times(st.sigma, st.p, st.p_n, dsig_tr, m.kin.model, m.constants,
                                         self.table)
            if Dx is None:                     # D stored by the evaluations
                st.store_tangent()
                Dx = ufl.dot(st.D, dsig_tr)
            dsig = to_tensor(Dx)
        return dsig, dsig_tr, dsig_rot

    def _volume_coupling(self, m, cof) -> None:
        """F-bar: K_u_theta, the residual's derivative in the mean dilatation (the material part:
        P = sigma(F_bar) cof F depends on theta through sigma only), and B, compiled into the
        model's VolumeAverage."""
        dtheta = m.volume.trial()
        dsig = self._material(m, dtheta, m.volume.theta)[0]
        P = dsig * cof if m.update.geometric else dsig
        m.volume.coupling_forms(ufl.inner(P, m.kin.grad3(m.v)) * m.kin.weight() * m.rule.dx, self._jit)

    def _jacobian(self, m, cof, internal):
        """The exact Jacobian: the geometric part (sigma held), the material part d sigma = D
        d sigma_tr, the items' terms (UFL's derivative) and, in plane-stress plasticity, the
        thickness stretch's part (with F-bar at fixed mean dilatation: the model adds its part)."""
        u, du, st = m.u, m.u_trial, m.state
        dsig, dsig_tr, dsig_rot = self._material(m, du)
        if m.volume is not None:
            self._volume_coupling(m, cof)
        w, grad_v, dx = m.kin.weight(), m.kin.grad3(m.v), m.rule.dx
        geometric = m.update.geometric
        if geometric:                          # sigma d(cof F): the derivative of a polynomial in F
            dcof = ufl.derivative(cof, u, du)
            J = ufl.inner(to_tensor(st.sigma) * dcof + dsig * cof, grad_v) * w * dx
        else:
            J = ufl.inner(dsig, grad_v) * w * dx
        if self._terms is not None:
            J = J + ufl.derivative(self._terms, u, du)
        if st.F22 is not None and geometric:
            # the direction of a derivative must be free of unevaluated derivatives
            dF22 = expand_derivatives(st.F22 * (ufl.dot(st.G_tr, dsig_tr) + ufl.dot(st.G_rot, dsig_rot)))
            J = J + ufl.derivative(internal, st.F22, dF22)
        return J

    @property
    def internal_force_form(self):
        """The internal force vector F_int = int P : Grad v (without the items' terms), compiled on
        first use: its norm is the force scale of the "force" convergence test."""
        if self._internal_form is None:
            self._internal_form = compat.form(self._internal, self._jit)
        return self._internal_form

    @property
    def items_form(self):
        """The items' terms of the residual alone (contact, pressure, ...: R = F_int + these, and
        the nodal loads), compiled on first use; None when no item has a term. Assembled next to
        :attr:`internal_force_form` it gives the residual and F_int from one pass over the cells."""
        if self._terms_form is None and self._terms is not None:
            self._terms_form = compat.form(self._terms, self._jit)
        return self._terms_form


def surface_table(mesh, surface) -> rm_ufl.Table:
    """The plastic law's loading ``surface`` (its hardening table) as Constants: models that differ
    in the table's values only share the compiled code."""
    p0, s0, h = surface.segments
    c = fem.Constant(mesh, np.stack([p0, s0, h]).astype(PETSc.ScalarType))
    n = len(p0)
    saturation = {}
    if surface.smooth:                    # its saturation term, dsigma and delta
        v = fem.Constant(mesh, np.array([surface.dsigma, surface.delta], dtype=PETSc.ScalarType))
        saturation = {"dsigma": v[0], "delta": v[1]}
    return rm_ufl.Table(*([c[i, k] for k in range(n)] for i in range(3)), **saturation)


def facet_traction(model, N, u=None, base: FacetBase | None = None):
    """In-plane components (in 3D all three) of P N on facets, P = J sigma F^-T at displacement u (default the
    model's current one), for Nitsche terms: the constitutive update evaluated at the facet's points
    as a UFL function of u, from the converged state of the last increment (cell-wise DG fits) or
    from a captured ``base`` (the state a lag state u_lag was solved from) and, for
    elastic-plastic bodies, the material's law in UFL. Everything that varies within an
    increment is a function of u, so the term's Jacobian is exact, and the traction at a lag
    state depends on u_lag and converged state only (docs/theory.md section 6.3)."""
    m = model
    u = m.u if u is None else u
    src, u_n = (m.state, m.u_n) if base is None else (base, base.u_n)
    up = m.update.build(u, u_n, src.facet("sigma_n"))
    sig, F22 = up.sigma, up.F22
    if m.plastic is not None:
        p_n = ufl.max_value(src.facet("p_n"), 0.0)           # the fit may dip below 0
        sig, ezz = m.plastic.facet(up.sigma_rot, up.sigma, p_n, m.kin.model, m.constants)
        if ezz is not None:
            F22 = src.facet("F22_n") * ufl.exp(ezz)
    N3 = N if m.kin.solid else ufl.as_vector([N[0], N[1], 0.0])
    if not m.update.geometric:          # linear kinematics: sigma N on the reference facet
        PN = sig * N3
    else:
        F = m.kin.F3(u, F22) if m.kin.model == PLANE_STRESS else m.kin.F3(u)
        PN = sig * (cofactor3(F) if m.kin.solid else cofactor(F)) * N3
    return PN if m.kin.solid else ufl.as_vector([PN[0], PN[1]])

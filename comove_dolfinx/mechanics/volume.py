"""F-bar: the stress computed from a deformation whose volume change is averaged over each cell.

Plastic flow keeps the volume. An element whose displacement field cannot deform at constant volume
at every quadrature point locks in a plastic zone (docs/verification.md, the flat punch): the
low-order quadrilaterals and hexahedra (Q1) among them. The F-bar method [de Souza Neto et al. 1996]
relaxes the constraint to one per cell: the stress update sees, in place of F,

    F_bar = (theta / J)^(1/d) F        (d = 3; d = 2 and F_bar_zz = F_zz = 1 in plane strain),

with J = det F and theta its mean over the cell, theta = int_K J w dX / int_K w dX (w the model's
volume weight, 2 pi r in axisymmetry): F_bar has the cell's mean volume change and F's isochoric
part. Equilibrium keeps the true F (P = sigma(F_bar) cof F). Under linear kinematics the same
idea is B-bar [Hughes 1980]: eps_bar = eps + (theta - tr eps) / d I_d, theta the mean of tr eps.

theta is the L2 projection of J onto the cell-wise constants (DG0), recomputed from the iterate
before each stress evaluation (theta_n from u_n, for the converged state of the update). The
Jacobian is exact: with theta a function of u through the projection, d theta = M^-1 B du (M the
diagonal of the cells' weighted volumes, B = int q dJ[du] w dX), so

    K = K_uu + K_u_theta M^-1 B,

K_uu the Jacobian at fixed theta (the forms' ``jacobian_form``) and K_u_theta the derivative of
the residual in theta; the product couples the dofs of one cell only, inside K_uu's pattern
(docs/theory.md section 5.5; a Taylor test checks it, tests/test_fbar.py).
"""
from __future__ import annotations

import numpy as np
import ufl
from dolfinx import fem
from petsc4py import PETSc

from .. import compat
from .kinematics import PLANE_STRAIN


class VolumeAverage:
    """The cell-wise mean dilatation theta of a model's iterate and converged state (DG0
    Functions), what the stress update makes of it, and the Jacobian's condensed part.

    Built by the model when its body has ``fbar=True`` and handed to the stress update
    (``update.volume``) before any form is built."""

    def __init__(self, model):
        m = self.model = model
        self.d = 2 if m.kin.model == PLANE_STRAIN else 3
        self.Q = compat.function_space(m.mesh, "DG", 0)
        self.theta = fem.Function(self.Q, name="mean_dilatation")
        self.theta_n = fem.Function(self.Q, name="mean_dilatation_n")
        self._generation = None               # the converged state theta_n was computed for
        self._forms = None
        self._matrices = None

    # -- what the stress update sees -----------------------------------------------------------
    def theta_for(self, u):
        """theta of the displacement ``u``: the model's iterate or its converged state."""
        if u is self.model.u:
            return self.theta
        if u is self.model.u_n:
            return self.theta_n
        raise ValueError("F-bar (fbar=True): the averaged volume change is known for the iterate and "
                         "the converged state only (Nitsche's facet stress is not averaged: use "
                         "method='penalty' with fbar)")

    def _plane(self):
        """I_d: the identity in the directions whose volume change is averaged."""
        return ufl.as_tensor(np.diag([1.0, 1.0, 0.0])) if self.d == 2 else ufl.Identity(3)

    def modified_F(self, F, u):
        """F_bar = (theta / det F)^(1/d) F (the in-plane block only in plane strain)."""
        f = (self.theta_for(u) / ufl.det(F)) ** (1.0 / self.d)
        if self.d == 2:
            return ufl.dot(ufl.as_tensor([[f, 0, 0], [0, f, 0], [0, 0, 1.0]]), F)
        return f * F

    def modified_strain(self, eps, u):
        """eps_bar = eps + (theta - tr eps) / d I_d (B-bar, linear kinematics)."""
        return eps + (self.theta_for(u) - ufl.tr(eps)) / self.d * self._plane()

    # -- theta from the iterate -----------------------------------------------------------------
    def _build_forms(self):
        m = self.model
        q, w, dx = ufl.TestFunction(self.Q), m.kin.weight(), m.rule.dx
        dil, dil_n = m.update.dilatation(m.u), m.update.dilatation(m.u_n)
        mass_form = compat.form(q * w * dx)
        self._minv = compat.create_vector(mass_form)
        compat.assemble_vector(self._minv, mass_form)
        self._minv.reciprocal()
        self._forms = (compat.form(dil * q * w * dx), compat.form(dil_n * q * w * dx))

    def _average(self, form, f) -> None:
        """f = M^-1 (the assembled ``form``): the cell means (ghost cells too)."""
        vec = compat.petsc_vec(f)
        compat.assemble_vector(vec, form)
        vec.pointwiseMult(vec, self._minv)
        vec.ghostUpdate(addv=PETSc.InsertMode.INSERT, mode=PETSc.ScatterMode.FORWARD)

    def refresh(self, generation: int) -> None:
        """theta of the current iterate; theta_n too when the converged state changed since the
        last call (``generation``: the evaluation's count of those changes)."""
        if self._forms is None:
            self._build_forms()
        if generation != self._generation:
            self._average(self._forms[1], self.theta_n)
            self._generation = generation
        self._average(self._forms[0], self.theta)

    # -- the Jacobian's condensed part ----------------------------------------------------------
    def coupling_forms(self, d_residual_d_theta, jit=None) -> None:
        """Compile K_u_theta (``d_residual_d_theta``: the residual's derivative in a DG0 trial
        function, a bilinear form on (V, Q)) and B = int q dJ[du] w dX."""
        m = self.model
        q, w, dx = ufl.TestFunction(self.Q), m.kin.weight(), m.rule.dx
        B = ufl.derivative(m.update.dilatation(m.u) * q * w * dx, m.u, m.u_trial)
        self._coupling = (compat.form(d_residual_d_theta, jit), compat.form(B, jit))

    def trial(self):
        """The DG0 trial function of K_u_theta."""
        return ufl.TrialFunction(self.Q)

    def add_condensed(self, A: PETSc.Mat, bcs=()) -> None:
        """A += K_u_theta M^-1 B, the constrained rows and columns left out (A assembled, with
        K_uu's pattern, which holds the product's)."""
        a_ut, a_b = self._coupling
        if self._matrices is None:
            self._matrices = [compat.create_matrix(a_ut), compat.create_matrix(a_b), None]
        K, B, _ = self._matrices
        compat.assemble_matrix(K, a_ut, bcs)
        compat.assemble_matrix(B, a_b, bcs)
        B.diagonalScale(L=self._minv)
        self._matrices[2] = C = K.matMult(B, result=self._matrices[2])
        A.axpy(1.0, C, structure=PETSc.Mat.Structure.SUBSET_NONZERO_PATTERN)

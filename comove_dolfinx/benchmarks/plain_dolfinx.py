"""What a user would write instead of this package: a compressible neo-Hookean body solved by dolfinx's
own Newton solver, on the ring scene's mesh.

The ring's quarter (the same mesh, P2 space, quadrature degree and symmetry supports as the scene's
model) is pressed at its crown by a prescribed vertical displacement of the outer boundary within
``CROWN`` of the axis (a rigid punch bonded to it, instead of the scene's plate with contact and
friction), in increments, each solved from the last by ``dolfinx``'s Newton solver with MUMPS
(:func:`comove_dolfinx.compat.plain_newton`). The stored energy per unit reference area (plane
strain, C = F^T F of the 2 x 2 gradient, J = det F)::

    W = mu / 2 (tr C - 2 - 2 ln J) + lambda / 2 (ln J)^2

with the ring's Lame constants; its residual and Jacobian are UFL's derivatives of the energy, as in
dolfinx's hyperelasticity demo. Linearised at u = 0 it is linear elasticity with the same constants.
"""
from __future__ import annotations

import time

import numpy as np
import ufl
from dolfinx import fem, mesh as dmesh
from petsc4py import PETSc

from .. import compat

#: the outer boundary within this horizontal distance of the axis (a fraction of the outer radius)
#: carries the crown's prescribed displacement
CROWN = 0.2
#: MUMPS through PETSc's options, as dolfinx's demos set it
MUMPS = {"ksp_type": "preonly", "pc_type": "lu", "pc_factor_mat_solver_type": "mumps"}
#: Newton's relative tolerance (on the correction: :func:`comove_dolfinx.compat.plain_newton`)
RTOL = 1e-8


def lame(E: float, nu: float) -> tuple[float, float]:
    """(lambda, mu) of Young's modulus and Poisson's ratio."""
    return E * nu / ((1 + nu) * (1 - 2 * nu)), E / (2 * (1 + nu))


def energy(u, lam, mu):
    """The neo-Hookean stored energy density W(u) of the module's docstring (plane strain)."""
    d = len(u)
    F = ufl.Identity(d) + ufl.grad(u)
    J = ufl.det(F)
    return mu / 2 * (ufl.tr(F.T * F) - d - 2 * ufl.ln(J)) + lam / 2 * ufl.ln(J) ** 2


class PlainNeoHooke:
    """The neo-Hookean crown press on a model's mesh, space, quadrature and supports.

    Parameters
    ----------
    model : Model
        A finalized model of the ring scene (its mesh, ``V``, ``rule.dx``, ``bcs`` and Lame
        constants are used; nothing of it is changed).
    R_out : float
        The ring's outer radius (locates the crown).
    monitor : callable, optional
        Called with the norm of each residual Newton evaluates (for tests; it costs a norm).
    """

    def __init__(self, model, R_out: float, monitor=None):
        self.model = model
        msh, V = model.mesh, model.V
        self.u = fem.Function(V)
        v, du = ufl.TestFunction(V), ufl.TrialFunction(V)
        lam, mu = lame(model.elastic.E, model.elastic.nu)
        self.lam = fem.Constant(msh, PETSc.ScalarType(lam))
        self.mu = fem.Constant(msh, PETSc.ScalarType(mu))
        Pi = energy(self.u, self.lam, self.mu) * model.rule.dx
        self.F = ufl.derivative(Pi, self.u, v)
        self.J = ufl.derivative(self.F, self.u, du)
        self.push = fem.Constant(msh, PETSc.ScalarType(0.0))
        self.bcs = [*model.bcs, self._crown_bc(R_out)]
        self.solve = compat.plain_newton(self.F, self.u, self.bcs, self.J, MUMPS, RTOL,
                                          monitor=monitor)

    def _crown_bc(self, R_out: float):
        """u_y = ``self.push`` on the outer boundary within CROWN * R_out of the axis."""
        msh, V = self.model.mesh, self.model.V
        fdim = msh.topology.dim - 1

        def crown(x):
            return (np.hypot(x[0], x[1]) > R_out * (1 - 1e-6)) & (x[0] < CROWN * R_out)
        facets = dmesh.locate_entities_boundary(msh, fdim, crown)
        dofs = fem.locate_dofs_topological(V.sub(1), fdim, facets)
        return fem.dirichletbc(self.push, dofs, V.sub(1))

    def run(self, pushes) -> dict:
        """Solve from rest for each crown displacement of ``pushes`` in turn (downward > 0): CPU
        seconds of the loop (``time.process_time``, this rank), Newton iterations, and whether every
        increment converged."""
        self.u.x.array[:] = 0.0
        its, ok = 0, True
        c0 = time.process_time()
        for p in pushes:
            self.push.value = -p
            n, converged = self.solve()
            its, ok = its + n, ok and converged
        return {"cpu": time.process_time() - c0, "iterations": its, "converged": ok}


def pushes_of(scene, increments: int) -> list[float]:
    """The crown displacements of the ring's first ``increments`` nominal increments: the plates'
    approach shared by the two halves (delta / 2) at the scene's nominal steps."""
    step = scene.delta_max / 2 / scene.n_increments
    return [step * k for k in range(1, increments + 1)]

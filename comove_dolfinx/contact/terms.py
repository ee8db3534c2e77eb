"""The contact item's residual term: the normal law and, with friction, the tangential one.

The terms come from the pure functions of laws.py with the obstacle's gap and normal at the current
position x = X + u and, for Nitsche, the model's facet traction (docs/theory.md section 6). The
weights are gamma = gamma0 E / h and gamma_t = gamma0_t E / h, h the cell size; gamma0 E, gamma0_t E
and mu are Constants, so that models that differ in them only share the compiled code.

Friction's slip threshold s is mu times a pressure: with the lagged law that of the lag state (the
body at u_lag against the obstacle where it stood then, history.py), with the coulomb law that of
the current iterate, differentiated with the rest.
"""
from __future__ import annotations

import numpy as np
import ufl
from dolfinx import fem
from petsc4py import PETSc

from .. import compat
from . import laws

FACET_DEGREE = 7          # 4 Gauss points per facet


def cell_sizes(msh) -> fem.Function:
    """The cell diameters h as a DG0 function (ghost cells too)."""
    tdim = msh.topology.dim
    DG0 = compat.function_space(msh, "DG", 0)
    h = fem.Function(DG0, name="cell_size")
    ncell = msh.topology.index_map(tdim).size_local + msh.topology.index_map(tdim).num_ghosts
    cells = np.arange(ncell, dtype=np.int32)
    h.x.array[compat.cell_dofs(DG0, ncell)[:, 0]] = compat.cell_sizes(msh, cells)
    return h


class ContactTerms:
    """The UFL of one contact item's terms (``item``: its settings and obstacle; ``history``: the
    fields it carries between increments, history.py).

    Attributes
    ----------
    R_c
        The residual term (linear in the test function), over the contact boundary.
    ds
        The contact boundary's measure (the facet rule of degree ``FACET_DEGREE``).
    p_ref, q_ref
        The contact pressure and the tangential traction along t_o, per unit reference area
        (q_ref None without friction; in 3D the tangential traction vector).
    slipping
        Where the friction law slips (a UFL condition; None without friction).
    p_lag, n_lag
        The lag state's pressure and the obstacle's normal there (the lagged law; else None).
    e_new
        The penalty friction's stick part at the current iterate (else None).
    base
        Nitsche's lagged law: the converged state u_lag was solved from (a FacetBase; else None).
    """

    def __init__(self, item, ctx, h, history):
        self.gamma0E = fem.Constant(ctx.mesh, PETSc.ScalarType(item.gamma0 * ctx.E))
        gamma = self.gamma0E / h
        u, v = ctx.u, ctx.v
        x = ctx.x + u
        obs = item.obstacle
        g, n_o = obs.gap(x), obs.normal(x)
        self.ds = ctx.ds(item.boundary, {"quadrature_degree": FACET_DEGREE})
        N = ufl.FacetNormal(ctx.mesh)
        PN = None
        if item.method == "penalty":
            R, p = laws.penalty_normal(g, n_o, v, gamma)
        else:
            PN = ctx.facet_traction(N)
            p_u = ufl.dot(n_o, PN)
            R, p = laws.nitsche_normal(g, n_o, v, gamma, item.theta, p_u, ufl.derivative(p_u, u, v))
        self.p_ref = p
        self.q_ref = self.slipping = self.p_lag = self.n_lag = self.e_new = self.base = None
        if item.mu > 0:
            R = R + self._friction(item, ctx, h, history, gamma, n_o, N, PN)
        self.R_c = R * ctx.weight * self.ds

    def _friction(self, item, ctx, h, history, gamma, n_o, N, PN):
        """The tangential term's integrand (and q_ref, slipping, ...: the class's attributes)."""
        self.gamma0tE = fem.Constant(ctx.mesh, PETSc.ScalarType(item.gamma0_t * ctx.E))
        gamma_t = self.gamma0tE / h
        self.mu_c = fem.Constant(ctx.mesh, PETSc.ScalarType(item.mu))      # no recompile for a new mu
        if item.friction == "lagged":
            s = self.mu_c * self._lag_pressure(item, ctx, history, gamma, N)
        else:
            s = self.mu_c * self.p_ref          # the current pressure: differentiated with the rest
        u, v, obs = ctx.u, ctx.v, item.obstacle
        if obs.dim == 3:
            return self._friction_3d(item, ctx, history, s, gamma_t, n_o, PN)
        t_o = ufl.as_vector([-n_o[1], n_o[0]])
        slip = ufl.dot(t_o, (u - ctx.u_n) - (obs.d - history.d_n))
        if item.method == "penalty":
            Rt, self.q_ref, trial, self.e_new = laws.penalty_friction(slip, history.e_n, s, t_o, v, gamma_t)
        else:
            q_u = ufl.dot(t_o, PN)
            Rt, self.q_ref, trial = laws.nitsche_friction(slip, s, t_o, v, gamma_t, item.theta, q_u,
                                                          ufl.derivative(q_u, u, v))
        self.slipping = ufl.gt(abs(trial), s)
        return Rt

    def _friction_3d(self, item, ctx, history, s, gamma_t, n_o, PN):
        """The tangential term in 3D: the slip is the vector (I - n_o n_o)(du - dd), the trial
        traction returns to the Coulomb disc of radius s (laws.py's ``*_vector`` laws); the
        penalty's stick part enters projected onto the current tangent plane (on a curved obstacle
        the plane turns from one increment to the next)."""
        u, v, obs = ctx.u, ctx.v, item.obstacle
        tangential = ufl.Identity(3) - ufl.outer(n_o, n_o)
        slip = tangential * ((u - ctx.u_n) - (obs.d - history.d_n))
        if item.method == "penalty":      # the stick part carried into the current tangent plane
            Rt, self.q_ref, norm, self.e_new = laws.penalty_friction_vector(slip, tangential * history.e_n,
                                                                            s, v, gamma_t)
        else:
            q_u = tangential * PN
            Rt, self.q_ref, norm = laws.nitsche_friction_vector(slip, s, v, gamma_t, item.theta, q_u,
                                                                ufl.derivative(q_u, u, v))
        self.slipping = ufl.gt(norm, s)
        return Rt

    def _lag_pressure(self, item, ctx, history, gamma, N):
        """The pressure of the lag state: the body at u_lag against the obstacle where it stood then
        (d_lag); for Nitsche, with the stress at u_lag from the state u_lag was solved from (a
        FacetBase, captured at each commit)."""
        obs = item.obstacle
        x_lag, d_lag = ctx.x + history.u_lag, history.d_lag
        g_lag, self.n_lag = obs.gap(x_lag, d_lag), obs.normal(x_lag, d_lag)
        if item.method == "penalty":
            self.p_lag = gamma * laws.positive_part(-g_lag)
        else:
            self.base = ctx.facet_base()
            PN_lag = ctx.facet_traction(N, history.u_lag, self.base)
            self.p_lag = laws.positive_part(ufl.dot(self.n_lag, PN_lag) - gamma * g_lag)
        return self.p_lag

"""The contact item: a tagged boundary against a rigid obstacle, penalty or Nitsche, Coulomb friction.

Its factor drives the obstacle's motion (obstacles.py); its terms come from the pure functions of
laws.py with the obstacle's gap and normal at the current position x = X + u and, for Nitsche, the
model's facet traction (docs/theory.md section 6).

Friction (``mu > 0``) has two laws, chosen by ``friction``:

* ``"lagged"`` (the default; Shang and Chen's scheme): the threshold is mu times the pressure of a lag state, the
  body at u_lag against the obstacle where it stood then: the converged state of the last increment,
  or with ``relag`` the state of the last pass within the increment, repeated until the pressure
  settles. The lag state depends on converged data only, and its pressure is the pressure that state
  converged with, to round-off: Nitsche's stress at u_lag is evaluated from the converged state u_lag
  was solved from (a FacetBase), not from the one after it;
* ``"coulomb"``: the slip threshold is mu times the pressure of the current iterate, solved in the
  same Newton loop as everything else (the threshold's derivative is in the Jacobian, which is then
  unsymmetric).

The tangential term has its own weight gamma_t = gamma0_t E / h (by default gamma0_t = min(gamma0,
10), docs/theory.md section 6.3). The penalty friction keeps its stick part e_n (a length: the elastic
tangential slip) as a boundary field (a lumped projection at each converged increment); Nitsche's
lives in the stress.

Results: the force from the residual (F . e = -R_c(u; e) for the constant fields e_x, e_y), the extent
(current length of the boundary where the pressure is positive, at the facet quadrature points), the
largest nodal penetration, the lengths that stick and slip, and nodal fields of pressure and shear.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import ufl
from dolfinx import fem
from mpi4py import MPI
from petsc4py import PETSc

from .. import compat
from ..loads import Item
from ..names import CONTACT_METHODS as METHODS
from ..names import FRICTION_LAWS
from . import laws
from .obstacles import ContactError, Obstacle

FACET_DEGREE = 7          # 4 Gauss points per facet


@dataclass
class ZoneInfo:
    """The contact set in the current configuration."""

    extent: float              # length in contact along the boundary (current configuration)
    max_penetration: float     # largest -g over the nodes of the contact boundary (0 if none)

    @property
    def in_contact(self) -> bool:
        return self.extent > 0.0


class Contact(Item):
    """Contact of the tagged boundary ``boundary`` with ``obstacle``.

    Parameters
    ----------
    method : "penalty" or "nitsche"
    gamma0 : float
        Dimensionless weight: gamma = gamma0 E / h, h the cell diameter.
    theta : 1, 0 or -1
        Nitsche's variant (symmetric, incomplete, skew-symmetric).
    mu : float
        Coulomb friction coefficient (0: frictionless).
    relag : bool
        With the lagged law: re-solve each increment with the threshold of its own solution until
        the pressure changes by less than ``relag_tol`` (at most ``max_passes`` passes).
    friction : "lagged" or "coulomb"
        The slip threshold mu p: "lagged" (the default) takes the pressure of the last converged
        increment (Shang and Chen's scheme; with ``relag``, of the last pass), "coulomb" p of the
        current iterate (in the same Newton loop). docs/theory.md section 6.3 says why lagged is
        the default.
    gamma0_t : float or None
        Dimensionless weight of the tangential (friction) term, gamma_t = gamma0_t E / h; None:
        min(gamma0, 10). Penalty: the stick part is elastic with stiffness gamma_t (a slip of q /
        gamma_t while sticking); Nitsche: consistent for any gamma0_t (docs/theory.md section 6.3).
    """

    kind = "contact"

    def __init__(self, boundary: str, obstacle: Obstacle, method: str = "penalty",
                 gamma0: float = 100.0, theta: int = 0, mu: float = 0.0, relag: bool = False,
                 max_passes: int = 10, relag_tol: float = 1e-4, friction: str = "lagged",
                 gamma0_t: float | None = None):
        super().__init__(boundary)
        if method not in METHODS:
            raise ContactError(f"contact method {method!r} is unknown: choose penalty or nitsche")
        if not (np.isfinite(gamma0) and gamma0 > 0):
            raise ContactError(f"gamma0 = {gamma0} must be a finite number > 0")
        if theta not in (1, 0, -1):
            raise ContactError(f"theta = {theta}: Nitsche's variant is 1, 0 or -1")
        if not (np.isfinite(mu) and mu >= 0):
            raise ContactError(f"mu = {mu}: the friction coefficient must be a finite number >= 0")
        if not isinstance(obstacle, Obstacle):
            raise ContactError(f"obstacle = {obstacle!r}: give a Plane, Circle or Profile")
        if friction not in FRICTION_LAWS:
            raise ContactError(f"friction = {friction!r} is unknown: choose coulomb (the current pressure) "
                               "or lagged (the last increment's)")
        if relag and friction != "lagged":
            raise ContactError("relag = True re-solves the lagged law: give friction='lagged' or "
                               "relag=False")
        if gamma0_t is None:
            gamma0_t = min(gamma0, 10.0)
        if not (isinstance(gamma0_t, (int, float)) and np.isfinite(gamma0_t) and gamma0_t > 0):
            raise ContactError(f"gamma0_t = {gamma0_t!r} must be a finite number > 0 (or None: min(gamma0, 10))")
        self.boundary, self.obstacle, self.method = boundary, obstacle, method
        self.gamma0, self.theta, self.mu = gamma0, theta, mu
        self.friction, self.gamma0_t = friction, float(gamma0_t)
        self.relag, self.max_passes, self.relag_tol = relag, max_passes, relag_tol
        self.factor_n = 0.0

    # -- the item protocol ------------------------------------------------------------------------
    def attach(self, ctx):
        """The contact terms of the residual (UFL, linear in the test function)."""
        msh = ctx.mesh
        self.comm, self.u, self._u_n = msh.comm, ctx.u, ctx.u_n
        self.obstacle.bind(msh)
        self.obstacle.set(self.factor)
        self._d_n = fem.Constant(msh, PETSc.ScalarType((0.0, 0.0)))     # obstacle at the last increment
        self._d_lag = fem.Constant(msh, PETSc.ScalarType((0.0, 0.0)))   # obstacle in the lag state
        self._d_n.value = self._d_lag.value = self.obstacle.displacement(self.factor_n)
        tdim = msh.topology.dim
        DG0 = compat.function_space(msh, "DG", 0)
        self.h = fem.Function(DG0, name="cell_size")
        ncell = msh.topology.index_map(tdim).size_local + msh.topology.index_map(tdim).num_ghosts
        cells = np.arange(ncell, dtype=np.int32)
        self.h.x.array[compat.cell_dofs(DG0, ncell)[:, 0]] = compat.cell_sizes(msh, cells)
        self.u_lag = fem.Function(ctx.V, name="u_lag")
        self.u_lag.x.array[:] = ctx.u_n.x.array
        # a Constant, so that models differing only in gamma0 share the compiled forms
        self._gamma0E = fem.Constant(msh, PETSc.ScalarType(self.gamma0 * ctx.E))
        gamma = self._gamma0E / self.h
        u, v, u_n = ctx.u, ctx.v, ctx.u_n
        x = ctx.x + u
        obs = self.obstacle
        g, n_o = obs.gap(x), obs.normal(x)
        t_o = ufl.as_vector([-n_o[1], n_o[0]])
        self.ds_c = ctx.ds(self.boundary, {"quadrature_degree": FACET_DEGREE})
        th = self.theta
        N = ufl.FacetNormal(msh)
        if self.method == "penalty":
            R, p = laws.penalty_normal(g, n_o, v, gamma)
        else:
            PN = ctx.facet_traction(N)
            p_u = ufl.dot(n_o, PN)
            R, p = laws.nitsche_normal(g, n_o, v, gamma, th, p_u, ufl.derivative(p_u, u, v))
        self.p_ref = p                                           # pressure per reference area
        self.q_ref = None
        self._base = self._base_kept = None
        if self.mu > 0:
            self._gamma0tE = fem.Constant(msh, PETSc.ScalarType(self.gamma0_t * ctx.E))
            gamma_t = self._gamma0tE / self.h
            self._mu_c = fem.Constant(msh, PETSc.ScalarType(self.mu))   # no recompile for a new mu
            if self.friction == "lagged":
                # the lag state: the body at u_lag against the obstacle where it stood then (d_lag)
                x_lag, d_lag = ctx.x + self.u_lag, self._d_lag
                g_lag, self._n_lag = obs.gap(x_lag, d_lag), obs.normal(x_lag, d_lag)
                if self.method == "penalty":
                    p_lag = gamma * laws.positive_part(-g_lag)
                else:
                    # the stress at u_lag from the state u_lag was solved from (captured at each commit)
                    self._base = ctx.facet_base()
                    PN_lag = ctx.facet_traction(N, self.u_lag, self._base)
                    p_lag = laws.positive_part(ufl.dot(self._n_lag, PN_lag) - gamma * g_lag)
                    self._base_kept = self._base.arrays()
                self._p_lag = p_lag
                s = self._mu_c * p_lag
            else:
                self._p_lag = None
                s = self._mu_c * p                # the current pressure: differentiated with the rest
            slip = ufl.dot(t_o, (u - u_n) - (obs.d - self._d_n))
            if self.method == "penalty":
                self.e_n = fem.Function(compat.function_space(msh, "Lagrange", ctx.degree), name="stick_slip")
                Rt, self.q_ref, trial, self._e_new = laws.penalty_friction(slip, self.e_n, s, t_o, v, gamma_t)
            else:
                q_u = ufl.dot(t_o, PN)
                Rt, self.q_ref, trial = laws.nitsche_friction(slip, s, t_o, v, gamma_t, th, q_u,
                                                              ufl.derivative(q_u, u, v))
            R = R + Rt
            self._slipping = ufl.gt(abs(trial), s)       # where the friction law slips
        self.R_c = R * ctx.weight * self.ds_c
        self._build_outputs(ctx)
        return self.R_c

    def _apply(self, factor):
        self.obstacle.set(factor)

    def commit(self) -> None:
        """Before the model's own state moves to the new increment (u_n still the old one)."""
        if self.mu > 0 and self.method == "penalty":
            vals = self._assemble_vec(self._form("e"))
            m, b = self._lumped, self._sdofs      # the boundary's nodes (elsewhere m is round-off)
            self.e_n.x.array[b] = vals[b] / m[b]
            self.e_n.x.scatter_forward()
        self.factor_n = self.factor
        self._d_n.value = self.obstacle.displacement(self.factor)
        self._d_lag.value = self._d_n.value
        self.u_lag.x.array[:] = self.u.x.array
        if self._base is not None:              # the model's state has not moved yet: u's own base
            self._base.capture()
            self._base_kept = self._base.arrays()

    def restore(self) -> None:
        self.u_lag.x.array[:] = self._u_n.x.array
        self._d_lag.value = self._d_n.value
        if self._base is not None:              # a relag pass may have moved it
            self._base.set_arrays(self._base_kept)

    def save_state(self) -> dict:
        out = super().save_state()
        out.update(factor_n=self.factor_n, d_n=np.array(self._d_n.value), d_lag=np.array(self._d_lag.value),
                   u_lag=("V", self.u_lag.x.array))
        if self.mu > 0 and self.method == "penalty":
            out["e_n"] = (self.e_n.function_space, self.e_n.x.array)
        return out

    def load_state(self, state: dict) -> None:
        super().load_state(state)
        self.factor_n = float(state["factor_n"])
        self._d_n.value, self._d_lag.value = state["d_n"], state["d_lag"]
        self.u_lag.x.array[:] = state["u_lag"]
        if "e_n" in state:
            self.e_n.x.array[:] = state["e_n"]

    def relag_pass(self) -> bool:
        """The lagged law with ``relag``: take the threshold from the current solution; True if it
        changed notably."""
        if not (self.relag and self.mu > 0 and self.friction == "lagged"):
            return False
        p_old = self._assemble_vec(self._form("p_lag"))
        self.u_lag.x.array[:] = self.u.x.array
        self._d_lag.value = self.obstacle.displacement(self.factor)
        if self._base is not None:              # this pass was solved from the current state
            self._base.capture()
        p_new = self._assemble_vec(self._form("p_lag"))
        scale = max(np.abs(p_new).max(), 1e-300)
        change = self.comm.allreduce(float(np.abs(p_new - p_old).max()) / scale, op=MPI.MAX)
        return change > self.relag_tol

    # -- results ------------------------------------------------------------------------------------
    def _build_outputs(self, ctx):
        """The forms of the results (compiled on first use: a run that never asks for one does not
        pay its compilation)."""
        msh = ctx.mesh
        self._e = fem.Constant(msh, PETSc.ScalarType((0.0, 0.0)))
        S = compat.function_space(msh, "Lagrange", ctx.degree)
        phi = ufl.TestFunction(S)
        # pressure and shear are projected with linear weights (non-negative hat functions), so a
        # pressure that the law keeps >= 0 stays >= 0 at the nodes; then interpolated onto S
        S1 = compat.function_space(msh, "Lagrange", 1)
        phi1 = ufl.TestFunction(S1)
        F = ctx.update.F(ctx.u)
        N = ufl.FacetNormal(msh)
        N3 = ufl.as_vector([N[0], N[1], 0.0])
        stretch = ufl.sqrt(ufl.dot(ufl.det(F) * ufl.inv(F).T * N3, ufl.det(F) * ufl.inv(F).T * N3))
        # current length of the contact set: in-plane stretch of the boundary where p > 0
        F2 = ufl.Identity(2) + ufl.grad(ctx.u)
        T = ufl.as_vector([-N[1], N[0]])
        chi = ufl.conditional(ufl.gt(self.p_ref, 0.0), 1.0, 0.0)
        dsc = self.ds_c
        self._ufl = {"force": -ufl.replace(self.R_c, {ctx.v: self._e}), "mass": phi * dsc,
                     "mass1": phi1 * dsc, "extent": chi * ufl.sqrt(ufl.dot(F2 * T, F2 * T)) * dsc,
                     "p": self.p_ref / stretch * phi1 * dsc}
        if self.mu > 0:
            # reference length of the contact set that slips (friction at its threshold) and sticks
            slipping = ufl.conditional(self._slipping, 1.0, 0.0)
            self._ufl.update(slip=chi * slipping * dsc, stick=chi * (1.0 - slipping) * dsc,
                             q=self.q_ref / stretch * phi1 * dsc)
            if self._p_lag is not None:
                self._ufl.update(p_lag=self._p_lag * phi * dsc,
                                 lag_force=self._p_lag * ufl.dot(self._n_lag, self._e) * ctx.weight * dsc)
            if self.method == "penalty":
                self._ufl["e"] = self._e_new * phi * dsc
        self._compiled = {}
        if "e" in self._ufl:            # every commit needs it: compiled with the model's forms
            self._form("e")
        self.pressure = fem.Function(S, name="contact_pressure")
        self.shear = fem.Function(S, name="contact_shear")
        self._vec = compat.create_vector(self._form("mass"))
        self._lumped = self._assemble_vec(self._form("mass"))
        self._f1 = fem.Function(S1)
        self._vec1 = compat.create_vector(self._form("mass1"))
        self._lumped1 = self._assemble_vec(self._form("mass1"), self._vec1)
        # nodes of the contact boundary (owned), for the contact zone
        fdim = msh.topology.dim - 1
        facets = ctx.facets(self.boundary)
        dofs = fem.locate_dofs_topological(ctx.V.sub(0), fdim, facets)   # unrolled indices of V
        nodes = np.unique(dofs // ctx.V.dofmap.index_map_bs)
        self._nodes = nodes[nodes < ctx.V.dofmap.index_map.size_local]   # owned nodes only
        self._X = ctx.V.tabulate_dof_coordinates()[self._nodes, :2]
        sdofs = fem.locate_dofs_topological(S, fdim, facets)
        self._sdofs = sdofs[sdofs < S.dofmap.index_map.size_local]
        self._off = np.ones(S.dofmap.index_map.size_local + S.dofmap.index_map.num_ghosts, dtype=bool)
        self._off[sdofs] = False                     # dofs away from the contact boundary
        # the boundary field's dof at each of the boundary's nodes (same points, matched by position
        # among the boundary's dofs, ghosts included)
        XS = np.round(S.tabulate_dof_coordinates()[sdofs, :2], 12).tolist()
        key = {tuple(x): int(d) for x, d in zip(XS, sdofs)}
        self._node_sdof = np.array([key.get(tuple(x), -1) for x in np.round(self._X, 12).tolist()], dtype=np.int64)
        s1 = fem.locate_dofs_topological(S1, fdim, facets)
        self._s1dofs = s1[s1 < S1.dofmap.index_map.size_local]
        self._p1_to_s = self._p1_interpolation(S, S1, ctx.degree)

    @staticmethod
    def _p1_interpolation(S, S1, degree: int):
        """(dofs of S, the two P1 dofs whose mean is their value) for the interpolation of a P1
        field into the boundary fields' space S (P1 or P2: a vertex takes its value, an edge's
        midpoint the mean of the edge's ends), in numpy: dolfinx's interpolation between two spaces
        cost as much as the rest of the output. None for other degrees."""
        if degree not in (1, 2):
            return None
        tdim = S.mesh.topology.dim
        imap = S.mesh.topology.index_map(tdim)
        n = imap.size_local + imap.num_ghosts
        cs, c1 = compat.cell_dofs(S, n), compat.cell_dofs(S1, n)
        # the P2 triangle's dofs: the vertices, then the edges opposite vertices 0, 1 and 2
        ends = [(0, 0), (1, 1), (2, 2)] + ([(1, 2), (0, 2), (0, 1)] if degree == 2 else [])
        dofs = np.concatenate([cs[:, k] for k in range(len(ends))])
        a = np.concatenate([c1[:, i] for i, _ in ends])
        b = np.concatenate([c1[:, j] for _, j in ends])
        return dofs, a, b

    @property
    def nodes(self) -> np.ndarray:
        """The contact boundary's owned nodes (numbering of the displacement's blocked dofs)."""
        return self._nodes

    @property
    def node_sdof(self) -> np.ndarray:
        """The dof of the boundary fields (``pressure``, ``shear``) at each of ``nodes`` (-1: none)."""
        return self._node_sdof

    def _form(self, name: str):
        """The compiled form ``name`` (collective: every rank asks for it at the same point)."""
        if name not in self._compiled:
            self._compiled[name] = fem.form(self._ufl[name])
        return self._compiled[name]

    def _assemble_vec(self, form, vec=None) -> np.ndarray:
        """Owned entries of an assembled linear form on the boundary field space (or ``vec``'s)."""
        vec = self._vec if vec is None else vec
        compat.assemble_vector(vec, form)
        return vec.array.copy()

    def check_start(self) -> None:
        """ContactError if the body already penetrates the obstacle in its initial state."""
        g = self.obstacle.gap_np(self._X, self.obstacle.displacement(self.factor))
        gmin = self.comm.allreduce(float(g.min()) if g.size else np.inf, op=MPI.MIN)
        scale = self.comm.allreduce(float(np.ptp(self._X)) if g.size else 0.0, op=MPI.MAX)
        if gmin < -1e-9 * max(scale, 1.0):
            raise ContactError(f"boundary {self.boundary!r} starts inside the obstacle (gap {gmin:.3g} "
                               "< 0): move the obstacle away from the body")

    def force(self) -> np.ndarray:
        """Total force of the obstacle on the body (x, y), from the residual's contact term."""
        out = np.zeros(2)
        for i in range(2):
            self._e.value = np.eye(2)[i]
            out[i] = self.comm.allreduce(fem.assemble_scalar(self._form("force")), op=MPI.SUM)
        return out

    def lag_force(self) -> np.ndarray:
        """Force (x, y) of the lag state's pressure on the body, the normal force that the friction
        threshold mu p_lag is taken from: after a commit, the normal part of that increment's
        :meth:`force` (zeros without friction and with the coulomb law, which has no lag state)."""
        out = np.zeros(2)
        if "lag_force" in self._ufl:
            for i in range(2):
                self._e.value = np.eye(2)[i]
                out[i] = self.comm.allreduce(fem.assemble_scalar(self._form("lag_force")), op=MPI.SUM)
        return out

    def update_fields(self) -> None:
        """Contact pressure and tangential traction (per current area) as boundary fields: lumped
        projections with the linear hat functions (weights >= 0: the pressure never goes below
        zero) onto the boundary's vertices, interpolated onto the boundary field space."""
        m, b, g = self._lumped1, self._s1dofs, self._f1
        for name, f in (("p", self.pressure), ("q", self.shear)):
            if name not in self._ufl:
                continue
            vals = self._assemble_vec(self._form(name), self._vec1)
            g.x.array[:] = 0.0
            g.x.array[b] = vals[b] / m[b]
            g.x.scatter_forward()
            if self._p1_to_s is None:
                f.interpolate(g)
            else:
                dofs, ea, eb = self._p1_to_s
                f.x.array[dofs] = 0.5 * (g.x.array[ea] + g.x.array[eb])
            f.x.array[self._off] = 0.0                # the interpolation reaches into the cells
            f.x.scatter_forward()

    def boundary_values(self, f) -> tuple[np.ndarray, np.ndarray]:
        """(reference coordinates, values) of a scalar output field (e.g. ``pressure``) at every node
        of the contact boundary, gathered on all ranks."""
        X = f.function_space.tabulate_dof_coordinates()[self._sdofs, :2]
        return (np.concatenate(self.comm.allgather(X)),
                np.concatenate(self.comm.allgather(f.x.array[self._sdofs])))

    def stick_slip(self) -> tuple[float, float]:
        """Reference lengths of the contact set where friction sticks and where it slips (zeros
        without friction), at the current iterate."""
        if "slip" not in self._ufl:
            return 0.0, 0.0
        return tuple(self.comm.allreduce(fem.assemble_scalar(f), op=MPI.SUM)
                     for f in (self._form("stick"), self._form("slip")))

    def zone_edges(self, axis: int = 0) -> tuple[float, float]:
        """Smallest and largest current coordinate ``axis`` of the boundary's nodes that carry
        contact pressure (NaN, NaN without contact): where the contact set begins and ends."""
        self.update_fields()
        ok = self._node_sdof >= 0
        p = np.zeros(len(self._nodes))
        p[ok] = self.pressure.x.array[self._node_sdof[ok]]
        x = (self._X + self.u.x.array.reshape(-1, 2)[self._nodes])[p > 0, axis]
        lo = self.comm.allreduce(float(x.min()) if x.size else np.inf, op=MPI.MIN)
        hi = self.comm.allreduce(float(x.max()) if x.size else -np.inf, op=MPI.MAX)
        return (lo, hi) if np.isfinite(lo) else (np.nan, np.nan)

    def zone(self) -> ZoneInfo:
        """Contact extent (from the facet quadrature points) and the largest nodal penetration."""
        extent = self.comm.allreduce(fem.assemble_scalar(self._form("extent")), op=MPI.SUM)
        x = self._X + self.u.x.array.reshape(-1, 2)[self._nodes]
        g = self.obstacle.gap_np(x, self.obstacle.displacement(self.factor))
        pen = self.comm.allreduce(float(max(-g.min(), 0.0)) if g.size else 0.0, op=MPI.MAX)
        return ZoneInfo(float(extent), pen)

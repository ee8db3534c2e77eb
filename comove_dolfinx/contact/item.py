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

Results: the force from the residual (F . e = -R_c(u; e) for the constant fields e_x, e_y), here;
the contact zone, its edges, the pressure profile at the quadrature points, the peak pressure, the
largest nodal penetration, the lengths that stick and slip and the nodal fields of pressure and shear
in contact/outputs.py (``Contact.outputs``), which the item's methods of those names hand over to.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import ufl
from dolfinx import fem
from mpi4py import MPI
from petsc4py import PETSc

from .. import checks, compat
from ..loads import Item
from ..names import CONTACT_METHODS as METHODS
from ..names import FRICTION_LAWS
from . import laws
from .obstacles import ContactError, Obstacle
from .outputs import ContactOutputs

FACET_DEGREE = 7          # 4 Gauss points per facet


@dataclass
class ZoneInfo:
    """The contact set in the current configuration."""

    extent: float              # current length of the contact set, between its edges (outputs.py)
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
        why = checks.first(
            checks.text("boundary", boundary, "the name of a tagged boundary"),
            checks.number("gamma0", gamma0, gt=0),
            checks.choice("theta", theta, (1, 0, -1), " (Nitsche's variant)"),
            checks.number("mu", mu, ge=0, what=" (the friction coefficient)"),
            checks.flag("relag", relag),
            checks.number("max_passes", max_passes, ge=1, whole=True, what=" (passes of relag per increment)"),
            checks.number("relag_tol", relag_tol, gt=0, what=" (relag's relative change of the pressure)"))
        if why is not None:
            raise ContactError(why)
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
        if checks.number("gamma0_t", gamma0_t, gt=0):
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

    # -- results (contact/outputs.py) ----------------------------------------------------------------
    def _build_outputs(self, ctx):
        """The results' forms and fields (contact/outputs.py), compiled on first use."""
        self.outputs = ContactOutputs(self, ctx)

    # what the item's own methods use of the results' forms, handed over to them
    _FROM_OUTPUTS = frozenset({"_e", "_ufl", "_vec", "_lumped", "_sdofs", "_X", "_nodes"})
    _RENAMED = {"_ufl": "ufl"}

    def __getattr__(self, name):
        if name in Contact._FROM_OUTPUTS and "outputs" in self.__dict__:
            return getattr(self.__dict__["outputs"], Contact._RENAMED.get(name, name))
        raise AttributeError(f"{type(self).__name__!r} object has no attribute {name!r}")

    @property
    def nodes(self) -> np.ndarray:
        """The contact boundary's owned nodes (numbering of the displacement's blocked dofs)."""
        return self.outputs._nodes

    @property
    def node_sdof(self) -> np.ndarray:
        """The dof of the boundary fields (``pressure``, ``shear``) at each of ``nodes`` (-1: none)."""
        return self.outputs._node_sdof

    def _form(self, name: str):
        """The compiled form ``name`` (collective: every rank asks for it at the same point)."""
        return self.outputs.form(name)

    def _assemble_vec(self, form, vec=None) -> np.ndarray:
        """Owned entries of an assembled linear form on the boundary field space (or ``vec``'s)."""
        return self.outputs.assemble_vec(form, vec)

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

    @property
    def pressure(self):
        """Contact pressure per current area as a boundary field (a Function of the displacement's
        degree, zero away from the boundary; contact/outputs.py): current whenever it is read, with
        or without a writer. Collective."""
        return self.outputs.field("pressure")

    @property
    def shear(self):
        """Tangential traction along t_o per current area as a boundary field, like ``pressure``
        (zero without friction). Collective."""
        return self.outputs.field("shear")

    def update_fields(self) -> None:
        """Bring ``pressure`` and ``shear`` up to date (reading them does it too). Collective."""
        self.outputs.update_fields()

    def boundary_values(self, f) -> tuple[np.ndarray, np.ndarray]:
        """(reference coordinates, values) of a boundary field at every node of the contact
        boundary, gathered on all ranks: ``f`` is ``"pressure"``, ``"shear"`` or the Function."""
        return self.outputs.boundary_values(f)

    def profile(self):
        """Pressure, shear and gap at the facet quadrature points, sorted along the boundary, with
        reference and current coordinates and arc length (contact/outputs.py, ``ContactProfile``; the
        same on every rank). Collective."""
        return self.outputs.profile()

    def peak_pressure(self) -> float:
        """The peak contact pressure per current area: a parabola fitted to the quadrature points'
        pressures over the facet of the largest mean pressure and its neighbours (contact/outputs.py;
        0 without contact). Collective."""
        return self.outputs.peak_pressure()

    def stick_slip(self) -> tuple[float, float]:
        """Reference lengths of the contact set where friction sticks and where it slips (zeros
        without friction), at the current iterate."""
        return self.outputs.stick_slip()

    def zone_edges(self, axis: int = 0) -> tuple[float, float]:
        """Smallest and largest current coordinate ``axis`` of the contact set's edges, where the
        pressure at the quadrature points reaches zero (contact/outputs.py; NaN, NaN without
        contact). Collective."""
        return self.outputs.zone_edges(axis)

    def zone(self) -> ZoneInfo:
        """The contact set's current length (between its edges, contact/outputs.py) and the largest
        nodal penetration. Collective."""
        return ZoneInfo(self.outputs.extent(), self.outputs.max_penetration())

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

In 3D (a body of kind ``solid`` against a Plane of 3-vectors, a Sphere, a Cylinder, an Extruded or
Revolved profile or a Surface) the slip is a vector of the obstacle's tangent plane and the
friction traction returns to the Coulomb disc (terms.py, laws.py); the obstacle's dimension must
be the body's.

The tangential term has its own weight gamma_t = gamma0_t E / h (by default gamma0_t = min(gamma0,
10), docs/theory.md section 6.3). The penalty friction keeps its stick part e_n (a length: the elastic
tangential slip) as a boundary field (a lumped projection at each converged increment); Nitsche's
lives in the stress.

The item is made of parts that each do one job: ``terms`` (terms.py: the residual term of the
normal and tangential laws), ``history`` (history.py: what it carries between increments, the lag
state of friction and the penalty's stick part) and ``outputs`` (outputs.py: the force, the contact
zone, its edges, the pressure profile at the quadrature points, the peak pressure, the largest nodal
penetration, the lengths that stick and slip, the nodal fields of pressure and shear and, in 3D,
the contact radius along a meridian), whose results are the item's too. An obstacle whose gap
comes from fields computed outside UFL (a Surface's closest points) is brought to the current
state before each assembly: by ``nodal``, which the model calls before it assembles the residual,
at each commit and relag pass, and before each result.
"""
from __future__ import annotations

import operator

import numpy as np
from mpi4py import MPI

from .. import checks
from ..delegation import delegate
from ..mechanics.items import Item
from ..choices import CONTACT_METHODS as METHODS
from ..choices import FRICTION_LAWS
from .history import ContactHistory
from .obstacles import ContactError, Obstacle
from .outputs import ContactOutputs, ZoneInfo
from .terms import FACET_DEGREE, ContactTerms, cell_sizes

__all__ = ["FACET_DEGREE", "Contact", "ZoneInfo"]


def tracked(path: str) -> property:
    """Like ``delegate(path)`` (an output of the item's parts), after the obstacle's fields computed
    outside UFL are brought to the current state (Obstacle.track; collective, as every output)."""
    getter = operator.attrgetter(path)

    def get(self):
        self.obstacle.track()
        return getter(self)
    return property(get, doc=f"``{path}`` (``self.{path}``), which documents it, at the current state.")


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
            raise ContactError(f"obstacle = {obstacle!r}: give a Plane, Circle or Profile (2D), or a "
                               "Plane, Sphere, Cylinder, Extruded, Revolved or Surface (3D)")
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
        """The contact terms of the residual (UFL, linear in the test function); builds the item's
        parts."""
        dim, obs = ctx.mesh.topology.dim, self.obstacle
        if obs.dim != dim:
            fix = ("give a 3D obstacle: Plane with 3-vectors, Sphere, Cylinder, Extruded, Revolved or Surface"
                   if dim == 3 else "give a 2D obstacle: Plane with 2-vectors, Circle or Profile")
            raise ContactError(f"contact on {self.boundary!r}: the obstacle {type(obs).__name__} is {obs.dim}D, "
                               f"the body {dim}D: {fix}")
        self.comm, self.u, self._u_n = ctx.mesh.comm, ctx.u, ctx.u_n
        self.obstacle.bind(ctx.mesh)
        self.obstacle.set(self.factor)
        self.h = cell_sizes(ctx.mesh)
        self.history = ContactHistory(ctx, self.obstacle.displacement(self.factor_n),
                                      stick=self.mu > 0 and self.method == "penalty")
        self.terms = ContactTerms(self, ctx, self.h, self.history)
        self.history.bind(self.terms, ctx, self.boundary)
        self.outputs = ContactOutputs(self, ctx)
        self.obstacle.on_boundary(ctx.facets(self.boundary))
        return self.terms.R_c

    def nodal(self):
        """No nodal forces. The model asks every item for them before each assembly of its residual:
        then an obstacle with fields computed outside UFL (a Surface's closest points) brings them
        to the current iterate and load factor. Collective."""
        self.obstacle.track()
        return None

    def _apply(self, factor):
        self.obstacle.set(factor)

    def commit(self) -> None:
        """Before the model's own state moves to the new increment (u_n still the old one)."""
        self.obstacle.track()                  # the stick part below is assembled at the current u
        self.factor_n = self.factor
        self.history.commit(self.u, self.obstacle.displacement(self.factor))

    def restore(self) -> None:
        self.history.restore(self._u_n)

    def save_state(self) -> dict:
        out = super().save_state()
        out["factor_n"] = self.factor_n
        out.update(self.history.save())
        return out

    def load_state(self, state: dict) -> None:
        super().load_state(state)
        self.factor_n = float(state["factor_n"])
        self.history.load(state)

    def relag_pass(self) -> bool:
        """The lagged law with ``relag``: take the threshold from the current solution; True if it
        changed notably."""
        if not (self.relag and self.mu > 0 and self.friction == "lagged"):
            return False
        change = self.history.relag(self.u, self.obstacle.displacement(self.factor), self.comm,
                                    self.obstacle.track)
        return change > self.relag_tol

    def check_start(self) -> None:
        """ContactError if the body already penetrates the obstacle in its initial state."""
        X = self.outputs.boundary.X
        g = self.obstacle.gap_np(X, self.obstacle.displacement(self.factor))
        gmin = self.comm.allreduce(float(g.min()) if g.size else np.inf, op=MPI.MIN)
        scale = self.comm.allreduce(float(np.ptp(X)) if g.size else 0.0, op=MPI.MAX)
        if gmin < -1e-9 * max(scale, 1.0):
            raise ContactError(f"boundary {self.boundary!r} starts inside the obstacle (gap {gmin:.3g} "
                               "< 0): move the obstacle away from the body")

    # -- results: the outputs' (contact/outputs.py; every one collective) ----------------------------
    nodes = delegate("outputs.boundary.nodes", "The contact boundary's owned nodes (numbering of the "
                     "displacement's blocked dofs).")
    node_sdof = delegate("outputs.fields.node_sdof", "The dof of the boundary fields (``pressure``, "
                         "``shear``) at each of ``nodes`` (-1: none).")
    force = tracked("outputs.force")
    lag_force = tracked("outputs.lag_force")
    pressure = tracked("outputs.pressure")
    shear = tracked("outputs.shear")
    update_fields = tracked("outputs.update_fields")
    boundary_values = tracked("outputs.boundary_values")
    profile = tracked("outputs.profile")
    peak_pressure = tracked("outputs.peak_pressure")
    stick_slip = tracked("outputs.stick_slip")
    zone_edges = tracked("outputs.zone_edges")
    zone = tracked("outputs.zone")
    meridian = tracked("outputs.meridians.meridian")
    radius = tracked("outputs.meridians.radius")

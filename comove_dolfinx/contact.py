"""Unilateral contact of a body with rigid obstacles: penalty or Nitsche, lagged Coulomb friction.

Conventions (theory.md section 5)
---------------------------------
* An obstacle gives, for the current position x = X + u of a boundary point, the signed gap g (>= 0
  when separate, < 0 when penetrating) and its unit normal n_o pointing from the obstacle into the
  body's side; the tangent is t_o = (-n_o[1], n_o[0]).
* Tractions on the body are per unit reference area (and per unit reference thickness in plane stress):
  contact traction = p n_o + q t_o with the pressure p >= 0.
* Penalty:  p = gamma [-g]_+,  gamma = gamma0 E / h (h the cell diameter).
* Nitsche (theta = 1, 0, -1), with the nominal normal traction of the current stress
  p(u) = n_o . (P N), P = J sigma F^-T:
      R_n = -(theta/gamma) int p(u) p'(u; v) + (1/gamma) int [p(u) - gamma g]_+ (theta p'(u; v) - gamma n_o.v)
  which reduces to the exact traction term -int p n_o.v whenever p = [p - gamma g]_+.
* Friction, Coulomb with the pressure lagged (Shang & Chen's scheme): the slip threshold s = mu p_lag
  uses the pressure of a lag state (u_lag, d_lag): the body and the obstacle as they stood at the last
  converged increment, or at the last pass within the increment when ``relag`` asks for true Coulomb.
  (The obstacle must be taken where it stood: the body's old position against the obstacle's new one
  would read the increment's whole approach as pressure.) Slip increment ds = t_o . ((u - u_n) - (d - d_n))
  relative to the obstacle's own motion d. With P_s(x) = x for |x| <= s, s sign(x) otherwise:
      penalty:  q = -P_s(gamma (e_n + ds)),   R_t = int P_s(gamma (e_n + ds)) t_o.v
                e_n, the elastic (stick) part of the tangential slip, is the friction history: a
                boundary field (lumped projection at each converged increment of P_s(...)/gamma);
      Nitsche:  q = P_s(q(u) - gamma ds), q(u) = t_o . (P N),
                R_t = -(theta/gamma) int q(u) q'(u; v) + (1/gamma) int P_s(q(u) - gamma ds)(theta q'(u; v) - gamma t_o.v)
                (no history: the stick traction lives in the stress).
  Stick is regularised by the same gamma (penalty) or weakly enforced (Nitsche).

The contact force is taken from the residual: F . e = -R_c(u; e) for the constant fields e = e_x, e_y.
The contact extent is measured where the method acts: the current length of the boundary over which the
pressure is positive at the facet quadrature points (``FACET_DEGREE``: 4 Gauss points per facet).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import ufl
from dolfinx import fem
from mpi4py import MPI
from petsc4py import PETSc

from . import compat

METHODS = ("penalty", "nitsche")
FACET_DEGREE = 7


class ContactError(ValueError):
    """Unusable contact input (the message names the value and the fix)."""


# ------------------------------------------------------------------------------------------------
# Rigid obstacles
# ------------------------------------------------------------------------------------------------
class Obstacle:
    """A rigid obstacle, fixed or translated rigidly by motion(t) (t the load factor)."""

    def __init__(self, motion=None):
        self.motion = motion
        self._d = None

    def displacement(self, t: float) -> np.ndarray:
        """Rigid displacement of the obstacle at load factor t."""
        if self.motion is None:
            return np.zeros(2)
        if callable(self.motion):
            return np.asarray(self.motion(t), dtype=float)
        return t * np.asarray(self.motion, dtype=float)

    def bind(self, mesh) -> None:
        if self._d is None:
            self._d = fem.Constant(mesh, PETSc.ScalarType((0.0, 0.0)))

    def set_load(self, t: float) -> None:
        self._d.value = self.displacement(t)

    # UFL (current position x; d the obstacle's displacement, default the current one) and NumPy
    # (positions (N, 2), load factor t) versions
    def gap(self, x, d=None):  # pragma: no cover - interface
        raise NotImplementedError

    def normal(self, x, d=None):  # pragma: no cover - interface
        raise NotImplementedError

    def gap_np(self, x: np.ndarray, t: float) -> np.ndarray:  # pragma: no cover - interface
        raise NotImplementedError


class Plane(Obstacle):
    """The rigid half-plane {(x - point) . normal <= 0}; ``normal`` points towards the body."""

    def __init__(self, point, normal, motion=None):
        super().__init__(motion)
        self.point = np.asarray(point, dtype=float)
        n = np.asarray(normal, dtype=float)
        if np.linalg.norm(n) == 0:
            raise ContactError("the plane's normal must not be zero")
        self.n = n / np.linalg.norm(n)

    def gap(self, x, d=None):
        d = self._d if d is None else d
        return ufl.dot(x - ufl.as_vector(self.point) - d, ufl.as_vector(self.n))

    def normal(self, x, d=None):
        return ufl.as_vector(self.n)

    def gap_np(self, x, t):
        return (x - self.point - self.displacement(t)) @ self.n


class Circle(Obstacle):
    """A rigid disc (cylinder) of radius ``radius``; the body is outside it."""

    def __init__(self, center, radius, motion=None):
        super().__init__(motion)
        if not radius > 0:
            raise ContactError(f"radius = {radius}: the obstacle's radius must be > 0")
        self.center = np.asarray(center, dtype=float)
        self.radius = float(radius)

    def _rel(self, x, d):
        return x - ufl.as_vector(self.center) - (self._d if d is None else d)

    def gap(self, x, d=None):
        r = self._rel(x, d)
        return ufl.sqrt(ufl.dot(r, r)) - self.radius

    def normal(self, x, d=None):
        r = self._rel(x, d)
        return r / ufl.sqrt(ufl.dot(r, r))

    def gap_np(self, x, t):
        return np.linalg.norm(x - self.center - self.displacement(t), axis=1) - self.radius


def _pos(x):
    """[x]_+, active at x = 0: a body that just touches gets contact stiffness at once."""
    return ufl.conditional(ufl.ge(x, 0.0), x, 0.0)


def _clip(x, s):
    """P_s(x), the projection onto [-s, s]; |x| = s counts as stick, so with s = 0 (no pressure
    yet) a zero slip keeps the stick stiffness instead of a singular tangent."""
    return ufl.conditional(ufl.le(abs(x), s), x, s * ufl.sign(x))


@dataclass
class ZoneInfo:
    """The contact set in the current configuration."""

    extent: float              # length in contact along the boundary (current configuration)
    max_penetration: float     # largest -g over the nodes of the contact boundary (0 if none)

    @property
    def in_contact(self) -> bool:
        return self.extent > 0.0


class Contact:
    """Contact of the tagged boundary ``boundary`` with ``obstacle``.

    Parameters
    ----------
    method:
        "penalty" or "nitsche".
    gamma0:
        Dimensionless weight; gamma = gamma0 E / h.
    theta:
        Nitsche variant: 1 (symmetric), 0, -1 (skew-symmetric).
    mu:
        Coulomb friction coefficient (0: frictionless).
    relag:
        False: the pressure of the last converged increment sets the slip threshold (Shang & Chen);
        True: the increment is re-solved with the threshold from its own solution until the pressure
        stops changing (true Coulomb), at most ``max_passes`` passes.
    """

    def __init__(self, boundary: str, obstacle: Obstacle, method: str = "penalty",
                 gamma0: float = 100.0, theta: float = 0.0, mu: float = 0.0, relag: bool = False,
                 max_passes: int = 10, relag_tol: float = 1e-4):
        if method not in METHODS:
            raise ContactError(f"contact method {method!r} is unknown: choose penalty or nitsche")
        if not gamma0 > 0:
            raise ContactError(f"gamma0 = {gamma0} must be > 0")
        if theta not in (1, 0, -1):
            raise ContactError(f"theta = {theta}: Nitsche's variant is 1, 0 or -1")
        if mu < 0:
            raise ContactError(f"mu = {mu}: the friction coefficient must be >= 0")
        self.boundary, self.obstacle, self.method = boundary, obstacle, method
        self.gamma0, self.theta, self.mu = gamma0, theta, mu
        self.relag, self.max_passes, self.relag_tol = relag, max_passes, relag_tol
        self.t = self.t_n = 0.0

    # -- model hooks -----------------------------------------------------------------------------
    def residual(self, model):
        """The contact terms of the residual (UFL, linear in model.v); builds the output forms."""
        msh = model.mesh
        self.model = model
        self.obstacle.bind(msh)
        self._d_n = fem.Constant(msh, PETSc.ScalarType((0.0, 0.0)))     # obstacle at the last increment
        self._d_lag = fem.Constant(msh, PETSc.ScalarType((0.0, 0.0)))   # obstacle in the lag state
        self._d_n.value = self._d_lag.value = self.obstacle.displacement(self.t_n)
        tdim = msh.topology.dim
        DG0 = compat.function_space(msh, "DG", 0)
        self.h = fem.Function(DG0, name="cell_size")
        ncell = msh.topology.index_map(tdim).size_local + msh.topology.index_map(tdim).num_ghosts
        cells = np.arange(ncell, dtype=np.int32)
        self.h.x.array[compat.cell_dofs(DG0, ncell)[:, 0]] = compat.cell_sizes(msh, cells)
        self.u_lag = fem.Function(model.V, name="u_lag")
        # a Constant, so that scenes differing only in gamma0 share the compiled forms
        gamma0E = fem.Constant(msh, PETSc.ScalarType(self.gamma0 * model.elastic.E))
        gamma = gamma0E / self.h
        self.gamma = gamma
        u, v, u_n = model.u, model.v, model.u_n
        x = model.x + u
        g = self.obstacle.gap(x)
        n_o = self.obstacle.normal(x)
        t_o = ufl.as_vector([-n_o[1], n_o[0]])
        w = model.kin.weight()
        dsc = model.ds(model.meshdata.ds_id(self.boundary),
                       metadata={"quadrature_degree": FACET_DEGREE})
        self.ds_c, self.w = dsc, w
        th = self.theta
        if self.method == "penalty":
            p = gamma * _pos(-g)
            Rn = -p * ufl.dot(n_o, v)
        else:
            N = ufl.FacetNormal(msh)
            PN = model.nominal_traction(N)
            p_u = ufl.dot(n_o, PN)
            p = _pos(p_u - gamma * g)
            dp = ufl.derivative(p_u, u, v)
            Rn = (-th / gamma * p_u * dp if th else 0) + p / gamma * (th * dp - gamma * ufl.dot(n_o, v))
        self.p_ref = p                                           # pressure per reference area
        R = Rn
        self.q_ref = None
        if self.mu > 0:
            # the lag state: the body at u_lag against the obstacle where it stood then (d_lag)
            x_lag, d_lag = model.x + self.u_lag, self._d_lag
            g_lag = self.obstacle.gap(x_lag, d_lag)
            if self.method == "penalty":
                p_lag = gamma * _pos(-g_lag)
            else:
                N = ufl.FacetNormal(msh)
                p_lag = _pos(ufl.dot(self.obstacle.normal(x_lag, d_lag),
                                     model.nominal_traction(N, self.u_lag)) - gamma * g_lag)
            s = self.mu * p_lag
            slip = ufl.dot(t_o, (u - u_n) - (self.obstacle._d - self._d_n))
            if self.method == "penalty":
                self.e_n = fem.Function(compat.function_space(msh, "Lagrange", model.degree),
                                        name="stick_slip")
                trial = gamma * (self.e_n + slip)
                q_tr = _clip(trial, s)
                self.q_ref = -q_tr
                self._e_new = q_tr / gamma
                R = R + q_tr * ufl.dot(t_o, v)
            else:
                q_u = ufl.dot(t_o, PN)
                trial = q_u - gamma * slip
                q = _clip(trial, s)
                dq = ufl.derivative(q_u, u, v)
                self.q_ref = q
                R = R + (-th / gamma * q_u * dq if th else 0) + q / gamma * (th * dq - gamma * ufl.dot(t_o, v))
            self._p_lag = p_lag
            self._slipping = ufl.gt(abs(trial), s)       # where the friction law slips
        self.R_c = R * w * dsc
        self._build_outputs(model, n_o, t_o)
        return self.R_c

    def set_load(self, t: float) -> None:
        self.t = t
        self.obstacle.set_load(t)

    def commit(self, model) -> None:
        """Called before the model's own state moves to the new increment (u_n still the old one)."""
        if self.mu > 0 and self.method == "penalty":
            vals = self._assemble_vec(self._form("e"))
            m = self._lumped
            b = self._sdofs             # the boundary's nodes (elsewhere m is round-off)
            self.e_n.x.array[b] = vals[b] / m[b]
            self.e_n.x.scatter_forward()
        self.t_n = self.t
        self._d_n.value = self.obstacle.displacement(self.t)
        self._d_lag.value = self._d_n.value
        self.u_lag.x.array[:] = model.u.x.array

    def restore(self, model) -> None:
        self.u_lag.x.array[:] = model.u_n.x.array
        self._d_lag.value = self._d_n.value

    def relag_pass(self, model) -> bool:
        """True Coulomb: take the threshold from the current solution; True if it changed notably."""
        if not (self.relag and self.mu > 0):
            return False
        p_old = self._assemble_vec(self._form("p_lag"))
        self.u_lag.x.array[:] = model.u.x.array
        self._d_lag.value = self.obstacle.displacement(self.t)
        p_new = self._assemble_vec(self._form("p_lag"))
        scale = max(np.abs(p_new).max(), 1e-300)
        change = model.comm.allreduce(float(np.abs(p_new - p_old).max()) / scale, op=MPI.MAX)
        return change > self.relag_tol

    # -- results -----------------------------------------------------------------------------------
    def _build_outputs(self, model, n_o, t_o):
        """The forms of the results (compiled on first use: a run that never asks for one does not
        pay its compilation)."""
        msh = model.mesh
        e = fem.Constant(msh, PETSc.ScalarType((0.0, 0.0)))
        self._e = e
        S = compat.function_space(msh, "Lagrange", model.degree)
        phi = ufl.TestFunction(S)
        F = model.update.F(model.u)
        N = ufl.FacetNormal(msh)
        N3 = ufl.as_vector([N[0], N[1], 0.0])
        stretch = ufl.sqrt(ufl.dot(ufl.det(F) * ufl.inv(F).T * N3, ufl.det(F) * ufl.inv(F).T * N3))
        # current length of the contact set: in-plane stretch of the boundary where p > 0
        F2 = ufl.Identity(2) + ufl.grad(model.u)
        T = ufl.as_vector([-N[1], N[0]])
        chi = ufl.conditional(ufl.gt(self.p_ref, 0.0), 1.0, 0.0)
        dsc = self.ds_c
        self._ufl = {"force": -ufl.replace(self.R_c, {model.v: e}), "mass": phi * dsc,
                     "extent": chi * ufl.sqrt(ufl.dot(F2 * T, F2 * T)) * dsc,
                     "p": self.p_ref / stretch * phi * dsc}
        if self.mu > 0:
            # reference length of the contact set that slips (friction at its threshold) and sticks
            slipping = ufl.conditional(self._slipping, 1.0, 0.0)
            self._ufl.update(slip=chi * slipping * dsc, stick=chi * (1.0 - slipping) * dsc,
                             q=self.q_ref / stretch * phi * dsc, p_lag=self._p_lag * phi * dsc)
            if self.method == "penalty":
                self._ufl["e"] = self._e_new * phi * dsc
        self._compiled = {}
        self.pressure = fem.Function(S, name="contact_pressure")
        self.shear = fem.Function(S, name="contact_shear")
        self._vec = compat.create_vector(self._form("mass"))
        self._lumped = self._assemble_vec(self._form("mass"))
        # nodes of the contact boundary (owned), for the contact zone
        fdim = msh.topology.dim - 1
        ft = model.meshdata.facet_tags
        facets = ft.indices[ft.values == model.meshdata.ds_id(self.boundary)]
        dofs = fem.locate_dofs_topological(model.V.sub(0), fdim, facets)   # unrolled indices of V
        nodes = np.unique(dofs // model.V.dofmap.index_map_bs)
        self._nodes = nodes[nodes < model.V.dofmap.index_map.size_local]   # owned nodes only
        self._X = model.V.tabulate_dof_coordinates()[self._nodes, :2]
        sdofs = fem.locate_dofs_topological(S, fdim, facets)
        self._sdofs = sdofs[sdofs < S.dofmap.index_map.size_local]

    def _form(self, name: str):
        """The compiled form ``name`` (collective: every rank asks for it at the same point)."""
        if name not in self._compiled:
            self._compiled[name] = fem.form(self._ufl[name])
        return self._compiled[name]

    def _assemble_vec(self, form) -> np.ndarray:
        """Owned entries of an assembled linear form on the boundary field space."""
        compat.assemble_vector(self._vec, form)
        return self._vec.array.copy()

    def check_start(self) -> None:
        """ContactError if the body already penetrates the obstacle in its initial state."""
        g = self.obstacle.gap_np(self._X, self.t)
        gmin = self.model.comm.allreduce(float(g.min()) if g.size else np.inf, op=MPI.MIN)
        scale = self.model.comm.allreduce(float(np.ptp(self._X)) if g.size else 0.0, op=MPI.MAX)
        if gmin < -1e-9 * max(scale, 1.0):
            raise ContactError(f"boundary {self.boundary!r} starts inside the obstacle (gap {gmin:.3g} "
                               "< 0): move the obstacle away from the body")

    def force(self) -> np.ndarray:
        """Total force of the obstacle on the body (x, y), from the residual's contact term."""
        out = np.zeros(2)
        for i in range(2):
            self._e.value = np.eye(2)[i]
            out[i] = self.model.comm.allreduce(fem.assemble_scalar(self._form("force")), op=MPI.SUM)
        return out

    def update_fields(self) -> None:
        """Contact pressure and tangential traction (per current area) as boundary fields."""
        m = self._lumped
        b = self._sdofs
        for name, f in (("p", self.pressure), ("q", self.shear)):
            if name not in self._ufl:
                continue
            vals = self._assemble_vec(self._form(name))
            f.x.array[:] = 0.0
            f.x.array[b] = vals[b] / m[b]
            f.x.scatter_forward()

    def boundary_values(self, f: fem.Function) -> tuple[np.ndarray, np.ndarray]:
        """(reference coordinates, values) of a scalar output field (e.g. ``pressure``) at every node
        of the contact boundary, gathered on all ranks."""
        X = f.function_space.tabulate_dof_coordinates()[self._sdofs, :2]
        comm = self.model.comm
        return (np.concatenate(comm.allgather(X)),
                np.concatenate(comm.allgather(f.x.array[self._sdofs])))

    def stick_slip(self) -> tuple[float, float]:
        """Reference lengths of the contact set where friction sticks and where it slips (zeros
        without friction), at the current iterate."""
        if "slip" not in self._ufl:
            return 0.0, 0.0
        comm = self.model.comm
        return tuple(comm.allreduce(fem.assemble_scalar(f), op=MPI.SUM)
                     for f in (self._form("stick"), self._form("slip")))

    def zone(self) -> ZoneInfo:
        """Contact extent (from the facet quadrature points) and the largest nodal penetration."""
        comm = self.model.comm
        extent = comm.allreduce(fem.assemble_scalar(self._form("extent")), op=MPI.SUM)
        x = self._X + self.model.u.x.array.reshape(-1, 2)[self._nodes]
        g = self.obstacle.gap_np(x, self.t)
        pen = comm.allreduce(float(max(-g.min(), 0.0)) if g.size else 0.0, op=MPI.MAX)
        return ZoneInfo(float(extent), pen)

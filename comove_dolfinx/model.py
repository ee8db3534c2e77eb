"""The finite-element model: spaces, quadrature state, loads, residual and its exact Jacobian.

Equilibrium is written on the reference mesh (the co-moving coordinates) with the nominal stress
P = J sigma F^-T (theory.md section 2), sigma coming from the stress update of ``updates.py`` and,
for elastic-plastic materials, the return map of ``materials.py`` at the quadrature points:

    R(u; v) = int P : Grad3 v  w dX  - (external work)  + (boundary terms, e.g. contact) = 0,

w = 2 pi r (axisymmetry) or the thickness b. The Jacobian is exact: the geometric part comes from UFL
differentiation of P at fixed sigma, the material part from UFL differentiation of the trial stress,
mapped by the return map's derivative D = d sigma / d sigma_trial (identity for elastic materials,
where UFL differentiates the update directly).

Loads scale with the load factor t of ``set_load``; follower pressure acts on the current face
(Nanson: t da = -p J F^-T N dA), dead tractions on the reference face. In plane stress, face loads
are per unit reference thickness.

Quadrature state (4-vectors xx, yy, zz, xy; see kinematics.py): ``sigma_n`` the converged stress of
increment n (for the polar update, the unrotated stress), ``sigma`` the stress at the current iterate,
``p_n``/``p`` the equivalent plastic strain, ``D`` (4x4) the return map's derivative.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import ufl
from dolfinx import fem
from mpi4py import MPI
from petsc4py import PETSc
from ufl.algorithms import expand_derivatives

from . import compat
from . import materials as mat
from . import materials_ufl as mat_ufl
from .kinematics import PLANE_STRESS, Kinematics, to_tensor, to_vec
from .parallel import agree
from .quadrature import CellInterpolator, QuadratureRule
from .updates import make_update


class InvertedElement(RuntimeError):
    """det F <= 0 at a quadrature point: the iterate is not admissible."""


class ReturnMapFailure(RuntimeError):
    """The constitutive update could not be evaluated (e.g. S-R split beyond 90 degrees)."""


@dataclass
class Plasticity:
    """An elastic-plastic material: ``law`` is "j2" (return mapping) or "chen" (Chen's rate law)."""

    hardening: mat.Hardening
    law: str = "j2"

    def __post_init__(self):
        if self.law not in ("j2", "chen"):
            raise ValueError(f"unknown plasticity law {self.law!r}: choose j2 or chen")


@dataclass
class _Ramp:
    """A value that scales with the load factor: value(t) = t * scale (or a callable of t)."""

    constant: fem.Constant
    scale: object

    def set(self, t: float) -> None:
        val = self.scale(t) if callable(self.scale) else np.asarray(self.scale) * t
        self.constant.value = val


@dataclass
class _FieldRamp:
    """A displacement field that moves with the load factor: g = displacement(x, t)."""

    function: fem.Function
    displacement: object

    def set(self, t: float) -> None:
        self.function.interpolate(lambda x: self.displacement(x, t))
        self.function.x.scatter_forward()


@dataclass
class _Dirichlet:
    name: str
    component: int | None
    ramp: _Ramp | None
    bc: object = field(repr=False)


class Model:
    """A 2D body on a Gmsh mesh with named facet tags.

    Parameters
    ----------
    meshdata:
        :class:`geometry.MeshData` (mesh, facet tags and their names).
    kind:
        "plane_strain", "plane_stress" or "axisymmetric".
    elastic:
        :class:`materials.Elastic`.
    update:
        Stress update name (see updates.py); default the S-R update.
    plasticity:
        ``None`` for an elastic body, else :class:`Plasticity`.
    degree:
        Lagrange degree of the displacement (2 by default; 1 locks in bending).
    quadrature_degree:
        Degree of the quadrature rule of the volume integrals (2: three points, exact stiffness of P2
        small-strain elasticity; axisymmetry needs 3 for the weight r).
    thickness:
        Out-of-plane thickness of plane models.
    """

    def __init__(self, meshdata, kind: str, elastic: mat.Elastic, update: str = "sr",
                 plasticity: Plasticity | None = None, degree: int = 2,
                 quadrature_degree: int | None = None, thickness: float = 1.0):
        self.meshdata = meshdata
        self.mesh = msh = meshdata.mesh
        self.comm = msh.comm
        self.elastic = elastic
        self.plasticity = plasticity
        if degree not in (1, 2):
            raise ValueError(f"degree = {degree}: use 1 or 2")
        self.degree = degree
        self.x = ufl.SpatialCoordinate(msh)
        self.kin = Kinematics(kind, self.x, thickness)
        if quadrature_degree is None:
            quadrature_degree = 2 * (degree - 1) + (1 if self.kin.axisymmetric else 0)
            quadrature_degree = max(quadrature_degree, 1 if degree == 1 else 2)
        self.rule = QuadratureRule(msh, quadrature_degree)
        self.update = make_update(update, self.kin, elastic)
        if plasticity is not None and not self.update.rotates:
            raise ValueError(f"update {update!r} cannot carry plasticity: use sr or hughes_winget")

        self.V = compat.function_space(msh, "Lagrange", degree, (2,))
        self.u = fem.Function(self.V, name="displacement")
        self.u_n = fem.Function(self.V, name="displacement_n")
        self.du = fem.Function(self.V, name="newton_correction")
        self.v = ufl.TestFunction(self.V)
        self.u_trial = ufl.TrialFunction(self.V)

        r = self.rule
        self.sigma_n = r.function((4,), "sigma_n")
        self.sigma = r.function((4,), "sigma")
        self.p_n = r.function((), "p_n") if plasticity else None
        self.p = r.function((), "p") if plasticity else None
        self.D = r.function((4, 4), "D") if plasticity else None
        self.D_rot = r.function((4, 4), "D_rot") if plasticity and plasticity.law == "chen" else None
        # plane-stress plasticity: the thickness stretch is state, F22 = F22_n exp(ezz), with the
        # derivatives of ezz with respect to the trial and the rotated old stress (materials.py)
        self.F22_n = self.F22_q = self.G_tr = self.G_rot = None
        if plasticity and kind == PLANE_STRESS:
            self.F22_n = r.function((), "F22_n", 1.0)
            self.F22_q = r.function((), "F22", 1.0)
            self.G_tr = r.function((4,), "dezz_dtr")
            self.G_rot = r.function((4,), "dezz_drot")

        self.ds = ufl.Measure("ds", domain=msh, subdomain_data=meshdata.facet_tags)
        self._dirichlet: list[_Dirichlet] = []
        self._ramps: list[_Ramp] = []
        self._external = []                # UFL integrands (already with ds)
        self.boundary_terms = []           # objects with residual(model), set_load, commit, restore
        self.load = 0.0
        self._compiled = False
        self._facet: dict = {}             # DG copies of quadrature data, for facet integrals

    # ----------------------------------------------------------------------------------------
    # Boundary conditions and loads (before finalize)
    # ----------------------------------------------------------------------------------------
    def _facets(self, name: str) -> np.ndarray:
        ft = self.meshdata.facet_tags
        return ft.indices[ft.values == self.meshdata.ds_id(name)]

    def fix(self, name: str, component: int | None = None, value=None) -> None:
        """Dirichlet condition on a tagged boundary: u (or u[component]) = t * value (default 0)."""
        facets = self._facets(name)
        fdim = self.mesh.topology.dim - 1
        if component is None:
            dofs = fem.locate_dofs_topological(self.V, fdim, facets)
            c = fem.Constant(self.mesh, PETSc.ScalarType((0.0, 0.0)))
            bc = fem.dirichletbc(c, dofs, self.V)
        else:
            dofs = fem.locate_dofs_topological(self.V.sub(component), fdim, facets)
            c = fem.Constant(self.mesh, PETSc.ScalarType(0.0))
            bc = fem.dirichletbc(c, dofs, self.V.sub(component))
        ramp = None if value is None else _Ramp(c, value)
        if ramp:
            self._ramps.append(ramp)
        self._dirichlet.append(_Dirichlet(name, component, ramp, bc))

    def prescribe(self, name: str, displacement, component: int | None = None) -> None:
        """Dirichlet condition u = displacement(x, t) (or u[component]) on a tagged boundary: a
        field, ``displacement(x, t)`` returning (2, N) values (or (N,) for a component) at the points
        x (3, N) for load factor t."""
        facets = self._facets(name)
        fdim = self.mesh.topology.dim - 1
        if component is None:
            g = fem.Function(self.V)
            dofs = fem.locate_dofs_topological(self.V, fdim, facets)
            bc = fem.dirichletbc(g, dofs)
        else:
            Vc = self.V.sub(component).collapse()[0]
            g = fem.Function(Vc)
            dofs = fem.locate_dofs_topological((self.V.sub(component), Vc), fdim, facets)
            bc = fem.dirichletbc(g, dofs, self.V.sub(component))
        ramp = _FieldRamp(g, displacement)
        self._ramps.append(ramp)
        self._dirichlet.append(_Dirichlet(name, component, ramp, bc))

    def reaction_forces(self, name: str) -> tuple[np.ndarray, np.ndarray]:
        """Reference positions (n, 2) and forces (n, 2) that the supports exert on the nodes of a
        tagged boundary (this rank's owned nodes), taken from the residual at the current state:
        at a constrained dof R = f_int - f_ext is the force the support must supply."""
        b = compat.create_vector(self.residual_form)
        compat.assemble_vector(b, self.residual_form)
        fdim = self.mesh.topology.dim - 1
        dofs = fem.locate_dofs_topological(self.V.sub(0), fdim, self._facets(name))
        bs = self.V.dofmap.index_map_bs
        nodes = np.unique(dofs // bs)
        nodes = nodes[nodes < self.V.dofmap.index_map.size_local]
        f = b.array.reshape(-1, bs)[nodes].copy()
        b.destroy()
        return self.V.tabulate_dof_coordinates()[nodes, :2], f

    def reaction(self, name: str) -> np.ndarray:
        """Total force (x, y) that the supports exert on a tagged boundary (all ranks)."""
        return self.comm.allreduce(self.reaction_forces(name)[1].sum(axis=0), op=MPI.SUM)

    def follower_pressure(self, name: str, magnitude) -> fem.Constant:
        """Pressure t * magnitude on the current face of a tagged boundary (pushes into the body)."""
        p = fem.Constant(self.mesh, PETSc.ScalarType(0.0))
        self._ramps.append(_Ramp(p, magnitude))
        N = ufl.FacetNormal(self.mesh)
        N3 = ufl.as_vector([N[0], N[1], 0.0])
        F = self.update.F(self.u)          # in plane stress: per unit reference thickness
        cof = ufl.det(F) * ufl.inv(F).T
        v3 = ufl.as_vector([self.v[0], self.v[1], 0.0])
        self._external.append(-p * ufl.dot(cof * N3, v3) * self.kin.weight()
                              * self.ds(self.meshdata.ds_id(name)))
        return p

    def dead_traction(self, name: str, vector) -> fem.Constant:
        """Traction t * vector per unit reference area of a tagged boundary (fixed direction)."""
        T = fem.Constant(self.mesh, PETSc.ScalarType((0.0, 0.0)))
        self._ramps.append(_Ramp(T, vector))
        self._external.append(ufl.dot(T, self.v) * self.kin.weight()
                              * self.ds(self.meshdata.ds_id(name)))
        return T

    # ----------------------------------------------------------------------------------------
    # Forms
    # ----------------------------------------------------------------------------------------
    @property
    def bcs(self) -> list:
        return [d.bc for d in self._dirichlet]

    def thickness_stretch(self, up):
        """F22 used in P: plane stress closed form (elastic), stored state (plastic), else None."""
        if self.kin.model != PLANE_STRESS:
            return None
        if self.F22_q is not None:
            return self.F22_q
        return up.F22

    def finalize(self, jit_options: dict | None = None) -> None:
        """Build and compile the residual, the Jacobian and the stress evaluation (once)."""
        u, v, dx = self.u, self.v, self.rule.dx
        up = self.update.build(u, self.u_n, self.sigma_n)
        self._update_expr = up
        F22 = self.thickness_stretch(up)
        F = self.kin.F3(u, F22) if F22 is not None else self.kin.F3(u)
        self.F = F
        J = ufl.det(F)
        w = self.kin.weight()
        P = J * to_tensor(self.sigma) * ufl.inv(F).T
        R = ufl.inner(P, self.kin.grad3(v)) * w * dx
        self._internal, self._internal_form = (R, jit_options), None
        for ext in self._external:
            R = R - ext
        for term in self.boundary_terms:
            R = R + term.residual(self)
        # Jacobian: the geometric part (UFL, sigma held), the material part d sigma = D d sigma_tr
        # (+ D_rot d sigma_rot) and, in plane-stress plasticity, the thickness stretch's part
        # dF22 = F22 (G_tr . d sigma_tr + G_rot . d sigma_rot)
        dsig_tr = to_vec(ufl.derivative(up.sigma, u, self.u_trial))
        dsig = to_tensor(dsig_tr)
        if self.plasticity is not None:
            dsig_rot = to_vec(ufl.derivative(up.sigma_rot, u, self.u_trial))
            dvec = ufl.dot(self.D, dsig_tr)
            if self.D_rot is not None:
                dvec = dvec + ufl.dot(self.D_rot, dsig_rot)
            dsig = to_tensor(dvec)
        Jac = ufl.derivative(R, u, self.u_trial) + \
            ufl.inner(J * dsig * ufl.inv(F).T, self.kin.grad3(v)) * w * dx
        if self.F22_q is not None:
            # the direction of a derivative must be free of unevaluated derivatives
            dF22 = expand_derivatives(self.F22_q * (ufl.dot(self.G_tr, dsig_tr)
                                                    + ufl.dot(self.G_rot, dsig_rot)))
            Jac = Jac + ufl.derivative(ufl.inner(P, self.kin.grad3(v)) * w * dx, self.F22_q, dF22)
        self.residual_form = compat.form(R, jit_options)
        self.jacobian_form = compat.form(Jac, jit_options)
        # Everything the constitutive stage needs, in one evaluation per iteration
        parts = [to_vec(up.sigma)]
        if self.plasticity is not None:
            parts.append(to_vec(up.sigma_rot))
        if up.state_new is not None:
            parts.append(up.state_new)
        self._n_parts = len(parts)
        Fu = self.update.F(u)
        parts.append(ufl.as_vector([ufl.det(Fu)]))
        self._eval = self.rule.expression(ufl.as_vector([c for p in parts for c in p]))
        self._state_new = None if up.state_new is None else np.zeros((self.rule.size, 4))
        self._compiled = True
        self.set_load(0.0)

    @property
    def internal_force_form(self):
        """The internal force vector F_int = int P : Grad v (without loads and contact terms),
        compiled on first use: its norm is the force scale of the "force" convergence test."""
        if self._internal_form is None:
            R, jit = self._internal
            self._internal_form = compat.form(R, jit)
        return self._internal_form

    def nominal_traction(self, N, u=None):
        """In-plane components of P N on facets, P = J sigma F^-T at displacement u (default the
        current one), for Nitsche terms. Facet integrals cannot see quadrature functions, so the
        constitutive update is evaluated at the facet's points as a UFL function of u: the stress
        update's trial stress from the converged state of the last increment (carried by cell-wise
        DG fits, exact for DG1 and the 3-point rule), and for elastic-plastic bodies the return map
        of materials_ufl with the converged plastic strain (and thickness stretch). Everything that
        varies within an increment is a function of u, so the facet term's Jacobian is exact, and
        the traction at a lag state u_lag depends on u_lag and committed state only."""
        u = self.u if u is None else u
        up = self.update.build(u, self.u_n, self._facet_state("sigma_n"))
        sig, F22 = up.sigma, up.F22
        plast = self.plasticity
        if plast is not None:
            p_n = ufl.max_value(self._facet_state("p_n"), 0.0)     # the fit may dip below 0
            e, hard = self.elastic, plast.hardening
            if plast.law == "chen":
                sig = mat_ufl.chen_update(up.sigma_rot, up.sigma, p_n, e, hard, self.kin.model)
            elif self.kin.model == PLANE_STRESS:
                sig = mat_ufl.j2_return_plane_stress(up.sigma, p_n, e, hard)
            else:
                sig = mat_ufl.j2_return(up.sigma, p_n, e, hard)
            if self.kin.model == PLANE_STRESS:
                ezz = mat_ufl.plane_stress_thickness(sig, up.sigma, up.sigma_rot, e)
                F22 = self._facet_state("F22_n") * ufl.exp(ezz)
        F = self.kin.F3(u, F22) if self.kin.model == PLANE_STRESS else self.kin.F3(u)
        PN = ufl.det(F) * sig * ufl.inv(F).T * ufl.as_vector([N[0], N[1], 0.0])
        return ufl.as_vector([PN[0], PN[1]])

    def _facet_state(self, name: str):
        """DG function holding a cell-wise fit of the converged quadrature state ``name`` (created
        on first use, refreshed at each commit): "sigma_n" (4-vector), "p_n", "F22_n" (scalars)."""
        if name not in self._facet:
            shape = () if name in ("p_n", "F22_n") else (4,)
            V = compat.function_space(self.mesh, "DG", max(self.degree - 1, 0), shape)
            f = fem.Function(V, name=name + "_dg")
            if name == "F22_n":
                f.x.array[:] = 1.0
            self._facet[name] = (f, CellInterpolator(self.rule, f.function_space))
        return self._facet[name][0]

    def _fit_facet(self, name: str, values) -> None:
        """Refresh the DG copy of ``name`` if a facet term uses it."""
        if name in self._facet:
            f, interp = self._facet[name]
            interp(values, f)

    # ----------------------------------------------------------------------------------------
    # Load factor, constitutive evaluation, commit / restore
    # ----------------------------------------------------------------------------------------
    def set_load(self, t: float) -> None:
        """Set every ramped load, prescribed displacement and moving obstacle to load factor t."""
        self.load = t
        for r in self._ramps:
            r.set(t)
        for term in self.boundary_terms:
            term.set_load(t)

    def evaluate_stress(self) -> None:
        """Stress (and tangent) at every quadrature point for the current displacement iterate.

        Raises, on every rank when it happens on any: :class:`InvertedElement` if det F <= 0 at a
        point, :class:`ReturnMapFailure` if the update is not defined (NaN) or the return map fails.
        """
        err = None
        try:
            self._evaluate_local()
        except (InvertedElement, ReturnMapFailure) as e:
            err = e
        except Exception as e:                 # noqa: BLE001 - e.g. a return map that did not converge
            err = ReturnMapFailure(f"the constitutive update failed: {e}")
        agree(self.comm, err)

    def _evaluate_local(self) -> None:
        """The constitutive stage on this rank's points (no collective call)."""
        vals = self.rule.evaluate(self._eval)
        detF = vals[:, -1]
        if not np.all(np.isfinite(vals)):
            raise ReturnMapFailure("the stress update returned NaN (increment too large?)")
        if detF.size and detF.min() <= 0.0:
            raise InvertedElement(f"det F = {detF.min():.3g} <= 0 at a quadrature point")
        sig_tr = vals[:, 0:4]
        col = 4
        sig = self.rule.view(self.sigma)
        if self.plasticity is None:
            sig[:] = sig_tr
        else:
            sig_rot = vals[:, 4:8]
            col = 8
            self._plastic_update(sig_rot, sig_tr)
        if self._state_new is not None:
            self._state_new[:] = vals[:, col:col + 4]

    def _plastic_update(self, sig_rot, sig_tr) -> None:
        plast = self.plasticity
        kind = self.kin.model
        p_n = self.p_n.x.array
        D_rot = None
        if plast.law == "j2":
            sig, p, D, deps_p = mat.j2_return(sig_tr, p_n, self.elastic, plast.hardening, kind)
        else:
            sig, p, D, D_rot, deps_p = mat.chen_update(sig_rot, sig_tr, p_n, self.elastic,
                                                       plast.hardening, kind)
            self.rule.view(self.D_rot)[:] = D_rot
        self.rule.view(self.sigma)[:] = sig
        self.p.x.array[:] = p
        self.rule.view(self.D)[:] = D
        if self.F22_q is not None:
            ezz, dtr, drot = mat.plane_stress_thickness(sig, sig_tr, sig_rot, D, D_rot, self.elastic)
            self.F22_q.x.array[:] = self.F22_n.x.array * np.exp(ezz)
            self.rule.view(self.G_tr)[:] = dtr
            self.rule.view(self.G_rot)[:] = drot

    def commit(self) -> None:
        """Accept the current iterate as the converged state of the increment."""
        for term in self.boundary_terms:          # before u_n moves: they may need the increment
            term.commit(self)
        self.u_n.x.array[:] = self.u.x.array
        if self._state_new is not None:
            self.rule.view(self.sigma_n)[:] = self._state_new
        else:
            self.sigma_n.x.array[:] = self.sigma.x.array
        if self.plasticity is not None:
            self.p_n.x.array[:] = self.p.x.array
            if self.F22_q is not None:
                self.F22_n.x.array[:] = self.F22_q.x.array
        self._fit_facet("sigma_n", self.rule.view(self.sigma_n))
        if self.plasticity is not None:
            self._fit_facet("p_n", self.p_n.x.array)
            if self.F22_n is not None:
                self._fit_facet("F22_n", self.F22_n.x.array)

    def restore(self) -> None:
        """Return to the last converged state (after a failed increment)."""
        self.u.x.array[:] = self.u_n.x.array
        for term in self.boundary_terms:
            term.restore(self)

    # ----------------------------------------------------------------------------------------
    # Derived quantities
    # ----------------------------------------------------------------------------------------
    def cauchy_stress(self) -> np.ndarray:
        """Cauchy stress at the points of the current iterate, shape (points, 4)."""
        return self.rule.view(self.sigma)

    def num_dofs(self) -> int:
        imap = self.V.dofmap.index_map
        return imap.size_global * self.V.dofmap.index_map_bs

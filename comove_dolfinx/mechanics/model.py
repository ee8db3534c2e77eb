"""The finite-element model of a body and its items: spaces, state, residual and exact Jacobian.

Equilibrium is written on the reference mesh (the co-moving coordinates) with the nominal stress
P = J sigma F^-T = sigma cof F (docs/theory.md sections 1 and 5; kinematics.cofactor, a polynomial in F),
sigma from the stress update of updates.py and, for
elastic-plastic materials, the return map at the quadrature points (materials.py, state.py):

    R(u; v) = int P : Grad3 v  w dX  + (the items' terms: loads, contact) = 0,

w = 2 pi r (axisymmetry) or the thickness b. The Jacobian is exact: the geometric part sigma d(cof F)
at fixed sigma, the material part d sigma cof F from the update's derivative of the trial stress (in
closed form for the S-R update, UFL's derivative for the others: StressUpdate.directional), mapped
by the return map's derivative D = d sigma / d sigma_trial (identity for elastic materials;
applied from the stored stress and plastic strain in
plane strain and axisymmetry, stored by each evaluation in plane stress), and in plane-stress
plasticity the part of the thickness stretch, dF22 = F22 (G_tr . d sigma_tr + G_rot . d sigma_rot).
A Taylor test checks it (taylor.py, tests/test_taylor.py). Under linear kinematics (the update
"small_strain", whose ``geometric`` is False) P = sigma on the reference configuration and the
Jacobian has no geometric part (docs/theory.md section 3.5).

Items (loads.py, contact/) build their terms from a :class:`Context` handed to them once: data flows
from the model to the items, never back. The load factor t of ``set_load`` sets every item.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import ufl
from dolfinx import fem
from mpi4py import MPI
from petsc4py import PETSc
from ufl.algorithms import expand_derivatives

from .. import compat
from ..parallel import agree
from .body import Body
from . import return_maps_ufl as rm_ufl
from .kinematics import PLANE_STRESS, Kinematics, cofactor, to_tensor, to_vec
from .quadrature import QuadratureRule
from .state import FacetBase, InvertedElement, QuadratureState, ReturnMapFailure
from .updates import make_update

__all__ = ["Context", "InvertedElement", "Model", "ReturnMapFailure", "rigid_motions"]


class ElasticConstants:
    """Young's modulus and Poisson's ratio as dolfinx Constants, with the moduli that the UFL laws use
    derived from them: the generated code does not hold their values, so models that differ only in
    the material constants share their compiled forms (and the JIT cache)."""

    def __init__(self, msh, elastic):
        self.E = fem.Constant(msh, PETSc.ScalarType(elastic.E))
        self.nu = fem.Constant(msh, PETSc.ScalarType(elastic.nu))
        E, nu = self.E, self.nu
        self.mu = E / (2.0 * (1.0 + nu))
        self.lmbda = E * nu / ((1.0 + nu) * (1.0 - 2.0 * nu))
        self.lmbda_plane_stress = E * nu / (1.0 - nu * nu)


@dataclass
class Context:
    """What an item sees of the model while it builds its terms (at build time only)."""

    mesh: object
    meshdata: object
    V: object                     # displacement space
    u: object                     # current displacement (Function)
    u_n: object                   # displacement of the last converged increment (Function)
    v: object                     # test function
    x: object                     # reference coordinates
    kin: Kinematics
    update: object                # the stress update (its F(u) is the loads' deformation gradient)
    E: float                      # Young's modulus (scales the contact stiffness)
    degree: int
    facet_traction: object        # (N, u, base) -> in-plane components of P N on facets
    facet_base: object            # () -> a new FacetBase of the body's converged state

    def facets(self, name: str) -> np.ndarray:
        ft = self.meshdata.facet_tags
        return ft.indices[ft.values == self.meshdata.ds_id(name)]

    def ds(self, name: str, metadata: dict | None = None):
        measure = ufl.Measure("ds", domain=self.mesh, subdomain_data=self.meshdata.facet_tags)
        return measure(self.meshdata.ds_id(name), metadata=metadata or {})

    @property
    def weight(self):
        return self.kin.weight()


def rigid_motions(V) -> tuple[np.ndarray, np.ndarray, float]:
    """The two translations and the in-plane rotation of the 2-D displacement space V at this
    rank's owned nodes, (nodes, component, motion); the rotation is about the centroid c of all the
    nodes and divided by their rms distance ``size`` from it, so that the three are of one
    magnitude. Returns (modes, c, size). Collective."""
    n = V.dofmap.index_map.size_local
    xy = V.tabulate_dof_coordinates()[:n, :2]
    comm = V.mesh.comm
    total = max(comm.allreduce(n, op=MPI.SUM), 1)
    c = comm.allreduce(xy.sum(axis=0), op=MPI.SUM) / total
    d = xy - c
    size = float(np.sqrt(comm.allreduce(float((d ** 2).sum()), op=MPI.SUM) / total)) or 1.0
    modes = np.zeros((n, 2, 3))
    modes[:, 0, 0] = modes[:, 1, 1] = 1.0
    modes[:, 0, 2], modes[:, 1, 2] = -d[:, 1] / size, d[:, 0] / size
    return modes, c, size


class Model:
    """A body and its items (loads, supports, contact), compiled into residual and Jacobian forms."""

    def __init__(self, body: Body, items=()):
        self.body = body
        self.meshdata = body.mesh
        self.mesh = msh = body.mesh.mesh
        self.comm = msh.comm
        self.elastic, self.plastic = body.elastic, body.plastic
        self.degree = body.degree
        self.x = ufl.SpatialCoordinate(msh)
        self.kin = Kinematics(body.kind, self.x, body.thickness)
        self.rule = QuadratureRule(msh, body.rule_degree())
        self.constants = ElasticConstants(msh, self.elastic)
        self.update = make_update(body.update, self.kin, self.constants)
        self.V = compat.function_space(msh, "Lagrange", body.degree, (2,))
        self.u = fem.Function(self.V, name="displacement")
        self.u_n = fem.Function(self.V, name="displacement_n")
        self.du = fem.Function(self.V, name="newton_correction")
        self.v = ufl.TestFunction(self.V)
        self.u_trial = ufl.TrialFunction(self.V)
        self.state = QuadratureState(self.rule, self.plastic, body.kind, body.degree)
        self.items = list(items)
        self.load = 0.0
        self._generation = 0                   # counts the changes of the converged state
        self._evaluated = None                 # (key, u) of the state's last evaluation

    # shortcuts to the state (read by outputs and tests)
    @property
    def sigma(self):
        return self.state.sigma

    @property
    def sigma_n(self):
        return self.state.sigma_n

    @property
    def p(self):
        return self.state.p

    @property
    def p_n(self):
        return self.state.p_n

    @property
    def F22_n(self):
        return self.state.F22_n

    # ----------------------------------------------------------------------------------------
    # Forms
    # ----------------------------------------------------------------------------------------
    def context(self) -> Context:
        return Context(self.mesh, self.meshdata, self.V, self.u, self.u_n, self.v, self.x, self.kin,
                       self.update, self.elastic.E, self.degree, self.facet_traction,
                       lambda: FacetBase(self.state, self.u_n))

    def finalize(self, jit_options: dict | None = None, compiled_return: bool = True) -> None:
        """Build and compile the residual, the Jacobian, the stress evaluation and the nodal det F
        check (once).
        ``compiled_return``: the return map of a plastic body in the generated stress evaluation
        (True, where the law has a compiled form: plane strain and axisymmetry) or in NumPy (False;
        plane stress always). Compiled, one pass over the points gives the stress and the plastic
        strain, and it is the faster at every size since the Jacobian applies D from the stored
        state (docs/performance.md)."""
        u, v, dx, st = self.u, self.v, self.rule.dx, self.state
        up = self.update.build(u, self.u_n, st.sigma_n)
        geometric = self.update.geometric     # False: linear kinematics, P = sigma on the reference
        if geometric:
            F22 = st.F22 if st.F22 is not None else up.F22
            F = self.kin.F3(u, F22) if self.kin.model == PLANE_STRESS else self.kin.F3(u)
            cof = cofactor(F)                 # J F^-T
            P = to_tensor(st.sigma) * cof
        else:
            F = self.update.F(u)
            P = to_tensor(st.sigma)
        self.F = F
        w = self.kin.weight()
        internal = ufl.inner(P, self.kin.grad3(v)) * w * dx
        self._internal, self._internal_form, self._jit = internal, None, jit_options
        ctx = self.context()
        R, terms = internal, None
        for item in self.items:
            term = item.attach(ctx)
            if term is not None:
                R = R + term
                terms = term if terms is None else terms + term
        self._terms, self._terms_form = terms, None
        # Jacobian: the geometric part (sigma held), the material part d sigma = D d sigma_tr, the
        # items' terms (UFL's derivative) and, in plane-stress plasticity, the thickness stretch's part
        dsig_tr, dsig_rot = self.update.directional(u, self.u_n, st.sigma_n, self.u_trial, up)
        dsig_tr = to_vec(dsig_tr)
        dsig = to_tensor(dsig_tr)
        table = None
        if self.plastic is not None:
            table = self._surface_table()
            dsig_rot = to_vec(dsig_rot)
            Dx = self.plastic.tangent_times(st.sigma, st.p, st.p_n, dsig_tr, self.kin.model,
                                            self.constants, table)
            if Dx is None:                     # D stored by the evaluations
                st.store_tangent()
                Dx = ufl.dot(st.D, dsig_tr)
            dsig = to_tensor(Dx)
        # the geometric part (sigma held) is sigma d(cof F), the derivative of a polynomial in F
        if geometric:
            dcof = ufl.derivative(cof, u, self.u_trial)
            Jac = ufl.inner(to_tensor(st.sigma) * dcof + dsig * cof, self.kin.grad3(v)) * w * dx
        else:
            Jac = ufl.inner(dsig, self.kin.grad3(v)) * w * dx
        if terms is not None:
            Jac = Jac + ufl.derivative(terms, u, self.u_trial)
        if st.F22 is not None and geometric:
            # the direction of a derivative must be free of unevaluated derivatives
            dF22 = expand_derivatives(st.F22 * (ufl.dot(st.G_tr, dsig_tr) + ufl.dot(st.G_rot, dsig_rot)))
            Jac = Jac + ufl.derivative(internal, st.F22, dF22)
        self.residual_ufl = R                 # (its signature names the compiled code)
        self.residual_form = compat.form(R, jit_options)
        self.jacobian_form = compat.form(Jac, jit_options)
        # everything the constitutive stage needs, in one evaluation per iterate: the trial
        # stress (and rotated old stress) for a return map in NumPy, or the return map compiled in
        parts = [to_vec(up.sigma)]
        compiled = None if self.plastic is None or not compiled_return else self.plastic.compiled(
            to_vec(up.sigma), st.p_n, self.kin.model, self.constants, table)
        if compiled is not None:
            sig, p = compiled
            parts = [sig, [p]]
            st.compiled = True
        elif self.plastic is not None:
            parts.append(to_vec(up.sigma_rot))
        if up.state_new is not None:
            parts.append(up.state_new)
            st.state_new = np.zeros((self.rule.size, 4))
        # det F (a linear body's is 1: it has no configuration to fold)
        parts.append(ufl.as_vector([ufl.det(self.update.F(u))]))
        self._eval = self.rule.expression(ufl.as_vector([c for p in parts for c in p]))
        # det F at the cells' nodes (vertices and, for P2, edge midpoints): folded_at_nodes
        pts = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]] +
                       ([[0.5, 0.5], [0.0, 0.5], [0.5, 0.0]] if self.degree == 2 else []))
        self._nodal_det = compat.expression(ufl.det(ufl.Identity(2) + ufl.grad(u)), pts) \
            if geometric else None
        self.set_load(0.0)

    def _surface_table(self):
        """The plastic law's loading surface (its hardening table) as a Constant: models that differ
        in the table's values only share the compiled stress evaluation."""
        surface = self.plastic.surface
        p0, s0, h = surface.segments
        c = fem.Constant(self.mesh, np.stack([p0, s0, h]).astype(PETSc.ScalarType))
        n = len(p0)
        saturation = {}
        if surface.smooth:                    # its saturation term, dsigma and delta
            v = fem.Constant(self.mesh, np.array([surface.dsigma, surface.delta], dtype=PETSc.ScalarType))
            saturation = {"dsigma": v[0], "delta": v[1]}
        return rm_ufl.Table(*([c[i, k] for k in range(n)] for i in range(3)), **saturation)

    @property
    def bcs(self) -> list:
        """The Dirichlet conditions of the items as they stand (a step may release a support)."""
        return [bc for item in self.items for bc in item.bcs]

    def free_motions(self) -> list[str]:
        """The rigid-body motions that the Dirichlet conditions (as they stand) leave free, described
        in words; empty when they hold the body. In the plane: the translations and the rotation
        (the nullspace of the constrained dofs' rows of the three modes of :func:`rigid_motions`); in
        axisymmetry only the translation along the axis is rigid. Contact may hold a free motion
        once it closes; until it does, the tangent is singular along it. Collective."""
        modes, c, size = rigid_motions(self.V)
        work = compat.create_vector(self.residual_form)
        rows = modes[compat.constrained(work, self.bcs).reshape(-1, 2)]
        work.destroy()
        G = self.comm.allreduce(rows.T @ rows, op=MPI.SUM)
        if self.kin.axisymmetric:
            return [] if G[1, 1] > 0.0 else ["translation along the axis"]
        w, vecs = np.linalg.eigh(G)
        free = vecs[:, w <= 1e-10 * max(w.max(), 1.0)]
        if free.shape[1] == 3:
            return ["translation in x", "translation in y", "rotation"]
        out = []
        for tx, ty, rot in (f / np.abs(f).max() for f in free.T):
            if abs(rot) < 1e-8:
                t = np.array([tx, ty]) / np.hypot(tx, ty)
                out.append("translation in " + ("x" if abs(t[1]) < 1e-8 else "y" if abs(t[0]) < 1e-8
                                                else f"direction ({t[0]:.3g}, {t[1]:.3g})"))
            else:                                     # t + rot e_z x (x - c) / size = rot e_z x (x - p) / size
                p = c + size * np.array([-ty, tx]) / rot
                out.append(f"rotation about ({p[0]:.4g}, {p[1]:.4g})")
        return out

    def release(self, item) -> None:
        """Take a support away (loads.Displacement.release): its force at the converged state,
        the residual at its dofs, becomes a nodal force that the step ramps down."""
        item.release(self._support_forces())

    def _support_forces(self) -> np.ndarray:
        """This rank's owned entries of the residual R = f_int - f_ext (nodal forces included)
        without Dirichlet conditions, at the current state: at a constrained dof, the force the
        support supplies."""
        b = compat.create_vector(self.residual_form)
        compat.assemble_vector(b, self.residual_form, add=self.nodal_loads())
        out = b.array.copy()
        b.destroy()
        return out

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

    def facet_traction(self, N, u=None, base: FacetBase | None = None):
        """In-plane components of P N on facets, P = J sigma F^-T at displacement u (default the
        current one), for Nitsche terms: the constitutive update evaluated at the facet's points as
        a UFL function of u, from the converged state of the last increment (cell-wise DG fits) or
        from a captured ``base`` (the state a lag state u_lag was solved from) and, for
        elastic-plastic bodies, the material's law in UFL. Everything that varies within an
        increment is a function of u, so the term's Jacobian is exact, and the traction at a lag
        state depends on u_lag and converged state only (docs/theory.md section 6.3)."""
        u = self.u if u is None else u
        src, u_n = (self.state, self.u_n) if base is None else (base, base.u_n)
        up = self.update.build(u, u_n, src.facet("sigma_n"))
        sig, F22 = up.sigma, up.F22
        if self.plastic is not None:
            p_n = ufl.max_value(src.facet("p_n"), 0.0)           # the fit may dip below 0
            sig, ezz = self.plastic.facet(up.sigma_rot, up.sigma, p_n, self.kin.model, self.constants)
            if ezz is not None:
                F22 = src.facet("F22_n") * ufl.exp(ezz)
        N3 = ufl.as_vector([N[0], N[1], 0.0])
        if not self.update.geometric:          # linear kinematics: sigma N on the reference facet
            PN = sig * N3
        else:
            F = self.kin.F3(u, F22) if self.kin.model == PLANE_STRESS else self.kin.F3(u)
            PN = sig * cofactor(F) * N3
        return ufl.as_vector([PN[0], PN[1]])

    # ----------------------------------------------------------------------------------------
    # Load factor, constitutive evaluation, commit / restore
    # ----------------------------------------------------------------------------------------
    def set_load(self, t: float) -> None:
        """Set every item (loads, prescribed displacements, obstacles) to load factor t."""
        self.load = t
        for item in self.items:
            item.set(t)

    def nodal_loads(self):
        """(owned dofs, their residual entries -f) of the items' nodal forces, or None."""
        parts = [item.nodal() for item in self.items]
        parts = [pt for pt in parts if pt is not None]
        if not parts:
            return None
        return (np.concatenate([d for d, _ in parts]).astype(np.int32),
                -np.concatenate([f for _, f in parts]))

    def folded_at_nodes(self) -> str | None:
        """Why the current iterate is inadmissible at the nodes, or None: the element map folds
        where det F <= 0 at a node of a cell (its vertices and, for P2, edge midpoints), which the
        quadrature points alone can miss. One evaluation per converged increment; none under linear
        kinematics (small_strain), whose geometry does not move."""
        if self._nodal_det is None:
            return None
        vals = compat.evaluate(self._nodal_det, self.mesh, self.rule.cells)
        worst = self.comm.allreduce(float(vals.min()) if vals.size else np.inf, op=MPI.MIN)
        if worst > 0.0:
            return None
        return f"det F = {worst:.3g} <= 0 at a node: an element folds (increment too large, or the body folds)"

    def evaluate_stress(self, again: bool = False) -> None:
        """Stress (and tangent) at every quadrature point for the current displacement iterate; nothing
        to do when the state already holds this iterate's (the same u, converged state and elastic
        constants: e.g. Newton's first residual after a friction re-lag pass, at the iterate just solved),
        unless ``again``: evaluated without that comparison, for a caller that has just set a new
        iterate (the line searches' trials) or wants the evaluation itself (the cost benchmarks).
        The converged state changes through :meth:`commit` and :meth:`load_state` only.

        Raises, on every rank when it happens on any: :class:`InvertedElement` if det F <= 0 at a
        point, :class:`ReturnMapFailure` if the update is not defined (NaN) or the return map fails.
        """
        key = (self._generation, float(self.constants.E.value), float(self.constants.nu.value))
        same = not again and self._evaluated is not None and self._evaluated[0] == key and \
            np.array_equal(self._evaluated[1], self.u.x.array)
        if same if self.comm.size == 1 else self.comm.allreduce(same, op=MPI.LAND):
            return                             # this iterate, from the same converged state
        err = None
        try:
            self.state.evaluate(self.rule.evaluate(self._eval))
        except (InvertedElement, ReturnMapFailure) as e:
            err = e
        except Exception as e:                 # noqa: BLE001 - e.g. a return map that did not converge
            err = ReturnMapFailure(f"the constitutive update failed: {e}")
        self._evaluated = None
        agree(self.comm, err)
        self._evaluated = (key, self.u.x.array.copy())

    def commit(self) -> None:
        """Accept the current iterate as the converged state of the increment."""
        for item in self.items:                # before u_n moves: they may need the increment
            item.commit()
        self.u_n.x.array[:] = self.u.x.array
        self.state.commit()
        self._generation += 1

    # -- checkpoints ----------------------------------------------------------------------------
    def save_state(self) -> dict:
        """A converged increment before it commits, to go on from it: name -> (kind, local array),
        kind "V" (the displacement's nodes) or "Q" (quadrature points), or a number. The old
        converged state (``_n``) is there too: with the iterate Newton factorised last it rebuilds
        the tangent that the predictor reuses."""
        st = self.state
        out = {"u": ("V", self.u.x.array), "u_n": ("V", self.u_n.x.array), "load": self.load}
        for name in ("sigma", "sigma_n", "p", "p_n", "F22", "F22_n"):
            f = getattr(st, name)
            if f is not None:
                out[name] = ("Q", self.rule.view(f))
        if st.state_new is not None:
            out["state_new"] = ("Q", st.state_new)
        return out

    def point_coordinates(self) -> np.ndarray:
        """Reference coordinates (points, 2) of this rank's quadrature points (ghost cells too)."""
        if getattr(self, "_xq", None) is None:
            self._xq = self.rule.evaluate(self.rule.expression(self.x))
        return self._xq

    def load_state(self, state: dict, items: list[dict], u_factorised=None, matrix=None) -> None:
        """Back to a saved converged increment (arrays already on this rank's numbering), then
        commit it. With ``u_factorised`` and ``matrix``, the tangent of that iterate is assembled
        first (against the old converged state, as Newton assembled it) into ``matrix``."""
        st = self.state
        self._generation += 1
        self.u_n.x.array[:] = state["u_n"]
        for name in ("sigma_n", "p_n", "F22_n"):
            if name in state:
                getattr(st, name).x.array[:] = np.asarray(state[name]).ravel()
        st.refit()
        self.load = float(state["load"])
        for item, saved in zip(self.items, items):
            item.load_state(saved)
        if u_factorised is not None:
            self.u.x.array[:] = u_factorised
            self.evaluate_stress()
            compat.assemble_matrix(matrix, self.jacobian_form, self.bcs)
        self.u.x.array[:] = state["u"]
        for name in ("sigma", "p", "F22"):
            if name in state:
                getattr(st, name).x.array[:] = np.asarray(state[name]).ravel()
        if "state_new" in state:
            st.state_new[:] = state["state_new"]
        self.commit()

    def restore(self) -> None:
        """Return to the last converged state (after a failed increment)."""
        self.u.x.array[:] = self.u_n.x.array
        for item in self.items:
            item.restore()

    # ----------------------------------------------------------------------------------------
    # Derived quantities
    # ----------------------------------------------------------------------------------------
    def cauchy_stress(self) -> np.ndarray:
        """Cauchy stress at the points of the current iterate, shape (points, 4)."""
        return self.rule.view(self.state.sigma)

    def supports_of(self, name: str) -> list:
        """The supports (items of kind "support") of the tagged boundary ``name``, released or not."""
        return [it for it in self.items if it.kind == "support" and getattr(it, "boundary", None) == name]

    def reaction_forces(self, name: str) -> tuple[np.ndarray, np.ndarray]:
        """Reference positions (n, 2) and forces (n, 2) that the supports of a tagged boundary exert
        on its nodes (this rank's owned nodes), from the residual at the current state
        (:meth:`_support_forces`), in the components that those supports hold; zero in the others
        (at a corner node, the residual in a component that another boundary's support holds is
        that support's force) and once a step released them. Where supports of two boundaries hold
        the same component of a corner node, that node's force counts for both."""
        R = self._support_forces()
        fdim = self.mesh.topology.dim - 1
        ft = self.meshdata.facet_tags
        facets = ft.indices[ft.values == self.meshdata.ds_id(name)]
        dofs = fem.locate_dofs_topological(self.V.sub(0), fdim, facets)
        bs = self.V.dofmap.index_map_bs
        nodes = np.unique(dofs // bs)
        nodes = nodes[nodes < self.V.dofmap.index_map.size_local]
        bcs = [bc for it in self.supports_of(name) for bc in it.bcs]
        work = compat.create_vector(self.residual_form)
        held = compat.constrained(work, bcs).reshape(-1, bs) if bcs else np.zeros((R.size // bs, bs), bool)
        work.destroy()
        f = np.where(held[nodes], R.reshape(-1, bs)[nodes], 0.0)
        return self.V.tabulate_dof_coordinates()[nodes, :2], f

    def reaction(self, name: str) -> np.ndarray:
        """Total force (x, y) that the supports of a tagged boundary exert on it (all ranks;
        :meth:`reaction_forces`)."""
        return self.comm.allreduce(self.reaction_forces(name)[1].sum(axis=0), op=MPI.SUM)

    def num_dofs(self) -> int:
        imap = self.V.dofmap.index_map
        return imap.size_global * self.V.dofmap.index_map_bs

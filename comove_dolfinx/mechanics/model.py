"""The finite-element model of a body and its items: spaces, state, residual and exact Jacobian.

A :class:`Model` holds the body's spaces and its state at the quadrature points (state.py), drives
its items (loads.py, contact/; the protocol of items.py) through the increments, and is made of
parts that each do one job:

* ``forms`` (forms.py, built by :meth:`Model.finalize`): the residual and its exact Jacobian,
  with the items' terms (docs/theory.md sections 1 and 5; a Taylor test checks the Jacobian,
  taylor.py, tests/test_taylor.py);
* ``evaluation`` (evaluation.py, built by :meth:`Model.finalize`): the stress at the quadrature
  points of each iterate, from the stress update of updates.py and, for elastic-plastic materials,
  the return map (materials.py, state.py);
* ``supports`` (supports.py): the Dirichlet conditions, the rigid motions they leave free,
  releasing a support, the reactions;
* ``state_io`` (state_io.py): the converged state as arrays, saved and loaded.

The names that callers use (``residual_form``, ``evaluate_stress``, ``reaction``, ``save_state``,
...) are the model's too, each its part's. Items build their terms from a :class:`Context` handed to
them once: data flows from the model to the items, never back. The load factor t of ``set_load``
sets every item.
"""
from __future__ import annotations

from functools import partial

import numpy as np
import ufl
from dolfinx import fem
from petsc4py import PETSc

from .. import compat
from ..delegation import delegate
from .body import Body
from .evaluation import StressEvaluation
from .forms import Forms, facet_traction
from .items import Context
from .kinematics import Kinematics
from .quadrature import QuadratureRule
from .state import FacetBase, InvertedElement, QuadratureState, ReturnMapFailure
from .state_io import StateIO
from .supports import Supports, rigid_motions
from .updates import make_update
from .volume import VolumeAverage

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
        self.V = compat.function_space(msh, "Lagrange", body.degree, (self.kin.dim,))
        self.u = fem.Function(self.V, name="displacement")
        self.u_n = fem.Function(self.V, name="displacement_n")
        self.du = fem.Function(self.V, name="newton_correction")
        self.v = ufl.TestFunction(self.V)
        self.u_trial = ufl.TrialFunction(self.V)
        self.state = QuadratureState(self.rule, self.plastic, body.kind, body.degree)
        self.volume = VolumeAverage(self) if body.fbar else None      # F-bar (volume.py)
        self.update.volume = self.volume
        self.items = list(items)
        self.load = 0.0
        self.supports = Supports(self)
        self.state_io = StateIO(self)

    def finalize(self, jit_options: dict | None = None, compiled_return: bool = True) -> None:
        """Build and compile the residual, the Jacobian (:attr:`forms`), the stress evaluation and
        the nodal det F check (:attr:`evaluation`), once. ``compiled_return``: the return map of a
        plastic body in the generated stress evaluation (True, where the law has a compiled form:
        plane strain, axisymmetry and 3D) or in NumPy (False; plane stress always; not in 3D, where
        the return map is compiled only); :class:`evaluation.StressEvaluation` says which is faster."""
        if not compiled_return and self.kin.solid and self.plastic is not None:
            raise ValueError("compiled_return = False: the 3D model's return map is compiled only; "
                             "use compiled_return=True")
        self.forms = Forms(self, jit_options)
        self.evaluation = StressEvaluation(self, self.forms.update_terms, self.forms.table, compiled_return)
        self.set_load(0.0)

    def context(self) -> Context:
        """What the items see of the model while they build their terms."""
        return Context(self.mesh, self.meshdata, self.V, self.u, self.u_n, self.v, self.x, self.kin,
                       self.update, self.elastic.E, self.degree, partial(facet_traction, self),
                       lambda: FacetBase(self.state, self.u_n))

    # -- load factor, increments ------------------------------------------------------------------
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

    def commit(self) -> None:
        """Accept the current iterate as the converged state of the increment."""
        for item in self.items:                # before u_n moves: they may need the increment
            item.commit()
        self.u_n.x.array[:] = self.u.x.array
        self.state.commit()
        self.evaluation.converged_state_changed()

    def restore(self) -> None:
        """Return to the last converged state (after a failed increment)."""
        self.u.x.array[:] = self.u_n.x.array
        for item in self.items:
            item.restore()

    def assemble_jacobian(self, A: PETSc.Mat, bcs=None) -> None:
        """Zero A and assemble the exact Jacobian at the current iterate (the stress evaluated),
        with the Dirichlet rows and columns of ``bcs`` (the model's by default); with F-bar its
        part through the mean dilatation added (volume.py)."""
        bcs = self.bcs if bcs is None else bcs
        compat.assemble_matrix(A, self.jacobian_form, bcs)
        if self.volume is not None:
            self.volume.add_condensed(A, bcs)

    # -- derived quantities -----------------------------------------------------------------------
    def cauchy_stress(self) -> np.ndarray:
        """Cauchy stress at the points of the current iterate, shape (points, 4), in 3D (points, 6)
        (xx, yy, zz, xy, yz, xz)."""
        return self.rule.view(self.state.sigma)

    def num_dofs(self) -> int:
        """The number of displacement dofs (all ranks)."""
        imap = self.V.dofmap.index_map
        return imap.size_global * self.V.dofmap.index_map_bs

    # -- the parts' names that callers use --------------------------------------------------------
    residual_ufl = delegate("forms.residual_ufl")
    residual_form = delegate("forms.residual_form")
    jacobian_form = delegate("forms.jacobian_form")
    internal_force_form = delegate("forms.internal_force_form")
    items_form = delegate("forms.items_form")
    F = delegate("forms.F")
    evaluate_stress = delegate("evaluation.evaluate")
    folded_at_nodes = delegate("evaluation.folded_at_nodes")
    bcs = delegate("supports.bcs")
    free_motions = delegate("supports.free_motions")
    release = delegate("supports.release")
    supports_of = delegate("supports.supports_of")
    reaction_forces = delegate("supports.reaction_forces")
    reaction = delegate("supports.reaction")
    save_state = delegate("state_io.save_state")
    load_state = delegate("state_io.load_state")
    point_coordinates = delegate("state_io.point_coordinates")
    # the quadrature state's fields (read by outputs and tests)
    sigma = delegate("state.sigma")
    sigma_n = delegate("state.sigma_n")
    p = delegate("state.p")
    p_n = delegate("state.p_n")
    F22_n = delegate("state.F22_n")

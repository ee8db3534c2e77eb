"""The constitutive stage of a model: the stress at the quadrature points for each iterate.

One compiled expression gives, per iterate, everything the stage needs: the trial stress (and the
rotated old stress) for a return map in NumPy, or the stress and plastic strain of the return map
compiled in (plane strain and axisymmetry), the update's own state if it has one, and det F. The
quadrature state (state.py) turns these into the stress and, where stored, the tangents. A second
expression checks det F at the cells' nodes, which the quadrature points alone can miss.
"""
from __future__ import annotations

import numpy as np
import ufl
from mpi4py import MPI

from .. import compat
from ..parallel import agree
from .state import InvertedElement, ReturnMapFailure


def _cell_nodes(cell: str, degree: int) -> np.ndarray:
    """The nodes of the reference cell: a simplex's vertices and, for degree 2, its edge midpoints;
    a quadrilateral's or hexahedron's tensor grid (its vertices, or the 3 x 3 (x 3) points of
    degree 2, edge midpoints, face centres and centre included)."""
    if cell in ("quadrilateral", "hexahedron"):
        t = np.linspace(0.0, 1.0, degree + 1)
        if cell == "quadrilateral":
            return np.array([[x, y] for y in t for x in t])
        return np.array([[x, y, z] for z in t for y in t for x in t])
    if cell == "triangle":
        return np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]] +
                        ([[0.5, 0.5], [0.0, 0.5], [0.5, 0.0]] if degree == 2 else []))
    v = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]])
    if degree != 2:
        return v
    return np.vstack([v, [0.5 * (v[i] + v[j]) for i in range(4) for j in range(i + 1, 4)]])


class StressEvaluation:
    """The stress of a model (mechanics/model.py) at the current iterate, evaluated once per iterate.

    ``update_terms``: the stress update's UFL of the increment (forms.py, ``Forms.update_terms``);
    ``table``: the plastic law's surface as Constants (or None); ``compiled_return``: the return map
    of a plastic body in the generated evaluation where the law has a compiled form (plane strain
    and axisymmetry), else in NumPy (plane stress always). Compiled, one pass over the points gives
    the stress and the plastic strain, and it is the faster at every size since the Jacobian applies
    D from the stored state (docs/performance.md).
    """

    def __init__(self, model, update_terms, table, compiled_return: bool = True):
        self.model = model
        self.generation = 0                    # counts the changes of the converged state
        self._evaluated = None                 # (key, u) of the last evaluation
        self._expression = model.rule.expression(self._columns(model, update_terms, table, compiled_return))
        self._nodal_det = self._nodal_det_expression(model)

    @staticmethod
    def _columns(m, up, table, compiled_return: bool):
        """The evaluated columns (state.QuadratureState.evaluate reads them in this order)."""
        st = m.state
        parts = [m.kin.vec(up.sigma)]
        compiled = None if m.plastic is None or not compiled_return else m.plastic.compiled(
            m.kin.vec(up.sigma), st.p_n, m.kin.model, m.constants, table)
        if compiled is not None:
            sig, p = compiled
            parts = [sig, [p]]
            st.compiled = True
        elif m.plastic is not None:
            parts.append(m.kin.vec(up.sigma_rot))
        if up.state_new is not None:
            parts.append(up.state_new)
            st.state_new = np.zeros((m.rule.size, m.kin.size))
        # det F (a linear body's is 1: it has no configuration to fold)
        parts.append(ufl.as_vector([ufl.det(m.update.F(m.u))]))
        return ufl.as_vector([c for p in parts for c in p])

    @staticmethod
    def _nodal_det_expression(m):
        """det F at the cells' nodes (vertices and, for P2, edge midpoints; on quadrilaterals and
        hexahedra every node of the tensor grid), or None under linear kinematics."""
        if not m.update.geometric:
            return None
        dim = 3 if m.kin.solid else 2
        nodes = _cell_nodes(compat.cell_name(m.mesh), m.degree)
        return compat.expression(ufl.det(ufl.Identity(dim) + ufl.grad(m.u)), nodes)

    def converged_state_changed(self) -> None:
        """The converged state moved (a commit, a checkpoint loaded): the next evaluation is due
        whatever the iterate."""
        self.generation += 1

    def evaluate(self, again: bool = False) -> None:
        """Stress (and tangent) at every quadrature point for the current displacement iterate; nothing
        to do when the state already holds this iterate's (the same u, converged state and elastic
        constants: e.g. Newton's first residual after a friction re-lag pass, at the iterate just solved),
        unless ``again``: evaluated without that comparison, for a caller that has just set a new
        iterate (the line searches' trials) or wants the evaluation itself (the cost benchmarks).
        The converged state changes through the model's ``commit`` and ``load_state`` only.

        Raises, on every rank when it happens on any: :class:`InvertedElement` if det F <= 0 at a
        point, :class:`ReturnMapFailure` if the update is not defined (NaN) or the return map fails.
        """
        m = self.model
        key = (self.generation, float(m.constants.E.value), float(m.constants.nu.value))
        same = not again and self._evaluated is not None and self._evaluated[0] == key and \
            np.array_equal(self._evaluated[1], m.u.x.array)
        if same if m.comm.size == 1 else m.comm.allreduce(same, op=MPI.LAND):
            return                             # this iterate, from the same converged state
        err = None
        if m.volume is not None:               # F-bar: the mean dilatation of this iterate first
            m.volume.refresh(self.generation)
        try:
            m.state.evaluate(m.rule.evaluate(self._expression))
        except (InvertedElement, ReturnMapFailure) as e:
            err = e
        except Exception as e:                 # noqa: BLE001 - e.g. a return map that did not converge
            err = ReturnMapFailure(f"the constitutive update failed: {e}")
        self._evaluated = None
        agree(m.comm, err)
        self._evaluated = (key, m.u.x.array.copy())

    def folded_at_nodes(self) -> str | None:
        """Why the current iterate is inadmissible at the nodes, or None: the element map folds
        where det F <= 0 at a node of a cell (its vertices and, for P2, edge midpoints), which the
        quadrature points alone can miss. One evaluation per converged increment; none under linear
        kinematics (small_strain), whose geometry does not move."""
        if self._nodal_det is None:
            return None
        m = self.model
        vals = compat.evaluate(self._nodal_det, m.mesh, m.rule.cells)
        worst = m.comm.allreduce(float(vals.min()) if vals.size else np.inf, op=MPI.MIN)
        if worst > 0.0:
            return None
        return f"det F = {worst:.3g} <= 0 at a node: an element folds (increment too large, or the body folds)"

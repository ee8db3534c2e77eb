"""A model's converged state as plain arrays, for checkpoints (io/checkpoint.py writes and reads them).

What is saved: the displacement of the increment and of the one before, the load factor, and the
quadrature state (stress, plastic strain, thickness stretch, the update's own state), each with the
kind of its layout so that a checkpoint can be read on another partition: "V" (the displacement's
nodes) or "Q" (the quadrature points, located by :meth:`StateIO.point_coordinates`).
"""
from __future__ import annotations

import numpy as np


_POINT_FIELDS = ("sigma", "sigma_n", "p", "p_n", "F22", "F22_n")


class StateIO:
    """Saves and loads the converged state of a model (mechanics/model.py)."""

    def __init__(self, model):
        self.model = model
        self._xq = None

    def save_state(self) -> dict:
        """A converged increment before it commits, to go on from it: name -> (kind, local array),
        kind "V" (the displacement's nodes) or "Q" (quadrature points), or a number. The old
        converged state (``_n``) is there too: with the iterate Newton factorised last it rebuilds
        the tangent that the predictor reuses."""
        m = self.model
        st = m.state
        out = {"u": ("V", m.u.x.array), "u_n": ("V", m.u_n.x.array), "load": m.load}
        for name in _POINT_FIELDS:
            f = getattr(st, name)
            if f is not None:
                out[name] = ("Q", m.rule.view(f))
        if st.state_new is not None:
            out["state_new"] = ("Q", st.state_new)
        return out

    def point_coordinates(self) -> np.ndarray:
        """Reference coordinates (points, the body's dimension) of this rank's quadrature points (ghost cells too)."""
        if self._xq is None:
            rule = self.model.rule
            self._xq = rule.evaluate(rule.expression(self.model.x))
        return self._xq

    def load_state(self, state: dict, items: list[dict], u_factorised=None, matrix=None) -> None:
        """Back to a saved converged increment (arrays already on this rank's numbering), then
        commit it. With ``u_factorised`` and ``matrix``, the tangent of that iterate is assembled
        first (against the old converged state, as Newton assembled it) into ``matrix``."""
        m = self.model
        st = m.state
        m.evaluation.converged_state_changed()
        m.u_n.x.array[:] = state["u_n"]
        self._set_point_fields(state, ("sigma_n", "p_n", "F22_n"))
        st.refit()
        m.load = float(state["load"])
        for item, saved in zip(m.items, items):
            item.load_state(saved)
        if u_factorised is not None:
            m.u.x.array[:] = u_factorised
            m.evaluate_stress()
            m.nodal_loads()          # as before Newton's assembly: the items' fields at this iterate
            m.assemble_jacobian(matrix)
        m.u.x.array[:] = state["u"]
        self._set_point_fields(state, ("sigma", "p", "F22"))
        if "state_new" in state:
            st.state_new[:] = state["state_new"]
        m.commit()

    def _set_point_fields(self, state: dict, names) -> None:
        """The quadrature state's fields ``names`` from ``state`` (those it holds)."""
        st = self.model.state
        for name in names:
            if name in state:
                getattr(st, name).x.array[:] = np.asarray(state[name]).ravel()

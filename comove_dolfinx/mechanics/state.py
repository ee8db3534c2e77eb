"""The material state at the quadrature points, and its copies on the facets.

Quadrature functions (4-vectors xx, yy, zz, xy, in 3D 6-vectors xx, yy, zz, xy, yz, xz; see
kinematics.py): ``sigma_n`` the converged state of
increment n (the stress, or for the polar update the unrotated stress), ``sigma`` the stress at the
current iterate; for elastic-plastic bodies ``p_n``/``p`` the equivalent plastic strain; in
plane-stress plasticity ``D``, the derivative of the return map (the other models' Jacobian applies
it from sigma, p and p_n), ``F22_n``/``F22``
the thickness stretch, F22 = F22_n exp(ezz), and ``G_tr``/``G_rot`` the derivatives of ezz
(docs/theory.md section 4.3).

Facet integrals cannot see quadrature functions (dolfinx evaluates none there); the converged state
is copied to cell-wise DG fits at each commit (exact interpolation for DG1 and the 3-point rule), from
which the material law is evaluated again on the facets when a term asks for the stress there.
A :class:`FacetBase` keeps a copy of those fits (and of u_n) as they were when an increment was
solved from them, so that the facet stress of that solution can be evaluated again later, exactly.
"""
from __future__ import annotations

import math

import numpy as np
from dolfinx import fem

from .. import compat
from . import return_maps as rm
from .quadrature import CellInterpolator, QuadratureRule


class InvertedElement(RuntimeError):
    """det F <= 0 at a quadrature point: the iterate is not admissible."""


class ReturnMapFailure(RuntimeError):
    """The constitutive update could not be evaluated (e.g. S-R split beyond 90 degrees)."""


class QuadratureState:
    """State of a body at its quadrature points (``plastic``: a materials.Plastic or None)."""

    def __init__(self, rule: QuadratureRule, plastic, kind: str, degree: int):
        self.rule, self.plastic, self.kind = rule, plastic, kind
        self.size = n = 6 if kind == "solid" else 4          # the stored vectors' length
        r = rule
        self.sigma_n = r.function((n,), "sigma_n")
        self.sigma = r.function((n,), "sigma")
        self.p_n = r.function((), "p_n") if plastic else None
        self.p = r.function((), "p") if plastic else None
        # d sig / d sig_tr, elastic everywhere but at the points that yielded in the last evaluation:
        # stored only for a law whose Jacobian cannot apply it from the state (store_tangent)
        self.D = None
        self._yielding = np.zeros(0, dtype=np.int64)
        self.F22_n = self.F22 = self.G_tr = self.G_rot = None
        if plastic and kind == "plane_stress":
            self.F22_n = r.function((), "F22_n", 1.0)
            self.F22 = r.function((), "F22", 1.0)
            self.G_tr = r.function((4,), "dezz_dtr")
            self.G_rot = r.function((4,), "dezz_drot")
        self.state_new: np.ndarray | None = None     # the update's own state, if not sigma
        self.compiled = False     # the model's evaluation holds the return map (stress, p, D)
        self._fit_degree = max(degree - 1, 0)
        self._facet: dict = {}

    def store_tangent(self) -> None:
        """Keep D = d sig / d sig_tr at the points, written by every evaluation (the plane-stress
        return; the model asks for it when the law has no :meth:`Plastic.tangent_times`)."""
        self.D = self.rule.function((4, 4), "D", rm.elastic_tangent(self.kind))

    # -- the constitutive stage (local to the rank: no collective call) -------------------------
    def evaluate(self, vals: np.ndarray) -> None:
        """From the evaluated update (columns: trial stress, rotated old stress if plastic, the
        update's own state if any, det F; or with ``compiled``: stress, p, ..., det F) to the
        stress (and, where stored, the tangents) at the points."""
        if not math.isfinite(vals.sum()):      # a NaN or an infinity anywhere
            raise ReturnMapFailure("the stress update returned NaN (increment too large?)")
        worst = vals[:, -1].min() if len(vals) else 1.0
        if worst <= 0.0:
            raise InvertedElement(f"det F = {worst:.3g} <= 0 at a quadrature point")
        view, n = self.rule.view, self.size
        sig_tr, col = vals[:, 0:n], n
        if self.plastic is None:
            view(self.sigma)[:] = sig_tr
        elif self.compiled:                    # the return map was evaluated with the update
            view(self.sigma)[:] = vals[:, 0:n]
            self.p.x.array[:] = vals[:, n]
            col = n + 1
        else:
            sig_rot, col = vals[:, n:2 * n], 2 * n
            out = self.plastic.update(sig_rot, sig_tr, self.p_n.x.array, self.kind,
                                      tangent=self.D is not None)
            view(self.sigma)[:] = out.sig
            self.p.x.array[:] = out.p
            if self.D is not None:
                D = view(self.D)
                D[self._yielding] = rm.elastic_tangent(self.kind)       # those of the last evaluation
                D[out.index] = out.D
                self._yielding = out.index
            if self.F22 is not None:
                self.F22.x.array[:] = self.F22_n.x.array * np.exp(out.ezz)
                view(self.G_tr)[:] = out.dezz_tr
                view(self.G_rot)[:] = out.dezz_rot
        if self.state_new is not None:
            self.state_new[:] = vals[:, col:col + n]

    def commit(self) -> None:
        """The current stress (or the update's own state) becomes the converged state."""
        view = self.rule.view
        if self.state_new is not None:
            view(self.sigma_n)[:] = self.state_new
        else:
            self.sigma_n.x.array[:] = self.sigma.x.array
        if self.plastic is not None:
            self.p_n.x.array[:] = self.p.x.array
            if self.F22_n is not None:
                self.F22_n.x.array[:] = self.F22.x.array
        self._fit("sigma_n", view(self.sigma_n))
        if self.plastic is not None:
            self._fit("p_n", self.p_n.x.array)
            if self.F22_n is not None:
                self._fit("F22_n", self.F22_n.x.array)

    def refit(self) -> None:
        """Refresh the facet fits from the converged state (after it was set from outside)."""
        view = self.rule.view
        self._fit("sigma_n", view(self.sigma_n))
        if self.plastic is not None:
            self._fit("p_n", self.p_n.x.array)
            if self.F22_n is not None:
                self._fit("F22_n", self.F22_n.x.array)

    # -- copies on the facets --------------------------------------------------------------------
    def facet(self, name: str):
        """DG function holding a cell-wise fit of the converged state ``name`` (created on first use,
        refreshed at each commit): "sigma_n" (4-vector, 6 in 3D), "p_n", "F22_n" (scalars)."""
        if name not in self._facet:
            shape = () if name in ("p_n", "F22_n") else (self.size,)
            V = compat.function_space(self.rule.mesh, "DG", self._fit_degree, shape)
            f = fem.Function(V, name=name + "_dg")
            source = {"sigma_n": self.sigma_n, "p_n": self.p_n, "F22_n": self.F22_n}[name]
            interp = CellInterpolator(self.rule, V)
            interp(self.rule.view(source), f)
            self._facet[name] = (f, interp)
        return self._facet[name][0]

    def _fit(self, name: str, values) -> None:
        if name in self._facet:
            f, interp = self._facet[name]
            interp(values, f)


class FacetBase:
    """The converged state that a displacement is solved from, as the facet terms see it: the
    displacement u_n and the facet fits of the state (copies, taken by :meth:`capture`).

    The material law on the facets is evaluated from the fits of the converged state of the
    increment's start; once that state moves on (commit), the new fits describe the same solution
    only to the fit's error. A term that needs the facet stress of an earlier solution (the pressure
    of the last converged increment, for lagged friction) evaluates the law at that solution from a
    base captured when it was solved, and gets the same stress to round-off (docs/theory.md section 6.3).
    """

    def __init__(self, state: QuadratureState, u_n: fem.Function):
        self._state, self._u_n = state, u_n
        self.u_n = fem.Function(u_n.function_space, name="u_n_base")
        self.u_n.x.array[:] = u_n.x.array
        self._fits: dict = {}

    def facet(self, name: str):
        """The copy of the state's fit ``name`` (see :meth:`QuadratureState.facet`)."""
        if name not in self._fits:
            src = self._state.facet(name)
            f = fem.Function(src.function_space, name=name + "_base")
            f.x.array[:] = src.x.array
            self._fits[name] = f
        return self._fits[name]

    def capture(self) -> None:
        """Take the body's converged state as it is now."""
        self.u_n.x.array[:] = self._u_n.x.array
        for name, f in self._fits.items():
            f.x.array[:] = self._state.facet(name).x.array

    def arrays(self) -> list:
        """Copies of what the base holds (for :meth:`set_arrays`)."""
        return [self.u_n.x.array.copy()] + [f.x.array.copy() for f in self._fits.values()]

    def set_arrays(self, arrays: list) -> None:
        for f, a in zip([self.u_n, *self._fits.values()], arrays):
            f.x.array[:] = a

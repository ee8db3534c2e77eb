"""The item protocol: what a model asks of the things that load, support or touch its body.

Loads and supports (loads.py) and contact (contact/) are items; the model (model.py) drives them
through this protocol only:

* ``attach(ctx)``: build its UFL residual term (or None) and its Dirichlet conditions from the
  model's :class:`Context`; called once, when the model is compiled;
* ``reset()``: back to the start of a run (factor 0, no step's ramp, supports in place): a
  :class:`job.Job` resets its items before each run, so the same items serve several runs;
* ``set(t)``: the state at load factor t of the current step (amplitudes are Constants, so nothing
  is recompiled);
* ``commit()`` / ``restore()``: at a converged / failed increment (history-dependent items);
* ``bcs``: its Dirichlet conditions; ``nodal()``: forces added straight to nodes (point loads);
* ``save_state()`` / ``load_state(state)``: what it holds at a converged increment (checkpoints).

Amplitudes: an item carries a reference value (a pressure, a vector, a displacement field) scaled by
a factor; a :class:`job.Step` ramps the factor over the step, linearly from where the previous step
left it to a target (or along a path of its own), and an item that a step does not mention keeps its
factor. Signs: the residual is R = f_int - f_ext, so loads contribute -(their virtual work).

Data flows from the model to the items, never back: an item sees the model through the
:class:`Context` handed to ``attach``, at build time only.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np
import ufl

from ..checks import is_number
from .kinematics import Kinematics


class ItemError(ValueError):
    """An item that cannot be used; the message names the value and the fix."""


def finite(name: str, value, shape: tuple = ()) -> np.ndarray:
    """``value`` as a float array of ``shape`` (a number, or a vector of numbers); :class:`ItemError`
    naming ``name`` unless it has that shape and is finite (numbers only: not strings, not True/False)."""
    flat = np.ravel(np.asarray(value, dtype=object)) if shape else [value]
    ok = len(flat) == (shape[0] if shape else 1) and all(is_number(v) for v in flat)
    a = np.asarray(value, dtype=float) if ok else np.zeros(0)
    if a.shape != shape or not np.all(np.isfinite(a)):
        want = "a finite number" if shape == () else f"{shape[0]} finite numbers"
        raise ItemError(f"{name} = {value!r}: give {want}")
    return a


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
        """The local indices of the facets of the tagged boundary ``name``."""
        ft = self.meshdata.facet_tags
        return ft.indices[ft.values == self.meshdata.ds_id(name)]

    def ds(self, name: str, metadata: dict | None = None):
        """The surface measure of the tagged boundary ``name``."""
        measure = ufl.Measure("ds", domain=self.mesh, subdomain_data=self.meshdata.facet_tags)
        return measure(self.meshdata.ds_id(name), metadata=metadata or {})

    @property
    def weight(self):
        """The integration weight: 2 pi r in axisymmetry, the thickness in the plane."""
        return self.kin.weight()


class Item:
    """Base class: a factor ramped by the steps, no term, no state."""

    kind = "load"          # "load", "support" or "contact"; for listings and default ramps

    def __init__(self, name: str | None = None):
        self.name = name
        self.bcs: list = []
        self.reset()

    def reset(self) -> None:
        """Back to the start of a run: factor 0, ramped from 0 to 1 over the load range unless a
        Step says otherwise (a Job calls it before each run)."""
        self._start, self._target = 0.0, 1.0
        self._path: Callable[[float], float] | None = None
        self.factor = 0.0

    # -- steps --------------------------------------------------------------------------------
    def ramp(self, target) -> None:
        """Over the coming step, go from the current factor to ``target`` (a number), or follow
        ``target(s)`` (a callable of the step's load factor s in [0, 1])."""
        self._start = self.factor
        if callable(target):
            self._path, self._target = target, None
        else:
            self._path, self._target = None, float(finite(f"{self} target", target))

    def hold(self) -> None:
        """Keep the current factor over the coming step."""
        self.ramp(self.factor)

    def factor_at(self, t: float) -> float:
        """The factor at the step's load factor ``t`` in [0, 1]."""
        if self._path is not None:
            return float(self._path(t))
        return self._start + (self._target - self._start) * t

    def set(self, t: float) -> None:
        """Go to the step's load factor ``t``."""
        self.factor = self.factor_at(t)
        self._apply(self.factor)

    def _apply(self, factor: float) -> None:
        pass

    # -- the protocol's other parts ------------------------------------------------------------
    def attach(self, ctx: Context):
        """The item's residual term (None here), built from the model's ``ctx``."""
        return None

    def nodal(self):
        """(dofs, forces) added to the nodes at the current factor, or None."""
        return None

    def commit(self) -> None:
        pass

    def restore(self) -> None:
        pass

    # -- checkpoints: what the item holds at a converged increment, before it commits -------------
    def save_state(self) -> dict:
        return {"factor": self.factor, "start": self._start}

    def load_state(self, state: dict) -> None:
        """Back to a saved state; the step's ramp must have been set (``ramp``/``hold``) first."""
        self._start = float(state["start"])
        self.set_factor(float(state["factor"]))

    def set_factor(self, factor: float) -> None:
        self.factor = factor
        self._apply(factor)

    def __repr__(self) -> str:
        return f"{type(self).__name__}({self.name or ''})"

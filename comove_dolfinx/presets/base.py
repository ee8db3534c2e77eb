"""Presets: the paper's scenes as parameter sets that build a public-API job (docs/scenes.md).

Units: cm and kgf (stresses in kgf/cm^2), as in Shang & Chen's examples.

Every scene is a dataclass; ``comove scenes`` lists the fields with their defaults and ``--set
key=value`` overrides them. A scene builds its mesh (``mesh_data``), and from it the body, items,
probes and steps of a :class:`comove_dolfinx.Job` (``job``), with the public API only.
"""
from __future__ import annotations

import dataclasses
import math
import os
from dataclasses import dataclass
from typing import ClassVar

from ..deprecated import renamed_field, warn_renamed
from ..mechanics.material_data import Elastic
from ..choices import CONTACT_METHODS as METHODS
from ..choices import FRICTION_LAWS, PREDICTORS, UPDATES, first_increment_error

#: scene parameters that were renamed: old name -> new name (``--set`` still takes the old one)
RENAMED = {"n_steps": "n_increments"}

# dolfinx, gmsh and the rest are imported by the methods that build: checking parameters stays light


#: Young's moduli a scene accepts: the residual's norm squares forces of the order of E (times
#: lengths), which leave double precision (1e-308 to 1e308) beyond about 1e154 and below 1e-154;
#: inside this range the elastica follows its closed form (tests/test_elastica.py)
E_RANGE = (1e-100, 1e100)


class SceneError(ValueError):
    """A scene name or parameter that cannot be used; the message says what to do."""


@renamed_field("n_steps", "n_increments")
@dataclass
class Scene:
    """Parameters shared by every scene (numerics). ``n_steps``, the old name of ``n_increments``,
    is still read and taken by ``--set``, with a DeprecationWarning."""

    name: ClassVar[str] = ""
    summary: ClassVar[str] = ""
    kind: ClassVar[str] = ""
    columns: ClassVar[tuple[str, ...]] = ()
    #: the parameter whose value is the history's ``load`` at the end of the loading
    load_parameter: ClassVar[str] = ""
    #: parameters that shape what a checkpoint holds (the mesh and its fields, the stress update,
    #: the items and their geometry): a restart cannot change them (:meth:`restart_change_error`)
    fixed_at_restart: ClassVar[tuple[str, ...]] = ("mesh", "size", "degree", "order", "update")
    doc: ClassVar[dict[str, str]] = {
        "E": "Young's modulus [kgf/cm^2]", "nu": "Poisson's ratio",
        "update": f"stress update: {', '.join(UPDATES)}",
        "degree": "displacement degree (1 or 2)", "size": "mesh size [cm]",
        "order": "geometry order of the mesh (0: same as degree)",
        "n_increments": "nominal number of equal load increments",
        "max_cutbacks": "halvings of a failed increment before the run stops",
        "first": "the first increment as a fraction 1, 0.5, 0.25, ... of the nominal one (doubled "
                 "back after easy increments)",
        "mesh": "a Gmsh .msh file to use instead of the built-in geometry",
        "predictor": "start of each increment: none (the last converged state), linear or quadratic "
                     "(extrapolation of the last converged states), tangent (Euler step along the "
                     "path's tangent)",
        "retry": "try a failed increment once more from the other start (predictor or last state) "
                 "before halving it",
    }

    E: float = 1000.0
    nu: float = 0.3
    update: str = "sr"
    degree: int = 2
    size: float = 0.125
    order: int = 0
    n_increments: int = 20
    max_cutbacks: int = 6
    first: float = 1.0
    mesh: str = ""
    predictor: str = "none"
    retry: bool = False

    # -- parameters --------------------------------------------------------------------------
    def validate(self) -> None:
        """Raise SceneError (or MaterialError) naming any unusable value and the fix."""
        for f in dataclasses.fields(self):
            v = getattr(self, f.name)
            if isinstance(v, float) and not math.isfinite(v):
                raise SceneError(f"{f.name} = {v}: give a finite number")
        if not 1 <= self.n_increments <= 1_000_000:
            raise SceneError(f"n_increments = {self.n_increments}: give a number of increments from 1 to 1000000")
        if not 0 <= self.max_cutbacks <= 30:
            raise SceneError(f"max_cutbacks = {self.max_cutbacks}: give a number from 0 to 30")
        why = first_increment_error(self.first, self.max_cutbacks)
        if why:
            raise SceneError(why)
        self.elastic()
        if not E_RANGE[0] <= self.E <= E_RANGE[1]:
            raise SceneError(f"E = {self.E:g}: give a Young's modulus from {E_RANGE[0]:g} to {E_RANGE[1]:g} "
                             "(the solver takes norms of forces of the order of E, whose squares must "
                             "stay within double precision): state the scene in other units")
        if self.mesh and not os.path.isfile(self.mesh):
            raise SceneError(f"mesh = {self.mesh!r}: no such file; give the path of a Gmsh .msh file")
        if self.update not in UPDATES:
            raise SceneError(f"update = {self.update!r} is unknown: choose one of {', '.join(UPDATES)}")
        if self.degree not in (1, 2):
            raise SceneError(f"degree = {self.degree}: use 1 or 2")
        if self.order not in (0, 1, 2):
            raise SceneError(f"order = {self.order}: use 1, 2 or 0 (same as degree)")
        if not self.size > 0:
            raise SceneError(f"size = {self.size}: the mesh size must be > 0")
        if self.n_increments < 1:
            raise SceneError(f"n_increments = {self.n_increments}: need at least one increment")
        if self.max_cutbacks < 0:
            raise SceneError(f"max_cutbacks = {self.max_cutbacks} must be >= 0")
        if self.predictor not in PREDICTORS:
            raise SceneError(f"predictor = {self.predictor!r} is unknown: choose one of "
                             f"{', '.join(PREDICTORS)}")

    def elastic(self) -> Elastic:
        return Elastic(self.E, self.nu)

    @property
    def geometry_order(self) -> int:
        return self.order or self.degree

    @classmethod
    def parameters(cls) -> list[tuple[str, object, str]]:
        """(name, default, description) of every parameter."""
        out = []
        for f in dataclasses.fields(cls):
            default = f.default if f.default is not dataclasses.MISSING else f.default_factory()
            out.append((f.name, default, cls.doc.get(f.name, "")))
        return out

    def with_overrides(self, pairs: list[str]) -> "Scene":
        """A copy with ``key=value`` overrides converted to each field's type."""
        types = {f.name: type(f.default) if f.default is not dataclasses.MISSING else str
                 for f in dataclasses.fields(self)}
        changes = {}
        for pair in pairs:
            key, sep, text = pair.partition("=")
            key = key.strip()
            if key in RENAMED:
                warn_renamed(f"the scene parameter {key}", RENAMED[key])
                key = RENAMED[key]
            if not sep:
                raise SceneError(f"--set {pair!r}: write key=value")
            if key not in types:
                raise SceneError(f"scene {self.name!r} has no parameter {key!r}; its parameters are: "
                                 f"{', '.join(types)} (see 'comove scenes')")
            if key in changes:
                raise SceneError(f"--set {key} is given twice ({key}={changes[key]!r} and {pair.strip()!r}): "
                                 "give it once")
            changes[key] = _convert(key, text.strip(), types[key])
        return dataclasses.replace(self, **changes)

    # -- the job ---------------------------------------------------------------------------
    def load_msh(self, comm, required):
        from .. import geometry
        return geometry.load_msh(self.mesh, comm, required=required)

    def mesh_data(self, comm):  # pragma: no cover - interface
        raise NotImplementedError

    def build(self, md) -> tuple:  # pragma: no cover - interface
        """(body, items, probes) of the scene on the mesh ``md``."""
        raise NotImplementedError

    @property
    def load_max(self) -> float:
        """Value of the history's ``load`` column at the end of the loading."""
        return getattr(self, self.load_parameter)

    def restart_change_error(self, key: str, old, reached: float | None) -> str | None:
        """Why the parameter ``key`` cannot go from ``old`` (the checkpoint's run) to this scene's
        value at a restart whose history has reached the load ``reached`` (None: no row), or None.
        The parameters of :attr:`fixed_at_restart` never change; the final load cannot go below the
        load reached, nor change sign."""
        new = getattr(self, key)
        if key in self.fixed_at_restart:
            return (f"{key} cannot change at a restart: it shapes what the checkpoint holds (mesh, "
                    "fields, items): start afresh with --overwrite")
        if key == self.load_parameter and reached is not None and (
                abs(new) < abs(reached) or new * reached < 0):
            return (f"{key} = {new:g} is short of the load the run has reached ({reached:g}): give a final "
                    f"load beyond it")
        return None

    def fibres(self) -> list:
        """(name, reference direction) of the fibres whose normal stress goes to the XDMF output."""
        return []

    def newton_settings(self):
        """Newton settings of the scene (the solver's defaults unless a scene needs others)."""
        from ..solver import NewtonSettings
        return NewtonSettings()

    def steps(self) -> list:
        """One step: every item from 0 to 1 in n_increments nominal increments."""
        from ..job import Step
        return [Step(self.n_increments, predictor=self.predictor, max_cutbacks=self.max_cutbacks, first=self.first,
                     retry=self.retry)]

    def job(self, md, writers=()):
        """The scene as a job on the mesh ``md`` (history ``load`` = load factor x load_max)."""
        from ..job import Job
        body, items, probes = self.build(md)
        self.items = items
        return Job(body, items, self.steps(), probes, writers, newton=self.newton_settings(),
                   load=lambda t, s=self.load_max: t * s)


def _convert(key: str, text: str, typ):
    try:
        if typ is bool:
            if text.lower() in ("1", "true", "yes", "on"):
                return True
            if text.lower() in ("0", "false", "no", "off"):
                return False
            raise ValueError
        return typ(text)
    except ValueError:
        raise SceneError(f"{key}={text!r} is not a valid {typ.__name__}") from None


@dataclass
class ContactScene(Scene):
    """A scene whose body meets rigid obstacles: the contact parameters."""

    doc: ClassVar[dict[str, str]] = {
        **Scene.doc, "gap": "distance from the contact face to the rigid plane [cm]",
        "mu": "Coulomb friction coefficient",
        "contact": f"contact method: {', '.join(METHODS)} or off",
        "gamma0": "contact stiffness gamma0: gamma = gamma0 E / h (penalty and Nitsche)",
        "theta": "Nitsche variant: 1 symmetric, 0, -1 skew-symmetric",
        "relag": "with friction = lagged: re-solve each increment until the lagged pressure settles",
        "friction": "friction law: lagged (the paper's scheme, tangential weight gamma0) or coulomb "
                    "(current pressure, tangential weight min(gamma0, 10))"}

    fixed_at_restart: ClassVar[tuple[str, ...]] = (*Scene.fixed_at_restart, "gap", "contact", "friction")

    gap: float = 1.0
    mu: float = 0.1
    contact: str = "penalty"
    gamma0: float = 100.0
    theta: int = 0
    relag: bool = False
    friction: str = "lagged"

    def validate(self):
        super().validate()
        if self.mu < 0:
            raise SceneError(f"mu = {self.mu}: the friction coefficient must be >= 0")
        if self.contact not in (*METHODS, "off"):
            raise SceneError(f"contact = {self.contact!r}: choose {', '.join(METHODS)} or off")
        if not self.gamma0 > 0:
            raise SceneError(f"gamma0 = {self.gamma0} must be > 0")
        if self.theta not in (1, 0, -1):
            raise SceneError(f"theta = {self.theta}: use 1, 0 or -1")
        if not self.gap >= 0:
            raise SceneError(f"gap = {self.gap}: the obstacle must not start inside the body (gap >= 0)")
        if self.friction not in FRICTION_LAWS:
            raise SceneError(f"friction = {self.friction!r}: choose {' or '.join(FRICTION_LAWS)}")
        if self.relag and self.friction != "lagged":
            raise SceneError("relag = true re-solves the lagged law: set friction = lagged")

    def restart_change_error(self, key: str, old, reached: float | None) -> str | None:
        """As the scene's; besides, friction cannot be switched on or off (``mu`` from or to 0):
        the checkpoint holds the friction history only with friction."""
        if key == "mu" and (old == 0) != (self.mu == 0):
            return ("mu cannot go from or to 0 at a restart: the checkpoint holds a friction history "
                    "only with friction: start afresh with --overwrite")
        return super().restart_change_error(key, old, reached)

    def newton_settings(self):
        """The paper's friction scheme keeps the line search on ||R|| that its stored histories
        were computed with (tests/reference); the solver's default with friction is the energy's."""
        from ..solver import NewtonSettings
        paper = self.contact != "off" and self.friction == "lagged"
        return NewtonSettings(line_search="residual" if paper else None)

    def contact_item(self, boundary: str, obstacle):
        """The contact item of the scene's parameters (None when contact = off)."""
        from ..contact import Contact
        if self.contact == "off":
            return None
        lagged = self.friction == "lagged"        # the paper's scheme, as the paper weighs it
        return Contact(boundary, obstacle, method=self.contact, gamma0=self.gamma0, theta=self.theta,
                       mu=self.mu, relag=self.relag, friction=self.friction,
                       gamma0_t=self.gamma0 if lagged else None)

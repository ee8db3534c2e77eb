"""The scenes: parameters with the defaults of scenes.md, validation, and how each builds its model.

Units: cm and kgf (stresses in kgf/cm^2), as in Shang & Chen's examples.

Every scene is a dataclass; ``comove scenes`` lists the fields with their defaults and ``--set
key=value`` overrides them. A scene builds its mesh (``mesh_data``) and its model (``build_model``),
names the columns of its history and fills the scene-specific ones (``history_row``).
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import ClassVar

import ufl
from mpi4py import MPI

from . import geometry
from .contact import METHODS, Contact, Plane
from .materials import Elastic, Hardening
from .model import Model, Plasticity
from .output import Probe
from .solver import NewtonSettings, StepSettings
from .updates import UPDATES

COMMON_COLUMNS = ("newton_its", "wall_s")


# the scene parameter "predictor" -> StepSettings.predictor
PREDICTORS = {"none": False, "linear": 1, "quadratic": 2, "tangent": "tangent"}


class SceneError(ValueError):
    """A scene name or parameter that cannot be used; the message says what to do."""


@dataclass
class Scene:
    """Parameters shared by every scene (numerics)."""

    name: ClassVar[str] = ""
    summary: ClassVar[str] = ""
    kind: ClassVar[str] = ""
    columns: ClassVar[tuple[str, ...]] = ()
    doc: ClassVar[dict[str, str]] = {
        "E": "Young's modulus [kgf/cm^2]", "nu": "Poisson's ratio",
        "update": f"stress update: {', '.join(UPDATES)}",
        "degree": "displacement degree (1 or 2)", "size": "mesh size [cm]",
        "order": "geometry order of the mesh (0: same as degree)",
        "n_steps": "nominal number of equal load increments",
        "max_cutbacks": "halvings of a failed increment before the run stops",
        "mesh": "a Gmsh .msh file to use instead of the built-in geometry",
        "predictor": "start of each increment: none (the last converged state), linear or quadratic "
                     "(extrapolation of the last converged states), tangent (Euler step along the "
                     "path's tangent)",
    }

    E: float = 1000.0
    nu: float = 0.3
    update: str = "sr"
    degree: int = 2
    size: float = 0.125
    order: int = 0
    n_steps: int = 20
    max_cutbacks: int = 6
    mesh: str = ""
    predictor: str = "none"

    # -- parameters --------------------------------------------------------------------------
    def validate(self) -> None:
        """Raise SceneError (or MaterialError) naming any unusable value and the fix."""
        self.elastic()
        if self.update not in UPDATES:
            raise SceneError(f"update = {self.update!r} is unknown: choose one of {', '.join(UPDATES)}")
        if self.degree not in (1, 2):
            raise SceneError(f"degree = {self.degree}: use 1 or 2")
        if self.order not in (0, 1, 2):
            raise SceneError(f"order = {self.order}: use 1, 2 or 0 (same as degree)")
        if not self.size > 0:
            raise SceneError(f"size = {self.size}: the mesh size must be > 0")
        if self.n_steps < 1:
            raise SceneError(f"n_steps = {self.n_steps}: need at least one increment")
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
            if not sep:
                raise SceneError(f"--set {pair!r}: write key=value")
            if key not in types:
                raise SceneError(f"scene {self.name!r} has no parameter {key!r}; its parameters are: "
                                 f"{', '.join(types)} (see 'comove scenes')")
            changes[key] = _convert(key, text.strip(), types[key])
        return dataclasses.replace(self, **changes)

    # -- model -------------------------------------------------------------------------------
    def load_msh(self, comm, required):
        return geometry.load_msh(self.mesh, comm, required=required)

    def mesh_data(self, comm):  # pragma: no cover - interface
        raise NotImplementedError

    def build_model(self, meshdata) -> Model:  # pragma: no cover - interface
        raise NotImplementedError

    @property
    def load_max(self) -> float:
        """Value of the history's ``load`` column at load factor 1."""
        raise NotImplementedError

    def history_columns(self) -> list[str]:
        return ["step", "load", *self.columns, *COMMON_COLUMNS]

    def history_row(self, model) -> dict:  # pragma: no cover - interface
        raise NotImplementedError

    def contacts(self) -> list:
        """The contact terms of the built model (none for a scene without obstacles)."""
        return []

    def fibres(self, model) -> list:
        """(name, reference direction) of the fibres whose normal stress goes to the XDMF output."""
        return []

    def newton_settings(self) -> NewtonSettings:
        """Newton settings of the scene (the solver's defaults unless a scene needs others)."""
        return NewtonSettings()

    def step_settings(self) -> StepSettings:
        """Increment control of the scene: n_steps nominal increments, max_cutbacks halvings."""
        return StepSettings(n_steps=self.n_steps, max_cutbacks=self.max_cutbacks,
                            predictor=PREDICTORS[self.predictor])


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



def _check_strip(scene) -> None:
    if not (scene.L > 0 and scene.h > 0):
        raise SceneError(f"L = {scene.L}, h = {scene.h}: both must be > 0")


def _strip_mesh(scene, comm, need):
    """The L x h rectangle of the cantilever scenes, or the user's mesh with the ``need`` tags."""
    if scene.mesh:
        return scene.load_msh(comm, need)
    return geometry.rectangle(scene.L, scene.h, scene.size, order=scene.geometry_order, comm=comm)


# ------------------------------------------------------------------------------------------------
@dataclass
class Elastica(Scene):
    """Verification: cantilever under a dead vertical tip load (Mattiasson's elastica, theory 7.1)."""

    name: ClassVar[str] = "elastica"
    summary: ClassVar[str] = ("cantilever L=10, h=0.25 (plane stress), dead tip load "
                              "lam = P L^2/(E I); compare with the elastica")
    kind: ClassVar[str] = "plane_stress"
    columns: ClassVar[tuple[str, ...]] = ("tip_ux", "tip_uy")
    doc: ClassVar[dict[str, str]] = {**Scene.doc, "L": "length [cm]", "h": "depth [cm]",
                                     "lam": "final load parameter P L^2/(E I)"}

    L: float = 10.0
    h: float = 0.25
    lam: float = 5.0
    n_steps: int = 10
    predictor: str = "tangent"     # 5.5 Newton iterations per increment, 6.8 from the last state

    def validate(self):
        super().validate()
        _check_strip(self)

    def mesh_data(self, comm):
        return _strip_mesh(self, comm, ("left", "right"))

    @property
    def load_max(self):
        return self.lam

    def build_model(self, md):
        m = Model(md, self.kind, self.elastic(), update=self.update, degree=self.degree)
        EI = self.E * self.h ** 3 / 12.0
        P = self.lam * EI / self.L ** 2
        m.fix("left")
        m.dead_traction("right", (0.0, -P / self.h))   # total P per unit thickness, downwards
        self._tip = Probe(m.V, (self.L, 0.5 * self.h))
        return m

    def history_row(self, model):
        ux, uy = self._tip(model.u)
        return {"tip_ux": ux, "tip_uy": uy}

    def fibres(self, model):
        return [("fibre_stress", (1.0, 0.0))]       # along the deformed beam axis


@dataclass
class ContactScene(Scene):
    """A scene whose body meets rigid obstacles: the contact parameters."""

    doc: ClassVar[dict[str, str]] = {
        **Scene.doc, "gap": "distance from the contact face to the rigid plane [cm]",
        "mu": "Coulomb friction coefficient",
        "contact": f"contact method: {', '.join(METHODS)} or off",
        "gamma0": "contact stiffness gamma0: gamma = gamma0 E / h (penalty and Nitsche)",
        "theta": "Nitsche variant: 1 symmetric, 0, -1 skew-symmetric",
        "relag": "true Coulomb: re-solve each increment until the lagged pressure settles"}

    gap: float = 1.0
    mu: float = 0.1
    contact: str = "penalty"
    gamma0: float = 100.0
    theta: int = 0
    relag: bool = False

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

    def contacts(self) -> list:
        term = getattr(self, "contact_term", None)
        return [term] if term is not None else []

    def add_contact(self, model, boundary: str, obstacle) -> Contact | None:
        """Attach a contact term (or nothing when contact = off)."""
        if self.contact == "off":
            return None
        c = Contact(boundary, obstacle, method=self.contact, gamma0=self.gamma0, theta=self.theta,
                    mu=self.mu, relag=self.relag)
        model.boundary_terms.append(c)
        return c


@dataclass
class Beam(ContactScene):
    """Cantilever pressed onto a rigid foundation by a follower pressure (scenes.md)."""

    name: ClassVar[str] = "beam"
    summary: ClassVar[str] = ("cantilever L=10, h=0.5 (plane stress) under follower pressure q "
                              "up to 0.5, rigid plane 3 below, mu = 0.1")
    kind: ClassVar[str] = "plane_stress"
    columns: ClassVar[tuple[str, ...]] = ("tip_ux", "tip_uy", "contact_length", "contact_force")
    doc: ClassVar[dict[str, str]] = {**ContactScene.doc, "L": "length [cm]", "h": "depth [cm]",
                                     "q_max": "final pressure on the upper face [kgf/cm^2]"}

    L: float = 10.0
    h: float = 0.5
    q_max: float = 0.5
    gap: float = 3.0

    def validate(self):
        super().validate()
        _check_strip(self)

    def mesh_data(self, comm):
        return _strip_mesh(self, comm, ("left", "top", "bottom"))

    @property
    def load_max(self):
        return self.q_max

    def build_model(self, md):
        m = Model(md, self.kind, self.elastic(), update=self.update, degree=self.degree)
        m.fix("left")
        m.follower_pressure("top", self.q_max)
        self.contact_term = self.add_contact(m, "bottom", Plane((0.0, -self.gap), (0.0, 1.0)))
        self._tip = Probe(m.V, (self.L, 0.0))
        return m

    def history_row(self, model):
        ux, uy = self._tip(model.u)
        c = self.contact_term
        length = c.zone().extent if c else 0.0
        force = c.force()[1] if c else 0.0
        return {"tip_ux": ux, "tip_uy": uy, "contact_length": length, "contact_force": force}

    def fibres(self, model):
        return [("fibre_stress", (1.0, 0.0))]       # along the deformed beam axis


@dataclass
class Plate(ContactScene):
    """Thick circular plate pressed onto a rigid base (axisymmetric, scenes.md)."""

    name: ClassVar[str] = "plate"
    summary: ClassVar[str] = ("circular plate R=10, t=2 (axisymmetric), follower pressure p up to "
                              "10, lower rim held in z, rigid base 1.5 below, mu = 0.1")
    kind: ClassVar[str] = "axisymmetric"
    columns: ClassVar[tuple[str, ...]] = ("center_uz", "contact_radius", "rim_ur", "contact_force")
    doc: ClassVar[dict[str, str]] = {**ContactScene.doc, "R": "radius [cm]", "t": "thickness [cm]",
                                     "z_support": "height of the supported part of the rim [cm]",
                                     "p_max": "final pressure on the upper face [kgf/cm^2]"}

    R: float = 10.0
    t: float = 2.0
    z_support: float = 0.25
    p_max: float = 10.0
    gap: float = 1.5
    size: float = 0.25
    # From the last converged state: the tangent start takes 6.4 Newton iterations per increment
    # against 8.6 at the default gamma0, but with gamma0 = 1000 it stalls at p = 9.5 in stick-slip
    # cycling (bench contact), where this start completes the run.

    def validate(self):
        super().validate()
        if not (self.R > 0 and self.t > 0 and 0 < self.z_support < self.t):
            raise SceneError(f"R = {self.R}, t = {self.t}, z_support = {self.z_support}: need R, t > 0 "
                             "and 0 < z_support < t")

    def mesh_data(self, comm):
        need = ("axis", "top", "bottom", "rim_support")
        if self.mesh:
            return self.load_msh(comm, need)
        return geometry.plate_section(self.R, self.t, self.z_support, self.size,
                                      order=self.geometry_order, comm=comm)

    @property
    def load_max(self):
        return self.p_max

    def build_model(self, md):
        m = Model(md, self.kind, self.elastic(), update=self.update, degree=self.degree)
        m.fix("axis", component=0)            # u_r = 0 on the axis of symmetry
        m.fix("rim_support", component=1)     # lower part of the rim: u_z = 0, free in r
        m.follower_pressure("top", self.p_max)
        self.contact_term = self.add_contact(m, "bottom", Plane((0.0, -self.gap), (0.0, 1.0)))
        self._center = Probe(m.V, (0.0, 0.0))
        self._rim = Probe(m.V, (self.R, 0.0))
        return m

    def history_row(self, model):
        c = self.contact_term
        radius, force = 0.0, 0.0
        if c:
            radius = c.zone().extent       # the contact set is a disc around the axis
            force = c.force()[1]
        return {"center_uz": self._center(model.u)[1], "contact_radius": radius,
                "rim_ur": self._rim(model.u)[0], "contact_force": force}

    def fibres(self, model):
        return [("radial_stress", (1.0, 0.0))]      # along the deformed radius (bending stress)


# Representative mild steel of scenes.md: equivalent plastic strain -> yield stress [kgf/cm^2]
RING_HARDENING = "0:2800, 0.01:3000, 0.05:3600, 0.1:4000, 0.2:4500, 0.5:5300"


def parse_table(text: str) -> Hardening:
    """A hardening table written ``p0:s0, p1:s1, ...`` (flat beyond the last point)."""
    try:
        pairs = [item.split(":") for item in text.replace(";", ",").split(",") if item.strip()]
        strain, stress = zip(*[(float(a), float(b)) for a, b in pairs])
    except ValueError:
        raise SceneError(f"hardening = {text!r}: write the table as strain:stress pairs separated "
                         "by commas, e.g. 0:2800,0.01:3000") from None
    return Hardening(strain, stress)


@dataclass
class Ring(ContactScene):
    """Metal ring crushed between rigid plates (quarter, plane strain, elastic-plastic; scenes.md).

    The quarter x, y >= 0 carries u_x = 0 on x = 0 and u_y = 0 on y = 0 (the lower plate's half of
    the crush is taken by symmetry); the upper plate starts tangent at the crown (0, R_out) and moves
    down by delta / 2. History: P = 2 x (vertical force on the quarter) per unit axial length,
    contact_width = 2 x (contact length on the quarter) across the whole plate, crown_gap = distance
    between the crown and the plate (> 0 once the crown lifts off and contact splits into two zones).
    """

    name: ClassVar[str] = "ring"
    summary: ClassVar[str] = ("ring OD 11.43, wall 0.866 (quarter, plane strain, J2 mild steel) "
                              "crushed between rigid plates to delta = 6.6, mu = 0.1")
    kind: ClassVar[str] = "plane_strain"
    columns: ClassVar[tuple[str, ...]] = ("force", "contact_width", "crown_gap", "max_plastic_strain")
    doc: ClassVar[dict[str, str]] = {
        **ContactScene.doc, "gap": "initial gap between the crown and the upper plate [cm]",
        "R_out": "outer radius [cm]", "wall": "wall thickness [cm]",
        "delta_max": "final approach of the two plates [cm]",
        "hardening": "yield stress table p:sigma_y [kgf/cm^2], flat beyond the last point",
        "law": "plasticity: j2 (return mapping) or chen (Chen's single-parameter rate law: no "
               "return to the yield surface, so its error is first order in the increment; "
               "give it about 16 x the increments of j2, see README)",
        "plane": "plane_strain or plane_stress"}

    E: float = 1.89e6
    nu: float = 0.3
    size: float = 0.22
    n_steps: int = 36
    gap: float = 0.0
    gamma0: float = 1.0
    R_out: float = 5.715
    wall: float = 0.866
    delta_max: float = 6.6
    hardening: str = RING_HARDENING
    law: str = "j2"
    plane: str = "plane_strain"
    # The crush is a smooth path: each increment starts from the Euler step along its tangent, 4.4
    # Newton iterations per increment at the default 36 increments; from the quadratic extrapolation
    # of the last converged states 5.6 (same increments, same P); from the last converged state
    # alone 211 increments at 11.4 (its elastic tangent overshoots into the hinges' mechanism).
    predictor: str = "tangent"

    def validate(self):
        super().validate()
        if not (self.R_out > 0 and 0 < self.wall < self.R_out):
            raise SceneError(f"R_out = {self.R_out}, wall = {self.wall}: need 0 < wall < R_out")
        if not self.delta_max > 0:
            raise SceneError(f"delta_max = {self.delta_max} must be > 0")
        if self.law not in ("j2", "chen"):
            raise SceneError(f"law = {self.law!r}: choose j2 or chen")
        if self.plane not in ("plane_strain", "plane_stress"):
            raise SceneError(f"plane = {self.plane!r}: choose plane_strain or plane_stress")
        if self.update not in ("sr", "hughes_winget"):
            raise SceneError(f"update = {self.update!r} cannot carry plasticity: use sr or hughes_winget")
        self.table()

    def table(self) -> Hardening:
        return parse_table(self.hardening)

    def newton_settings(self) -> NewtonSettings:
        # Travelling plastic hinges: the first corrections of an increment overshoot (points at the
        # hinges' borders switch between loading and unloading, free boundary points swing into
        # the plate); Crisfield's energy line search scales them back. Convergence: out-of-balance
        # force below 1e-3 of the forces carried (||F_int||): P within 0.003 % of a run converged to
        # 1e-6 (0.06 % at 40 increments; bench ring_tolerance), where 5e-3 puts up to 2.2 % into P.
        # gamma0 = 0.1 would take 3.9 iterations per increment instead of 4.4, but its penetration
        # (2.5e-3) delays the crown's lift-off from delta = 1.49 to 1.55 (bench ring_newton).
        return NewtonSettings(line_search="energy", energy_eta=0.2, scale="force", rtol=1e-3)

    def mesh_data(self, comm):
        need = ("xsym", "ysym", "outer")
        if self.mesh:
            return self.load_msh(comm, need)
        return geometry.annulus_sector(self.R_out - self.wall, self.R_out, self.size,
                                       order=self.geometry_order, comm=comm)

    @property
    def load_max(self):
        return self.delta_max

    def build_model(self, md):
        m = Model(md, self.plane, self.elastic(), update=self.update, degree=self.degree,
                  plasticity=Plasticity(self.table(), self.law))
        m.fix("xsym", component=0)
        m.fix("ysym", component=1)
        plate = Plane((0.0, self.R_out + self.gap), (0.0, -1.0),
                      motion=(0.0, -0.5 * self.delta_max))
        self._plate = plate
        self.contact_term = self.add_contact(m, "outer", plate)
        self._crown = Probe(m.V, (0.0, self.R_out))
        return m

    def history_row(self, model):
        c = self.contact_term
        force = width = 0.0
        if c:
            force = -2.0 * c.force()[1]            # the plate pushes the quarter down
            width = 2.0 * c.zone().extent
        uy = self._crown(model.u)[1]
        plate_y = self.R_out + self.gap - 0.5 * self.delta_max * model.load
        crown_gap = plate_y - (self.R_out + uy)
        p = model.p.x.array
        pmax = model.comm.allreduce(float(p.max()) if p.size else 0.0, op=MPI.MAX)
        return {"force": force, "contact_width": width, "crown_gap": crown_gap,
                "max_plastic_strain": pmax}

    def fibres(self, model):
        x = model.x
        r = ufl.sqrt(x[0] ** 2 + x[1] ** 2)
        return [("hoop_stress", (-x[1] / r, x[0] / r))]   # along the deformed ring's circumference


def split_delta(load, crown_gap, contact_width) -> float | None:
    """The approach at which the ring's contact zone splits for good: the last opening of the crown
    gap (contact elsewhere), after which it stays open, interpolated linearly between the two
    increments around it (the crown lifts off gradually; the increment alone resolves it to 0.22).
    A stiff penalty lets the crown flicker open by round-off amounts early on; those close again
    and do not count. None if the crown is closed at the end."""
    split, prev = None, (0.0, -1.0)
    for d, g, w in zip(load, crown_gap, contact_width):
        if g > 0 and w > 0:
            if split is None:
                d0, g0 = prev
                split = d0 + (d - d0) * (-g0) / (g - g0) if g0 <= 0 else d
        else:
            split = None
        prev = (d, g)
    return split


SCENES: dict[str, type[Scene]] = {cls.name: cls for cls in (Beam, Plate, Ring, Elastica)}


def get_scene(name: str, overrides: list[str] = ()) -> Scene:
    """The scene called ``name`` with ``key=value`` overrides, validated."""
    if name not in SCENES:
        raise SceneError(f"unknown scene {name!r}: choose one of {', '.join(SCENES)}")
    scene = SCENES[name]().with_overrides(list(overrides))
    scene.validate()
    return scene



"""The four scenes of docs/scenes.md, each built with the public API (body, items, probes)."""
from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

from ..checks import mesh_size_error
from ..mechanics.material_data import Hardening, MaterialError
from ..choices import LAWS, PLASTIC_UPDATES
from .base import ContactScene, Scene, SceneError

# What builds a scene (dolfinx, gmsh, UFL) is imported by the methods that build (`from .build
# import ...`): creating and checking a scene's parameters stays light.


def _check_strip(scene) -> None:
    if not (scene.L > 0 and scene.h > 0):
        raise SceneError(f"L = {scene.L}, h = {scene.h}: both must be > 0")
    _check_cells(scene, "rectangle", L=scene.L, H=scene.h)


def _check_cells(scene, builder: str, **params) -> None:
    """SceneError when the scene's built-in mesh would have more cells than a mesh may have
    (checks.mesh_size_error, estimated before gmsh runs); nothing with a mesh file of the user's."""
    why = None if scene.mesh else mesh_size_error(builder, {**params, "size": scene.size})
    if why is not None:
        raise SceneError(why)


def _check_small_against_E(scene, name: str, value: float) -> None:
    """A load or yield stress of the order of Young's modulus (a strain of 100 % or more from it
    alone) is a units mistake, not a problem this model answers: refuse it before the run goes to NaN."""
    if abs(value) >= scene.E:
        raise SceneError(f"{name} = {value} is not small against E = {scene.E}: a stress of the order of "
                         "Young's modulus strains the body by 100 % or more; check the units of both (kgf/cm^2)")


def _strip_mesh(scene, comm, need):
    """The L x h rectangle of the cantilever scenes, or the user's mesh with the ``need`` tags."""
    from .build import geometry
    if scene.mesh:
        return scene.load_msh(comm, need)
    return geometry.rectangle(scene.L, scene.h, scene.size, order=scene.geometry_order, comm=comm)


# ------------------------------------------------------------------------------------------------
@dataclass
class Elastica(Scene):
    """Verification: cantilever under a dead vertical tip load (Mattiasson's elastica, docs/theory.md section 8.1)."""

    name: ClassVar[str] = "elastica"
    load_parameter: ClassVar[str] = "lam"
    fixed_at_restart: ClassVar[tuple[str, ...]] = (*Scene.fixed_at_restart, "L", "h")
    summary: ClassVar[str] = ("cantilever L=10, h=0.25 (plane stress), dead tip load "
                              "lam = P L^2/(E I); compare with the elastica")
    kind: ClassVar[str] = "plane_stress"
    columns: ClassVar[tuple[str, ...]] = ("tip_ux", "tip_uy")
    doc: ClassVar[dict[str, str]] = {**Scene.doc, "L": "length [cm]", "h": "depth [cm]",
                                     "lam": "final load parameter P L^2/(E I)"}

    L: float = 10.0
    h: float = 0.25
    lam: float = 5.0
    n_increments: int = 10
    predictor: str = "tangent"     # 4.8 Newton iterations per increment, 6.8 from the last state

    def validate(self):
        super().validate()
        _check_strip(self)

    def mesh_data(self, comm):
        return _strip_mesh(self, comm, ("left", "right"))

    def build(self, md):
        from .build import Body, Fixed, NodeDisplacement, Traction
        body = Body(md, self.kind, self.elastic(), update=self.update, degree=self.degree)
        P = self.lam * self.E * self.h ** 3 / 12.0 / self.L ** 2      # lam = P L^2 / (E I)
        items = [Fixed("left"),
                 Traction("right", (0.0, -P / self.h))]                 # total P per unit thickness
        return body, items, [NodeDisplacement("tip", (self.L, 0.5 * self.h))]

    def fibres(self):
        return [("fibre_stress", (1.0, 0.0))]       # along the deformed beam axis


@dataclass
class Beam(ContactScene):
    """Cantilever pressed onto a rigid foundation by a follower pressure (docs/scenes.md)."""

    name: ClassVar[str] = "beam"
    load_parameter: ClassVar[str] = "q_max"
    fixed_at_restart: ClassVar[tuple[str, ...]] = (*ContactScene.fixed_at_restart, "L", "h")
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
        _check_small_against_E(self, "q_max", self.q_max)

    def mesh_data(self, comm):
        return _strip_mesh(self, comm, ("left", "top", "bottom"))

    def build(self, md):
        from .build import Body, ContactForce, ContactLength, Fixed, NodeDisplacement, Plane, Pressure, or_zero
        body = Body(md, self.kind, self.elastic(), update=self.update, degree=self.degree)
        items = [Fixed("left"), Pressure("top", self.q_max)]
        contact = self.contact_item("bottom", Plane((0.0, -self.gap), (0.0, 1.0)))
        probes = [NodeDisplacement("tip", (self.L, 0.0))]
        probes += or_zero(contact, ContactLength(contact), ContactForce(contact))
        items += [contact] if contact else []
        return body, items, probes

    def fibres(self):
        return [("fibre_stress", (1.0, 0.0))]       # along the deformed beam axis


@dataclass
class Plate(ContactScene):
    """Thick circular plate pressed onto a rigid base (axisymmetric, docs/scenes.md)."""

    name: ClassVar[str] = "plate"
    load_parameter: ClassVar[str] = "p_max"
    fixed_at_restart: ClassVar[tuple[str, ...]] = (*ContactScene.fixed_at_restart, "R", "t", "z_support")
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
    # cycling (measured by an earlier contact benchmark), where this start completes the run.

    def validate(self):
        super().validate()
        if not (self.R > 0 and self.t > 0 and 0 < self.z_support < self.t):
            raise SceneError(f"R = {self.R}, t = {self.t}, z_support = {self.z_support}: need R, t > 0 "
                             "and 0 < z_support < t")
        _check_cells(self, "plate_section", R=self.R, t=self.t, z_support=self.z_support)
        _check_small_against_E(self, "p_max", self.p_max)

    def mesh_data(self, comm):
        need = ("axis", "top", "bottom", "rim_support")
        if self.mesh:
            return self.load_msh(comm, need)
        from .build import geometry
        return geometry.plate_section(self.R, self.t, self.z_support, self.size,
                                      order=self.geometry_order, comm=comm)

    def build(self, md):
        from .build import Body, ContactForce, ContactLength, Fixed, NodeDisplacement, Plane, Pressure, or_zero
        body = Body(md, self.kind, self.elastic(), update=self.update, degree=self.degree)
        items = [Fixed("axis", component=0),           # u_r = 0 on the axis of symmetry
                 Fixed("rim_support", component=1),    # lower part of the rim: u_z = 0, free in r
                 Pressure("top", self.p_max)]
        contact = self.contact_item("bottom", Plane((0.0, -self.gap), (0.0, 1.0)))
        probes = [NodeDisplacement("center", (0.0, 0.0), component=1, column="center_uz")]
        probes += or_zero(contact, ContactLength(contact, "contact_radius"))
        probes.append(NodeDisplacement("rim", (self.R, 0.0), component=0, column="rim_ur"))
        probes += or_zero(contact, ContactForce(contact))
        items += [contact] if contact else []
        return body, items, probes

    def fibres(self):
        return [("radial_stress", (1.0, 0.0))]      # along the deformed radius (bending stress)


# Representative mild steel of docs/scenes.md: equivalent plastic strain -> yield stress [kgf/cm^2]
RING_HARDENING = "0:2800, 0.01:3000, 0.05:3600, 0.1:4000, 0.2:4500, 0.5:5300"


def parse_table(text: str) -> Hardening:
    """A hardening table written ``p0:s0, p1:s1, ...`` (flat beyond the last point)."""
    try:
        pairs = [item.split(":") for item in text.replace(";", ",").split(",") if item.strip()]
        strain, stress = zip(*[(float(a), float(b)) for a, b in pairs])
    except ValueError:
        raise SceneError(f"hardening = {text!r}: write the table as strain:stress pairs separated "
                         "by commas, e.g. 0:2800,0.01:3000") from None
    try:
        return Hardening(strain, stress)
    except MaterialError as err:              # named with the parameter the user wrote
        raise SceneError(f"hardening = {text!r}: {err}") from None


@dataclass
class Ring(ContactScene):
    """Metal ring crushed between rigid plates (quarter, plane strain, elastic-plastic; docs/scenes.md).

    The quarter x, y >= 0 carries u_x = 0 on x = 0 and u_y = 0 on y = 0 (the lower plate's half of
    the crush is taken by symmetry); the upper plate starts tangent at the crown (0, R_out) and moves
    down by delta / 2. History: P = 2 x (vertical force on the quarter) per unit axial length,
    contact_width = 2 x (contact length on the quarter) across the whole plate, crown_gap = distance
    between the crown and the plate (> 0 once the crown lifts off and contact splits into two zones).
    """

    name: ClassVar[str] = "ring"
    load_parameter: ClassVar[str] = "delta_max"
    fixed_at_restart: ClassVar[tuple[str, ...]] = (*ContactScene.fixed_at_restart, "R_out", "wall", "law", "plane")
    summary: ClassVar[str] = ("ring OD 11.43, wall 0.866 (quarter, plane strain, J2 mild steel) "
                              "crushed between rigid plates to delta = 6.6, mu = 0.1")
    kind: ClassVar[str] = "plane_strain"
    columns: ClassVar[tuple[str, ...]] = ("force", "contact_width", "crown_gap", "max_plastic_strain")
    doc: ClassVar[dict[str, str]] = {
        **ContactScene.doc, "gap": "initial gap between the crown and the upper plate [cm]",
        "R_out": "outer radius [cm]", "wall": "wall thickness [cm]",
        "delta_max": "final approach of the two plates [cm]",
        "hardening": "yield stress table p:sigma_y [kgf/cm^2], flat beyond the last point",
        "law": "plasticity: j2 (return mapping on the hardening table) or chen (Chen's "
               "single-parameter rate law: the return on its own loading surface, docs/theory.md 4.4)",
        "plane": "plane_strain or plane_stress"}

    E: float = 1.89e6
    nu: float = 0.3
    size: float = 0.22
    n_increments: int = 36
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
    # The first increment is an eighth of the nominal: the crown's point contact yields at once, and
    # Newton's corrections there overshoot into elastic unloading (the energy search cuts them to a
    # tenth). At half the nominal the first attempt still failed at 5k, 18k and 45k dofs (10-13
    # iterations) and took 18 iterations with 64 residual evaluations at 1.4k; from an eighth no
    # attempt fails at any of those sizes, and the whole crush takes 156 instead of 163 iterations,
    # 223 instead of 267 residuals at 1.4k (docs/performance.md, "The ring's first increment").
    first: float = 0.125

    def validate(self):
        super().validate()
        if not (self.R_out > 0 and 0 < self.wall < self.R_out):
            raise SceneError(f"R_out = {self.R_out}, wall = {self.wall}: need 0 < wall < R_out")
        _check_cells(self, "annulus_sector", r_in=self.R_out - self.wall, r_out=self.R_out)
        if not self.delta_max > 0:
            raise SceneError(f"delta_max = {self.delta_max} must be > 0")
        if self.law not in LAWS:
            raise SceneError(f"law = {self.law!r}: choose {' or '.join(LAWS)}")
        if self.plane not in ("plane_strain", "plane_stress"):
            raise SceneError(f"plane = {self.plane!r}: choose plane_strain or plane_stress")
        if self.update not in PLASTIC_UPDATES:
            raise SceneError(f"update = {self.update!r} cannot carry plasticity: use one of "
                             f"{', '.join(PLASTIC_UPDATES)}")
        _check_small_against_E(self, "the initial yield stress", self.table().stress[0])

    def table(self) -> Hardening:
        return parse_table(self.hardening)

    def newton_settings(self):
        # Travelling plastic hinges: the first corrections of an increment overshoot (points at the
        # hinges' borders switch between loading and unloading, free boundary points swing into
        # the plate); Crisfield's energy line search scales them back. Convergence: out-of-balance
        # force below 1e-3 of the forces carried (||F_int||): P within 0.003 % of a run converged to
        # 1e-6 (0.06 % at 40 increments, measured by an earlier tolerance study), where 5e-3 puts up to 2.2 % into P.
        # gamma0 = 0.1 would take 3.9 iterations per increment instead of 4.4, but its penetration
        # (2.5e-3) delays the crown's lift-off from delta = 1.49 to 1.55 (measured by an earlier Newton study).
        from .build import NewtonSettings
        return NewtonSettings(line_search="energy", energy_eta=0.2, scale="force", rtol=1e-3)

    def mesh_data(self, comm):
        need = ("xsym", "ysym", "outer")
        if self.mesh:
            return self.load_msh(comm, need)
        from .build import geometry
        return geometry.annulus_sector(self.R_out - self.wall, self.R_out, self.size,
                                       order=self.geometry_order, comm=comm)

    def build(self, md):
        from .build import (Body, ContactForce, ContactLength, CrownGap, Fixed, MaxPlasticStrain,
                            Plane, as_material, or_zero)
        material = as_material(self.E, self.nu, self.law, self.table())
        body = Body(md, self.plane, material, update=self.update, degree=self.degree)
        items = [Fixed("xsym", component=0), Fixed("ysym", component=1)]
        # the upper plate, tangent to the crown (0, R_out) plus the gap, moves down by delta / 2
        plate = Plane((0.0, self.R_out + self.gap), (0.0, -1.0), motion=(0.0, -0.5 * self.delta_max))
        contact = self.contact_item("outer", plate)
        items += [contact] if contact else []
        probes = or_zero(contact, ContactForce(contact, "force", scale=-2.0),     # both plates' halves
                         ContactLength(contact, "contact_width", scale=2.0))
        return body, items, probes + [CrownGap(self), MaxPlasticStrain()]

    def fibres(self):
        def hoop(x):                   # along the deformed ring's circumference
            import ufl
            r = ufl.sqrt(x[0] ** 2 + x[1] ** 2)
            return (-x[1] / r, x[0] / r)
        return [("hoop_stress", hoop)]


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



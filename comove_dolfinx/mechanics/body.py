"""A body: its mesh, the model (2D or 3D), the material, the stress update and the discretisation."""
from __future__ import annotations

from dataclasses import dataclass

from .. import compat
from ..checks import first, number
from ..choices import PLASTIC_UPDATES as ROTATING_UPDATES  # noqa: E402  (they carry a rotated old stress)
from .kinematics import MODELS
from .material_data import Elastic, MaterialError
from .materials import Plastic
from .updates import UPDATES


class BodyError(ValueError):
    """A body that cannot be built; the message names the value and the fix."""


@dataclass
class Body:
    """A solid: plane, axisymmetric or three-dimensional.

    Parameters
    ----------
    mesh : geometry.MeshData
        Mesh with named facet groups (``comove_dolfinx.geometry`` builds, reads or wraps one):
        triangles (or quadrilaterals) for the 2D models, tetrahedra or hexahedra for "solid".
    kind : str
        "plane_strain", "plane_stress" (forces per unit thickness), "axisymmetric" (x = r, y = z;
        forces are totals over the circumference) or "solid" (3D: three displacement components,
        the full 3x3 kinematics; docs/theory.md section 1.4).
    material : Elastic, J2 or Chen
        Elastic constants, or an elastic-plastic law with its hardening.
    update : str
        Stress update: "sr_log" (Chen's S-R decomposition of the increment with its strain measured
        logarithmically, the default), "sr" (the S-R update as the paper writes it), "hughes_winget",
        "polar", "svk", "neo_hooke" (docs/theory.md section 3), or "small_strain" (linear
        kinematics, section 3.5). Plastic bodies need sr_log, sr, hughes_winget or small_strain.
    degree : int
        Lagrange degree of the displacement, 1 or 2 (P1 locks in bending, and in plastic flow
        except in plane stress: docs/verification.md, the flat punch).
    thickness : float
        Out-of-plane thickness of plane models (ignored in 3D).
    quadrature_degree : int, optional
        Of the volume integrals, 1 to 30; by default 2 (3 points, exact P2 small-strain stiffness),
        3 in axisymmetry (the weight r), 1 for P1 (in 3D: 2 for P2, the 4-point rule, 1 for P1; on
        quadrilaterals and hexahedra the full Gauss rules, 4 (3 x 3 (x 3) points) for Q2 and 2
        (2 x 2 (x 2)) for Q1, one more in axisymmetry: fewer points leave the cells modes without
        stiffness).
    fbar : bool
        F-bar (B-bar under linear kinematics): the stress sees the volume change averaged over
        each cell (mechanics/volume.py, docs/theory.md section 5.5), which lifts the volumetric
        locking of Q1 quadrilaterals and hexahedra in plastic flow (docs/verification.md, the flat
        punch). Not for plane stress (which does not lock), P1 triangles and tetrahedra (one
        volume change per cell already: use ``degree=2``) or Nitsche contact.

    Every value is checked here: one that cannot be used raises :class:`BodyError` (or
    ``MaterialError``) naming it and the fix.
    """

    mesh: object
    kind: str = "plane_strain"
    material: object = None
    update: str = "sr_log"
    degree: int = 2
    thickness: float = 1.0
    quadrature_degree: int | None = None
    fbar: bool = False

    def __post_init__(self):
        if not all(hasattr(self.mesh, a) for a in ("mesh", "facet_tags", "tags")):
            raise BodyError(f"mesh = {self.mesh!r}: give a MeshData (cm.rectangle, cm.load_msh; a dolfinx "
                            "mesh through cm.from_dolfinx(mesh, facet_tags, names))")
        if not isinstance(self.kind, str) or self.kind not in MODELS:
            raise BodyError(f"kind = {self.kind!r} is unknown: choose one of {', '.join(MODELS)}")
        dim = self.mesh.mesh.topology.dim
        if (self.kind == "solid") != (dim == 3):
            want = "a 3D mesh of tetrahedra or hexahedra (cm.box)" if self.kind == "solid" else \
                "a 2D mesh (or kind = 'solid' for a 3D one)"
            raise BodyError(f"kind = {self.kind!r} on a mesh of dimension {dim}: give {want}")
        if not isinstance(self.material, (Elastic, Plastic)):
            raise BodyError(f"material = {self.material!r}: give Elastic(E, nu), J2(E, nu, hardening) "
                            "or Chen(E, nu, hardening)")
        if not isinstance(self.update, str) or self.update not in UPDATES:
            raise BodyError(f"update = {self.update!r} is unknown: choose one of {', '.join(UPDATES)}")
        if self.plastic is not None and self.update not in ROTATING_UPDATES:
            raise MaterialError(f"update {self.update!r} cannot carry plasticity: use one of "
                                f"{', '.join(ROTATING_UPDATES)}")
        if number("degree", self.degree, whole=True) or self.degree not in (1, 2):
            raise BodyError(f"degree = {self.degree!r}: use 1 or 2")
        why = first(number("thickness", self.thickness, gt=0),
                    None if self.quadrature_degree is None else number(
                        "quadrature_degree", self.quadrature_degree, ge=1, le=30, whole=True,
                        what=" (or None: the default of the degree and kind)"))
        if why:
            raise BodyError(why)
        if self.fbar not in (True, False):
            raise BodyError(f"fbar = {self.fbar!r}: give True (the volume change averaged over each cell) "
                            "or False")
        if self.fbar:
            self._check_fbar()

    def _check_fbar(self) -> None:
        """BodyError where F-bar does not apply."""
        if self.kind == "plane_stress":
            raise BodyError("fbar = True in plane stress: the thickness takes the volume change, so plane "
                            "stress does not lock; leave fbar out")
        simplex = compat.cell_name(self.mesh.mesh) in ("triangle", "tetrahedron")
        if simplex and self.degree == 1:
            raise BodyError("fbar = True on P1 triangles or tetrahedra changes nothing (their volume change "
                            "is one per cell already): use degree=2, which does not lock, or Q1 "
                            "quadrilaterals or hexahedra with fbar")

    @property
    def elastic(self) -> Elastic:
        return self.material if isinstance(self.material, Elastic) else self.material.elastic

    @property
    def plastic(self) -> Plastic | None:
        return self.material if isinstance(self.material, Plastic) else None

    def rule_degree(self) -> int:
        if self.quadrature_degree is not None:
            return self.quadrature_degree
        if compat.cell_name(self.mesh.mesh) in ("quadrilateral", "hexahedron"):
            return 2 * self.degree + (1 if self.kind == "axisymmetric" else 0)
        q = 2 * (self.degree - 1) + (1 if self.kind == "axisymmetric" else 0)
        return max(q, 1 if self.degree == 1 else 2)

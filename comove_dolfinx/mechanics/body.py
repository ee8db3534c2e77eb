"""A body: its mesh, the 2D model, the material, the stress update and the discretisation."""
from __future__ import annotations

import math
from dataclasses import dataclass

from ..choices import PLASTIC_UPDATES as ROTATING_UPDATES  # noqa: E402  (they carry a rotated old stress)
from .kinematics import MODELS
from .material_data import Elastic, MaterialError
from .materials import Plastic
from .updates import UPDATES


class BodyError(ValueError):
    """A body that cannot be built; the message names the value and the fix."""


@dataclass
class Body:
    """A 2D solid.

    Parameters
    ----------
    mesh : geometry.MeshData
        Mesh with named facet groups (``comove_dolfinx.geometry`` builds, reads or wraps one).
    kind : str
        "plane_strain", "plane_stress" (forces per unit thickness) or "axisymmetric" (x = r, y = z;
        forces are totals over the circumference).
    material : Elastic, J2 or Chen
        Elastic constants, or an elastic-plastic law with its hardening.
    update : str
        Stress update: "sr_log" (Chen's S-R decomposition of the increment with its strain measured
        logarithmically, the default), "sr" (the S-R update as the paper writes it), "hughes_winget",
        "polar", "svk", "neo_hooke" (docs/theory.md section 3), or "small_strain" (linear
        kinematics, section 3.5). Plastic bodies need sr_log, sr, hughes_winget or small_strain.
    degree : int
        Lagrange degree of the displacement, 1 or 2 (P1 locks in bending).
    thickness : float
        Out-of-plane thickness of plane models.
    quadrature_degree : int, optional
        Of the volume integrals; by default 2 (3 points, exact P2 small-strain stiffness), 3 in
        axisymmetry (the weight r), 1 for P1.
    """

    mesh: object
    kind: str = "plane_strain"
    material: object = None
    update: str = "sr_log"
    degree: int = 2
    thickness: float = 1.0
    quadrature_degree: int | None = None

    def __post_init__(self):
        if self.kind not in MODELS:
            raise BodyError(f"kind = {self.kind!r} is unknown: choose one of {', '.join(MODELS)}")
        if not isinstance(self.material, (Elastic, Plastic)):
            raise BodyError(f"material = {self.material!r}: give Elastic(E, nu), J2(E, nu, hardening) "
                            "or Chen(E, nu, hardening)")
        if self.update not in UPDATES:
            raise BodyError(f"update = {self.update!r} is unknown: choose one of {', '.join(UPDATES)}")
        if self.plastic is not None and self.update not in ROTATING_UPDATES:
            raise MaterialError(f"update {self.update!r} cannot carry plasticity: use one of "
                                f"{', '.join(ROTATING_UPDATES)}")
        if self.degree not in (1, 2) or isinstance(self.degree, bool):
            raise BodyError(f"degree = {self.degree!r}: use 1 or 2")
        if not (isinstance(self.thickness, (int, float)) and math.isfinite(self.thickness)
                and self.thickness > 0):
            raise BodyError(f"thickness = {self.thickness!r} must be a finite number > 0")

    @property
    def elastic(self) -> Elastic:
        return self.material if isinstance(self.material, Elastic) else self.material.elastic

    @property
    def plastic(self) -> Plastic | None:
        return self.material if isinstance(self.material, Plastic) else None

    def rule_degree(self) -> int:
        if self.quadrature_degree is not None:
            return self.quadrature_degree
        q = 2 * (self.degree - 1) + (1 if self.kind == "axisymmetric" else 0)
        return max(q, 1 if self.degree == 1 else 2)

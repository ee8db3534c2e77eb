"""What the scenes build with: the public API's heavy modules, and two probes of the scenes."""
from __future__ import annotations

import ufl  # noqa: F401

from .. import geometry  # noqa: F401
from ..contact import Plane  # noqa: F401
from ..loads import Fixed, Pressure, Traction  # noqa: F401
from ..mechanics.body import Body  # noqa: F401
from ..mechanics.materials import as_material  # noqa: F401
from ..probes import ContactForce, ContactLength, MaxPlasticStrain, NodeDisplacement, Value  # noqa: F401
from ..solver import NewtonSettings  # noqa: F401


class CrownGap(NodeDisplacement):
    """Height of the upper plate above the ring's crown (> 0 once the crown lifts off)."""

    def __init__(self, ring):
        super().__init__("crown", (0.0, ring.R_out), component=1, column="crown_gap")
        self.ring = ring

    def __call__(self, model) -> dict:
        r = self.ring
        plate_y = r.R_out + r.gap - 0.5 * r.delta_max * model.load
        return {"crown_gap": plate_y - (r.R_out + self.value(model.u)[1])}


def or_zero(contact, *probes) -> list:
    """The contact probes, or columns of zeros when the scene runs without contact."""
    if contact is not None:
        return list(probes)
    return [Value(p.columns[0], lambda model: 0.0) for p in probes]

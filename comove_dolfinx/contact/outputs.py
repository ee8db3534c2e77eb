"""The contact item's results: its force, the contact zone, its edges, the pressure profile, the
peak pressure, the lengths that stick and slip, the largest penetration and the boundary fields.

A :class:`ContactOutputs` belongs to one :class:`contact.Contact` (``contact.outputs``), whose
results (``force``, ``zone``, ``zone_edges``, ``profile``, ``peak_pressure``, ``pressure``, ...) are
its. It is made of the pressure profile at the facet quadrature points (profile.py; the zones and
the peak that follow from it, zones.py) and the nodal fields (fields.py), and computes the rest from
forms of the contact's terms.

Units and signs: those of the model. The traction of the obstacle on the body is p n_o + q t_o per
unit current area, n_o the obstacle's normal (towards the body), t_o = (-n_o[1], n_o[0]); the
pressure p >= 0. The contact laws give the pressure per unit reference area (``ContactTerms.p_ref``);
divided by the area stretch ``|J F^-T N|`` it is per current area (in axisymmetry the stretch includes
the hoop stretch r / R, so the force is the integral of the traction times 2 pi r over the current
boundary). The force is taken from the residual: F . e = -R_c(u; e) for the constant fields e_x, e_y.

Every method is collective (every rank calls it, and gets the same result).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import ufl
from dolfinx import fem
from mpi4py import MPI
from petsc4py import PETSc

from ..delegation import delegate
from .fields import BoundaryFields, BoundaryNodes
from .profile import FacetProfile
from .zones import ContactProfile, Zone, edge_fraction, gauss_points, peak_of, zones_of

__all__ = ["ContactOutputs", "ContactProfile", "Zone", "ZoneInfo", "edge_fraction", "gauss_points",
           "peak_of", "zones_of"]


@dataclass
class ZoneInfo:
    """The contact set in the current configuration."""

    extent: float              # current length of the contact set, between its edges (zones.py)
    max_penetration: float     # largest -g over the nodes of the contact boundary (0 if none)

    @property
    def in_contact(self) -> bool:
        return self.extent > 0.0


class ContactOutputs:
    """The results of one contact item (built by the item's ``attach``, at the end).

    It reads the item's terms (contact/terms.py) and compiles its forms and expressions on first
    use, so that a run that never asks for a result does not pay for its compilation. Its parts:
    ``boundary`` (the boundary's nodes, fields.BoundaryNodes), ``fields`` (the nodal pressure and
    shear, fields.BoundaryFields) and ``facet_profile`` (the pressure profile, its zones and peak,
    profile.FacetProfile).
    """

    def __init__(self, item, ctx):
        self.item, self.comm = item, item.comm
        terms = item.terms
        self._e = fem.Constant(ctx.mesh, PETSc.ScalarType((0.0, 0.0)))
        N = ufl.FacetNormal(ctx.mesh)
        stretch = area_stretch(ctx, N)
        self._ufl = {"force": -ufl.replace(terms.R_c, {ctx.v: self._e})}
        if item.mu > 0:
            # reference length of the contact set that slips (friction at its threshold) and sticks
            chi = ufl.conditional(ufl.gt(terms.p_ref, 0.0), 1.0, 0.0)
            slipping = ufl.conditional(terms.slipping, 1.0, 0.0)
            self._ufl.update(slip=chi * slipping * terms.ds, stick=chi * (1.0 - slipping) * terms.ds)
            if terms.p_lag is not None:        # the lagged law's threshold state (none for coulomb)
                self._ufl["lag_force"] = \
                    terms.p_lag * ufl.dot(terms.n_lag, self._e) * ctx.weight * terms.ds
        self._compiled: dict = {}
        p_cur = terms.p_ref / stretch
        q_cur = terms.q_ref / stretch if terms.q_ref is not None else None
        self.boundary = BoundaryNodes.of(ctx, item.boundary)
        self.fields = BoundaryFields(ctx, item.boundary, p_cur, q_cur, terms.ds, self.boundary, self.comm)
        self.facet_profile = FacetProfile(ctx, item.obstacle, item.u, p_cur, q_cur, N,
                                          ctx.facets(item.boundary), self.comm)

    def _form(self, name: str):
        """The compiled form ``name`` (collective: every rank asks for it at the same point)."""
        if name not in self._compiled:
            self._compiled[name] = fem.form(self._ufl[name])
        return self._compiled[name]

    def _components(self, name: str) -> np.ndarray:
        """The x and y components of the vector that the scalar form ``name`` gives for e = e_x, e_y."""
        out = np.zeros(2)
        for i in range(2):
            self._e.value = np.eye(2)[i]
            out[i] = self.comm.allreduce(fem.assemble_scalar(self._form(name)), op=MPI.SUM)
        return out

    def force(self) -> np.ndarray:
        """Total force of the obstacle on the body (x, y), from the residual's contact term."""
        return self._components("force")

    def lag_force(self) -> np.ndarray:
        """Force (x, y) of the lag state's pressure on the body, the normal force that the friction
        threshold mu p_lag is taken from: after a commit, the normal part of that increment's
        :meth:`force` (zeros without friction and with the coulomb law, which has no lag state)."""
        return self._components("lag_force") if "lag_force" in self._ufl else np.zeros(2)

    def stick_slip(self) -> tuple[float, float]:
        """Reference lengths of the contact set where friction sticks and where it slips (zeros
        without friction), at the current iterate, from the quadrature points."""
        if "slip" not in self._ufl:
            return 0.0, 0.0
        return tuple(self.comm.allreduce(fem.assemble_scalar(f), op=MPI.SUM)
                     for f in (self._form("stick"), self._form("slip")))

    def max_penetration(self) -> float:
        """The largest -g over the nodes of the contact boundary (0 if none)."""
        item, b = self.item, self.boundary
        x = b.X + item.u.x.array.reshape(-1, 2)[b.nodes]
        g = item.obstacle.gap_np(x, item.obstacle.displacement(item.factor))
        return self.comm.allreduce(float(max(-g.min(), 0.0)) if g.size else 0.0, op=MPI.MAX)

    def zone(self) -> ZoneInfo:
        """The contact set's current length (between its edges) and the largest nodal penetration."""
        return ZoneInfo(self.facet_profile.extent(), self.max_penetration())

    @property
    def pressure(self):
        """Contact pressure per current area as a boundary field (a Function of the displacement's
        degree, zero away from the boundary; fields.py): current whenever it is read."""
        return self.fields.field("pressure")

    @property
    def shear(self):
        """Tangential traction along t_o per current area as a boundary field, like ``pressure``
        (zero without friction)."""
        return self.fields.field("shear")

    update_fields = delegate("fields.update")
    boundary_values = delegate("fields.boundary_values")
    profile = delegate("facet_profile.profile")
    zones = delegate("facet_profile.zones")
    extent = delegate("facet_profile.extent")
    zone_edges = delegate("facet_profile.zone_edges")
    peak_pressure = delegate("facet_profile.peak_pressure")


def area_stretch(ctx, N):
    """The area stretch ``|J F^-T N|`` of the facets (the stress update's F; in axisymmetry with the
    hoop stretch): a quantity per unit reference area divided by it is per unit current area."""
    F = ctx.update.F(ctx.u)
    N3 = ufl.as_vector([N[0], N[1], 0.0])
    cof = ufl.det(F) * ufl.inv(F).T
    return ufl.sqrt(ufl.dot(cof * N3, cof * N3))

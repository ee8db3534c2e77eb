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

In 3D (a body of kind ``solid``) the traction is p n_o + q, q the tangential traction vector; the
force has three components; the contact set's measure is its area (the current area of the parts
of the boundary's facets where the pressure at the facet quadrature points is positive; the
reference area under linear kinematics); the peak pressure is the largest value of the nodal
pressure field; the profile along the boundary and the zones' edges are 2D only, and the contact
radius along a meridian of the boundary 3D only (``meridians``: radial.py).

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
from .obstacles import ContactError
from .profile import FacetProfile
from .radial import Meridians
from .zones import ContactProfile, Zone, edge_fraction, gauss_points, peak_of, zones_of

__all__ = ["ContactOutputs", "ContactProfile", "Zone", "ZoneInfo", "edge_fraction", "gauss_points",
           "peak_of", "zones_of"]


@dataclass
class ZoneInfo:
    """The contact set in the current configuration."""

    extent: float              # current length of the contact set, between its edges (zones.py); 3D: its area
    max_penetration: float     # largest -g over the nodes of the contact boundary (0 if none)

    @property
    def in_contact(self) -> bool:
        return self.extent > 0.0


class ContactOutputs:
    """The results of one contact item (built by the item's ``attach``, at the end).

    It reads the item's terms (contact/terms.py) and compiles its forms and expressions on first
    use, so that a run that never asks for a result does not pay for its compilation. Its parts:
    ``boundary`` (the boundary's nodes, fields.BoundaryNodes), ``fields`` (the nodal pressure and
    shear, fields.BoundaryFields), ``facet_profile`` (2D: the pressure profile, its zones and peak,
    profile.FacetProfile) and ``meridians`` (3D: the profiles along meridians of the boundary and
    the contact radius, radial.Meridians).
    """

    def __init__(self, item, ctx):
        self.item, self.comm, self.dim = item, item.comm, ctx.mesh.topology.dim
        terms = item.terms
        self._e = fem.Constant(ctx.mesh, PETSc.ScalarType((0.0,) * self.dim))
        N = ufl.FacetNormal(ctx.mesh)
        stretch = area_stretch(ctx, N)
        self._ufl = {"force": -ufl.replace(terms.R_c, {ctx.v: self._e})}
        if self.dim == 3:
            chi = ufl.conditional(ufl.gt(terms.p_ref, 0.0), 1.0, 0.0)
            self._ufl["area"] = chi * (stretch if ctx.update.geometric else 1.0) * terms.ds
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
        self.facet_profile = None if self.dim == 3 else \
            FacetProfile(ctx, item.obstacle, item.u, p_cur, q_cur, N, ctx.facets(item.boundary), self.comm)
        self.meridians = Meridians(ctx, item, p_cur, q_cur, N)

    def _form(self, name: str):
        """The compiled form ``name`` (collective: every rank asks for it at the same point)."""
        if name not in self._compiled:
            self._compiled[name] = fem.form(self._ufl[name])
        return self._compiled[name]

    def _components(self, name: str) -> np.ndarray:
        """The x and y (and z) components of the vector that the scalar form ``name`` gives for e = e_x,
        e_y (, e_z)."""
        out = np.zeros(self.dim)
        for i in range(self.dim):
            self._e.value = np.eye(self.dim)[i]
            out[i] = self.comm.allreduce(fem.assemble_scalar(self._form(name)), op=MPI.SUM)
        return out

    def force(self) -> np.ndarray:
        """Total force of the obstacle on the body (x, y; in 3D x, y, z), from the residual's contact
        term."""
        return self._components("force")

    def lag_force(self) -> np.ndarray:
        """Force (x, y) of the lag state's pressure on the body, the normal force that the friction
        threshold mu p_lag is taken from: after a commit, the normal part of that increment's
        :meth:`force` (zeros without friction and with the coulomb law, which has no lag state)."""
        return self._components("lag_force") if "lag_force" in self._ufl else np.zeros(self.dim)

    def stick_slip(self) -> tuple[float, float]:
        """Reference lengths (3D: areas) of the contact set where friction sticks and where it slips
        (zeros without friction), at the current iterate, from the quadrature points."""
        if "slip" not in self._ufl:
            return 0.0, 0.0
        return tuple(self.comm.allreduce(fem.assemble_scalar(f), op=MPI.SUM)
                     for f in (self._form("stick"), self._form("slip")))

    def max_penetration(self) -> float:
        """The largest -g over the nodes of the contact boundary (0 if none)."""
        item, b = self.item, self.boundary
        x = b.X + item.u.x.array.reshape(-1, self.dim)[b.nodes]
        g = item.obstacle.gap_np(x, item.obstacle.displacement(item.factor))
        return self.comm.allreduce(float(max(-g.min(), 0.0)) if g.size else 0.0, op=MPI.MAX)

    def area(self) -> float:
        """3D: the contact set's current area (the reference one under linear kinematics): the
        facets' area where the pressure at the quadrature points is positive."""
        self._only("area", 3)
        return self.comm.allreduce(fem.assemble_scalar(self._form("area")), op=MPI.SUM)

    def zone(self) -> ZoneInfo:
        """The contact set's current length (between its edges; in 3D its area) and the largest
        nodal penetration."""
        extent = self.area() if self.dim == 3 else self.facet_profile.extent()
        return ZoneInfo(extent, self.max_penetration())

    def peak_pressure(self) -> float:
        """The largest contact pressure per current area: in 2D from the profile at the quadrature
        points (zones.py), in 3D the largest value of the nodal pressure field (fields.py)."""
        if self.dim == 2:
            return self.facet_profile.peak_pressure()
        f = self.fields.field("pressure")
        vals = f.x.array[self.fields.sdofs]
        return self.comm.allreduce(float(vals.max()) if vals.size else 0.0, op=MPI.MAX)

    def _only(self, what: str, dim: int) -> None:
        """ContactError unless the body has dimension ``dim``."""
        if self.dim != dim:
            alt = "the contact area (ContactArea)" if dim == 2 else "the contact length (ContactLength)"
            raise ContactError(f"the contact's {what} is a {dim}D result, the body is {self.dim}D: ask for {alt}")

    def profile(self):
        """2D: the pressure profile along the boundary (profile.py)."""
        self._only("profile", 2)
        return self.facet_profile.profile()

    def zones(self):
        """2D: the contact zones along the boundary (zones.py)."""
        self._only("zones", 2)
        return self.facet_profile.zones()

    def extent(self) -> float:
        """2D: the contact set's current length between its edges."""
        self._only("length", 2)
        return self.facet_profile.extent()

    def zone_edges(self, axis: int = 0):
        """2D: the smallest and largest coordinate ``axis`` of the zones' edges."""
        self._only("zone edges", 2)
        return self.facet_profile.zone_edges(axis)

    @property
    def pressure(self):
        """Contact pressure per current area as a boundary field (a Function of the displacement's
        degree, zero away from the boundary; fields.py): current whenever it is read."""
        return self.fields.field("pressure")

    @property
    def shear(self):
        """Tangential traction along t_o per current area as a boundary field, like ``pressure``
        (zero without friction; in 3D the magnitude of the tangential traction)."""
        return self.fields.field("shear")

    update_fields = delegate("fields.update")
    boundary_values = delegate("fields.boundary_values")


def area_stretch(ctx, N):
    """The area stretch ``|J F^-T N|`` of the facets (the stress update's F; in axisymmetry with the
    hoop stretch): a quantity per unit reference area divided by it is per unit current area."""
    F = ctx.update.F(ctx.u)
    N3 = N if ctx.mesh.topology.dim == 3 else ufl.as_vector([N[0], N[1], 0.0])
    cof = ufl.det(F) * ufl.inv(F).T
    return ufl.sqrt(ufl.dot(cof * N3, cof * N3))

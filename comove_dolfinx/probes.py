"""Probes: the numbers a job records at every converged increment (the history's columns).

A probe names its ``columns``, is attached once to the compiled model (``attach(model)``) and returns
a dict of those columns for the converged state (``__call__(model)``); every rank calls it and gets
the same values. A job's history is the increment, time and load columns followed by every probe's.

::

    cm.NodeDisplacement("tip", (10.0, 0.0))           # tip_ux, tip_uy at the node at (10, 0)
    cm.NodeDisplacement("centre", (0.0, 0.0), component=1, column="center_uz")
    cm.ContactForce(contact, "force", component=1, scale=-2.0)   # symmetry: twice the quarter's
    cm.ContactLength(contact, "contact_width", scale=2.0)
    cm.ContactPeak(contact, "p_max")                  # the largest contact pressure
    cm.ContactArea(contact, "area", scale=4.0)        # 3D: the contact area (four quarters)
    cm.ContactRadius(contact, "a", direction=(1, 0, 0))   # 3D: the contact radius along y = 0
    cm.Reaction("left")                               # left_fx, left_fy: the supports' force
    cm.MaxPlasticStrain()
    cm.Value("crown_gap", lambda model: ...)          # anything else, from the model
"""
from __future__ import annotations

from typing import Callable

import numpy as np
from mpi4py import MPI

from .checks import choice, first, meridian_error, number, text


class ProbeError(ValueError):
    """A probe that cannot be placed (the message names the value and the fix)."""


def _refuse(*messages) -> None:
    """ProbeError with the first message that is not None (checks.py's messages)."""
    why = first(*messages)
    if why is not None:
        raise ProbeError(why)


def _contact_of(probe: str, contact):
    """``contact`` if it is a contact item or None (a job refuses a probe of no contact:
    :func:`check_contacts`), else ProbeError naming the probe."""
    if contact is not None and (getattr(contact, "kind", None) != "contact"
                                or not hasattr(type(contact), "zone")):   # a method or a property
        raise ProbeError(f"{probe}: contact = {contact!r}: give the Contact item itself (the one in the "
                         "job's items), not its name")
    return contact


def check_contacts(probes, items) -> None:
    """ProbeError naming the first probe that reads a contact which is not one of ``items`` (it would
    read a contact that the job never builds)."""
    for probe in probes:
        if not isinstance(probe, (ContactForce, ContactLength, ContactEdges, ContactPeak, ContactArea,
                                  ContactRadius)):
            continue
        contact, name = probe.contact, f"{type(probe).__name__} {probe.columns[0]!r}"
        if contact is None:
            raise ProbeError(f"{name}: contact = None: give it the Contact item it reads (one of the job's items)")
        if not any(contact is item for item in items):
            raise ProbeError(f"{name} reads the contact on boundary "
                             f"{getattr(contact, 'boundary', contact)!r}, which is not one of the job's items: "
                             "add that Contact to the items, or probe one that is")


def _columns(name: str, scale) -> None:
    _refuse(text("name", name, "the history's column name"), number("scale", scale))


class Probe:
    columns: tuple[str, ...] = ()

    def attach(self, model) -> None:
        pass

    def __call__(self, model) -> dict:  # pragma: no cover - interface
        raise NotImplementedError


class NodeDisplacement(Probe):
    """Displacement of the mesh node at ``point`` (reference coordinates; three in 3D): columns
    ``<name>_ux``, ``<name>_uy`` (and ``<name>_uz`` for a 3D point), or one column (``column``,
    default ``<name>_u<x|y|z>``) for one ``component`` (2: z, 3D only)."""

    def __init__(self, name: str, point, component: int | None = None, column: str | None = None,
                 tol: float = 1e-8):
        _refuse(text("name", name), choice("component", component, (None, 0, 1, 2),
                                           " (0: x, 1: y, 2: z in 3D, None: all)"),
                None if column is None else text("column", column), number("tol", tol, gt=0))
        ok = isinstance(point, (list, tuple, np.ndarray)) and len(point) in (2, 3) and \
            all(number("", v) is None for v in point)
        _refuse(None if ok else f"probe {name!r}: point = {point!r}: give two finite numbers (x, y), or "
                "three (x, y, z) in 3D")
        _refuse(None if component is None or component < len(point) else
                f"probe {name!r}: component = 2 needs a 3D point (x, y, z), got {point!r}")
        self.name, self.point, self.component, self.tol = name, np.asarray(point, float), component, tol
        self.dim = len(point)
        if component is None:
            self.columns = tuple(f"{name}_u{c}" for c in "xyz"[:self.dim])
        else:
            self.columns = (column or f"{name}_u{'xyz'[component]}",)

    def attach(self, model) -> None:
        V = model.V
        if V.dofmap.index_map_bs != self.dim:
            raise ProbeError(f"probe {self.name!r}: point = {tuple(self.point)} has {self.dim} coordinates, "
                             f"the body {V.dofmap.index_map_bs}: give {V.dofmap.index_map_bs}")
        X = V.tabulate_dof_coordinates()
        n_owned = V.dofmap.index_map.size_local
        d = np.linalg.norm(X[:n_owned, :self.dim] - self.point, axis=1)
        comm = model.comm
        best, owner = comm.allreduce((float(d.min()) if d.size else np.inf, comm.rank), op=MPI.MINLOC)
        if best > self.tol:
            raise ProbeError(f"probe {self.name!r}: no mesh node at {tuple(self.point)} (nearest at "
                             f"distance {best:.3g}); choose a mesh size that puts a node there")
        self._comm, self._owner = comm, owner
        self._dof = int(np.argmin(d)) if comm.rank == owner else -1

    def value(self, f) -> np.ndarray:
        """The probed node's value of a vector function of the displacement space."""
        k = self.dim
        val = np.zeros(k)
        if self._comm.rank == self._owner:
            val[:] = f.x.array[k * self._dof: k * self._dof + k]
        return self._comm.allreduce(val, op=MPI.SUM)

    def __call__(self, model) -> dict:
        u = self.value(model.u)
        if self.component is None:
            return dict(zip(self.columns, u))
        return {self.columns[0]: u[self.component]}


def _body_dim(probe: str, model, dims: tuple, alt: str) -> None:
    """ProbeError unless the model's body has one of the dimensions ``dims``; ``alt``: the probe to
    use instead."""
    dim = model.V.dofmap.index_map_bs
    if dim not in dims:
        raise ProbeError(f"{probe} is not defined for a {dim}D body: use {alt}")


class ContactForce(Probe):
    """Force of a contact item's obstacle on the body: ``component`` 0, 1 (or 2, z, for a 3D
    obstacle) times ``scale`` (one column ``name``), or every component (``<name>_fx``,
    ``<name>_fy`` and, for a 3D obstacle, ``<name>_fz``)."""

    def __init__(self, contact, name: str = "contact_force", component: int | None = 1, scale: float = 1.0):
        _columns(name, scale)
        _refuse(choice("component", component, (None, 0, 1, 2), " (0: x, 1: y, 2: z in 3D, None: all)"))
        self.contact, self.component, self.scale = _contact_of(f"ContactForce {name!r}", contact), component, scale
        dim = getattr(getattr(contact, "obstacle", None), "dim", 2)
        _refuse(None if component is None or component < dim else
                f"ContactForce {name!r}: component = 2 (z) needs a 3D obstacle, the contact's is 2D: give 0 or 1")
        self.columns = (name,) if component is not None else tuple(f"{name}_f{c}" for c in "xyz"[:dim])

    def __call__(self, model) -> dict:
        f = self.scale * self.contact.force()
        return {self.columns[0]: f[self.component]} if self.component is not None else dict(zip(self.columns, f))


class ContactLength(Probe):
    """Current length of the contact set (times ``scale``): the arc length between the edges of each
    connected contact zone, summed, where an edge is where the pressure at the facet quadrature points
    reaches zero (contact/zones.py: interpolated between the last point in contact and the first one
    out; a zone that reaches the end of the boundary, e.g. a symmetry line, ends there); the reference
    arc length under linear kinematics (``small_strain``). In axisymmetry, with the boundary starting
    at the axis, the radius of the contact disc. Accuracy against Hertz's half-width: docs/api.md,
    "Contact results"."""

    def __init__(self, contact, name: str = "contact_length", scale: float = 1.0):
        _columns(name, scale)
        self.contact, self.scale, self.columns = _contact_of(f"ContactLength {name!r}", contact), scale, (name,)

    def attach(self, model) -> None:
        _body_dim(f"ContactLength {self.columns[0]!r}", model, (2,), "ContactArea (the contact area)")

    def __call__(self, model) -> dict:
        return {self.columns[0]: self.scale * self.contact.zone().extent}


class ContactArea(Probe):
    """3D: the contact set's current area (times ``scale``; one column ``name``): the area of the
    boundary's facets, on the current surface, where the pressure at the facet quadrature points
    is positive (the reference area under linear kinematics, ``small_strain``). A facet cut by the
    contact's edge counts by its quadrature points in contact, so the area converges with the mesh
    at the rate at which the edge band narrows (docs/api.md, "Contact of 3D bodies")."""

    def __init__(self, contact, name: str = "contact_area", scale: float = 1.0):
        _columns(name, scale)
        self.contact, self.scale, self.columns = _contact_of(f"ContactArea {name!r}", contact), scale, (name,)

    def attach(self, model) -> None:
        _body_dim(f"ContactArea {self.columns[0]!r}", model, (3,), "ContactLength (the contact length)")

    def __call__(self, model) -> dict:
        return {self.columns[0]: self.scale * self.contact.zone().extent}


class ContactRadius(Probe):
    """3D: the contact radius along a meridian of the contact boundary (times ``scale``; one column
    ``name``): the half-plane that the axis through ``origin`` along ``axis`` bounds on the side of
    ``direction`` cuts the boundary along edges of its facets (a symmetry plane's border, say: the
    bottom's edge on y = 0 of a plate quarter with the defaults); the pressure is sampled along
    them as along a 2D boundary, the contact set's edges found as :class:`ContactLength` finds
    them (extrapolated beyond the last points in contact), and the radius is their largest current
    distance from the axis, 0 without contact (contact/radial.py). A meridian that meets no facet's
    edge is refused when the job starts."""

    def __init__(self, contact, name: str = "contact_radius", origin=(0.0, 0.0, 0.0), direction=(1.0, 0.0, 0.0),
                 axis=(0.0, 0.0, 1.0), scale: float = 1.0):
        _columns(name, scale)
        why = meridian_error(origin, direction, axis)
        _refuse(None if why is None else f"ContactRadius {name!r}: {why}")
        self.contact, self.scale, self.columns = _contact_of(f"ContactRadius {name!r}", contact), scale, (name,)
        self.meridian = (tuple(map(float, origin)), tuple(map(float, direction)), tuple(map(float, axis)))

    def attach(self, model) -> None:
        _body_dim(f"ContactRadius {self.columns[0]!r}", model, (3,), "ContactLength (the contact length)")
        from .contact import ContactError
        try:
            self.contact.meridian(*self.meridian)
        except ContactError as err:
            raise ProbeError(f"ContactRadius {self.columns[0]!r}: {err}") from None

    def __call__(self, model) -> dict:
        return {self.columns[0]: self.scale * self.contact.radius(*self.meridian)}


class ContactEdges(Probe):
    """Where the contact set begins and ends: the smallest and largest current coordinate ``axis`` of
    the contact zones' edges (``<name>_min``, ``<name>_max``; NaN without contact), each edge found
    as for :class:`ContactLength` (between the last quadrature point in contact and the first one out,
    or the boundary's end)."""

    def __init__(self, contact, name: str = "contact_edge", axis: int = 0):
        _refuse(text("name", name), choice("axis", axis, (0, 1), " (0: x, 1: y)"))
        self.contact, self.axis = _contact_of(f"ContactEdges {name!r}", contact), axis
        self.columns = (f"{name}_min", f"{name}_max")

    def attach(self, model) -> None:
        _body_dim(f"ContactEdges {self.columns[0][:-4]!r}", model, (2,), "ContactArea (the contact area)")

    def __call__(self, model) -> dict:
        return dict(zip(self.columns, self.contact.zone_edges(self.axis)))


class ContactPeak(Probe):
    """The largest contact pressure per current area (times ``scale``; one column ``name``): the
    largest value at the facet quadrature points, where the contact law is evaluated (0 without
    contact); for a 3D body the largest value of the nodal pressure field. Accuracy against
    Hertz's peak: docs/api.md, "Contact results" and "Contact of 3D bodies"."""

    def __init__(self, contact, name: str = "peak_pressure", scale: float = 1.0):
        _columns(name, scale)
        self.contact, self.scale, self.columns = _contact_of(f"ContactPeak {name!r}", contact), scale, (name,)

    def __call__(self, model) -> dict:
        return {self.columns[0]: self.scale * self.contact.peak_pressure()}


class Reaction(Probe):
    """Total force that the supports of a tagged boundary (its ``Fixed`` and ``Displacement`` items)
    exert on it: ``<name>_fx``, ``<name>_fy`` (and ``<name>_fz`` with ``dim`` 3, for a 3D body),
    from the residual at the boundary's nodes in the components those supports hold (a corner
    node's other component, held by a neighbouring boundary's support, is that support's;
    Model.reaction_forces). Zero once a step released them."""

    def __init__(self, boundary: str, name: str | None = None, dim: int = 2):
        _refuse(text("boundary", boundary), None if name is None else text("name", name),
                choice("dim", dim, (2, 3), " (3 for a 3D body)"))
        self.boundary, self.dim = boundary, dim
        name = name or boundary
        self.columns = tuple(f"{name}_f{c}" for c in "xyz"[:dim])

    def attach(self, model) -> None:
        if model.V.dofmap.index_map_bs != self.dim:
            raise ProbeError(f"Reaction({self.boundary!r}): dim = {self.dim}, the body has "
                             f"{model.V.dofmap.index_map_bs} displacement components: give "
                             f"dim={model.V.dofmap.index_map_bs}")
        if not model.supports_of(self.boundary):
            raise ProbeError(f"Reaction({self.boundary!r}): no support (Fixed, Displacement) acts on "
                             f"boundary {self.boundary!r}; give a supported boundary (ContactForce "
                             "gives an obstacle's force)")

    def __call__(self, model) -> dict:
        return dict(zip(self.columns, model.reaction(self.boundary)))


class MaxPlasticStrain(Probe):
    """Largest equivalent plastic strain over the quadrature points (0 for elastic bodies)."""

    columns = ("max_plastic_strain",)

    def __call__(self, model) -> dict:
        p = model.p.x.array if model.p is not None else np.zeros(0)
        return {self.columns[0]: model.comm.allreduce(float(p.max()) if p.size else 0.0, op=MPI.MAX)}


class Value(Probe):
    """A column computed by ``fn(model)`` (it must return the same number on every rank)."""

    def __init__(self, name: str, fn: Callable):
        _refuse(text("name", name), None if callable(fn) else f"Value {name!r}: fn = {fn!r}: give a function "
                "of the model")
        self.columns, self.fn = (name,), fn

    def __call__(self, model) -> dict:
        return {self.columns[0]: float(self.fn(model))}

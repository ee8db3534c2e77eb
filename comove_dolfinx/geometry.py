"""Gmsh builders for the 2D bodies of the scenes, cached as .msh files and loaded distributed.

Every builder makes a triangle mesh in the (x, y) plane (gdim = 2; for the axisymmetric plate x is the
radius r and y the axial coordinate z) with straight-sided (order 1) or curved (order 2, mid-side nodes on
the true arcs) triangles. Lengths are in the user's units (the scenes use cm).

Physical groups: one surface group "body" (cell tag ``BODY_TAG``) and one named curve group per boundary
part; their tag values, distinct per name and numbered from 1 in the order listed by each builder, are in
``MeshData.tags`` and are used as ``ds(data.ds_id("top"))`` with
``ufl.Measure("ds", domain=data.mesh, subdomain_data=data.facet_tags)``.

Caching: rank 0 builds the mesh once and writes ``<cache_dir>/<builder>_<hash>.msh``, where the hash
covers every parameter (order included) and the gmsh version; the file is written under a temporary name
and renamed, so a concurrent reader never sees half a file. Later calls, in any process, reuse the file.

Gmsh runs on rank 0 only: the builders call ``gmsh.initialize``/``gmsh.finalize`` there, so do not call
them from inside a gmsh session of your own.
"""
from __future__ import annotations

import hashlib
import json
import math
import os
import pathlib
from dataclasses import dataclass, field
from typing import Callable, Iterable

import dolfinx
import gmsh
import numpy as np
from mpi4py import MPI

from . import compat

__all__ = ["BODY_TAG", "MeshData", "MeshError", "annulus_sector", "fix_coordinate_element", "from_dolfinx", "load_msh",
           "plate_section", "quarter_disc", "rectangle"]

BODY_TAG = 1
"""Cell tag value of the physical surface "body" written by every builder."""

_CACHE_FORMAT = 1  # bump when a builder changes the meshes it writes, to invalidate old cache files
_ARRANGEMENT = "AlternateLeft"  # diagonals of structured triangles alternate, no preferred direction


class MeshError(ValueError):
    """A mesh file or a physical group is missing or unusable; the message names it and the fix."""


@dataclass
class MeshData:
    """A distributed dolfinx mesh with its cell and facet tags and the names of its facet groups.

    Attributes
    ----------
    mesh : dolfinx.mesh.Mesh
        The mesh (gdim = 2), already passed through `fix_coordinate_element`.
    cell_tags, facet_tags : dolfinx.mesh.MeshTags
        Tags of the physical surfaces and curves of the .msh file.
    tags : dict[str, int]
        Facet (curve) physical-group name -> tag value.
    path : pathlib.Path
        The .msh file the mesh was read from.
    cell_names : dict[str, int]
        Cell (surface) physical-group name -> tag value ({"body": 1} for the builders).
    """

    mesh: dolfinx.mesh.Mesh
    cell_tags: dolfinx.mesh.MeshTags
    facet_tags: dolfinx.mesh.MeshTags
    tags: dict[str, int]
    path: pathlib.Path
    cell_names: dict[str, int] = field(default_factory=dict)

    def ds_id(self, name: str) -> int:
        """Return the facet tag value of the physical group `name` (MeshError if there is none)."""
        try:
            return self.tags[name]
        except KeyError:
            raise MeshError(f"{self.path}: no facet group named {name!r}; available: "
                            f"{sorted(self.tags)}") from None


def fix_coordinate_element(mesh: dolfinx.mesh.Mesh) -> None:
    """Make the mesh's form cache keys stable from its first compilation on (see
    :func:`compat.fix_coordinate_element`; dolfinx 0.5 only, a no-op later). Meshes read from Gmsh
    already carry the variant; those of ``dolfinx.mesh.create_rectangle`` and friends do not."""
    compat.fix_coordinate_element(mesh)


def _positive(**values: float) -> None:
    """Raise ValueError unless every keyword value is a finite number > 0."""
    for name, value in values.items():
        if not (isinstance(value, (int, float, np.number)) and math.isfinite(value) and value > 0):
            raise ValueError(f"{name} must be a finite number > 0, got {value!r}")


def _check_order(order: int) -> int:
    """Return the geometry order as an int; ValueError unless it is 1 or 2."""
    if isinstance(order, bool) or order not in (1, 2):
        raise ValueError(f"order must be 1 or 2, got {order!r}")
    return int(order)


def _cache_path(builder: str, params: dict, cache_dir: str | os.PathLike) -> pathlib.Path:
    """File name <builder>_<10-hex hash of parameters, gmsh version and cache format>.msh."""
    key = json.dumps({"builder": builder, "params": params, "gmsh": gmsh.__version__,
                      "format": _CACHE_FORMAT}, sort_keys=True)
    digest = hashlib.sha1(key.encode()).hexdigest()[:10]
    return pathlib.Path(cache_dir) / f"{builder}_{digest}.msh"


def _start_gmsh() -> None:
    """Initialize gmsh without user configuration files and with terminal output off."""
    gmsh.initialize(readConfigFiles=False)
    gmsh.option.setNumber("General.Terminal", 0)  # errors still raise, with gmsh's message


def _add_group(dim: int, entities: list[int], tag: int, name: str) -> None:
    """Add the physical group `tag` of dimension `dim` with the given name."""
    gmsh.model.addPhysicalGroup(dim, entities, tag)  # gmsh 4.8: no name argument yet
    gmsh.model.setPhysicalName(dim, tag, name)


def _build(builder: str, params: dict, construct: Callable[[], None], comm: MPI.Comm,
           cache_dir: str | os.PathLike) -> MeshData:
    """Write the mesh on rank 0 unless its cache file exists, then read it on every rank.

    `construct` creates the geometry, the physical groups and the mesh-size settings of the current
    gmsh model (and synchronizes); this function meshes it, raises its order and writes the file.
    """
    path = _cache_path(builder, params, cache_dir)
    error = None
    if comm.rank == 0 and not path.exists():
        tmp = path.with_name(f".{path.stem}.{os.getpid()}.tmp.msh")  # gmsh wants the .msh suffix
        _start_gmsh()
        try:
            path.parent.mkdir(parents=True, exist_ok=True)
            gmsh.model.add(builder)
            construct()
            gmsh.model.mesh.generate(2)
            gmsh.model.mesh.setOrder(params["order"])  # order 2: new nodes on the true curves
            gmsh.write(str(tmp))
            os.replace(tmp, path)
        except Exception as err:  # gmsh raises plain Exception
            error = f"building {path} with gmsh failed: {err}"
        finally:
            gmsh.finalize()
            if tmp.exists():
                tmp.unlink()
    error = comm.bcast(error, root=0)  # also the barrier: no rank reads before the file exists
    if error is not None:
        raise MeshError(error)
    return load_msh(path, comm)


def _groups_of_current_model(path: pathlib.Path, required: Iterable[str]) -> tuple[dict, dict]:
    """Facet and cell physical groups (name -> tag) of the merged file; MeshError if unusable."""
    groups = gmsh.model.getPhysicalGroups()
    if not groups:
        raise MeshError(f"{path} has no physical groups; tag the body surface and the boundary curves "
                        "(Physical Surface / Physical Curve) before saving the mesh")
    top = max(dim for dim, _ in groups)
    if top != 2:
        raise MeshError(f"{path}: the highest physical group dimension is {top}; comove_dolfinx reads "
                        "2D meshes with a physical surface for the body (and curves for boundaries)")
    names: dict[int, dict[str, int]] = {1: {}, 2: {}}
    for dim, tag in groups:
        if dim in names:
            names[dim][gmsh.model.getPhysicalName(dim, tag) or str(tag)] = tag
    # model_to_mesh asserts one element type per entity on rank 0 only: check here to avoid a deadlock
    for dim in (1, 2):
        entities = [e for d, tag in groups if d == dim for e in gmsh.model.getEntitiesForPhysicalGroup(d, tag)]
        types = {t for e in entities for t in gmsh.model.mesh.getElementTypes(dim, e)}
        if len(types) > 1:
            raise MeshError(f"{path} mixes element types {sorted(types)} in its {dim}D physical groups; "
                            "dolfinx 0.5 needs one cell type (all triangles or all quadrilaterals)")
    z = gmsh.model.mesh.getNodes()[1][2::3]
    if z.size and np.abs(z).max() > 0:
        raise MeshError(f"{path} is not in the plane z = 0 (max |z| = {np.abs(z).max():g}); "
                        "comove_dolfinx reads 2D (x, y) meshes")
    missing = [name for name in required if name not in names[1]]
    if missing:
        raise MeshError(f"{path}: facet group(s) {missing} not found; present: {sorted(names[1])}. "
                        "Add them as named physical curves or fix the names asked for")
    return names[1], names[2]


def load_msh(path: str | os.PathLike, comm: MPI.Comm = MPI.COMM_WORLD,
             required: Iterable[str] = ()) -> MeshData:
    """Read a 2D gmsh .msh file on rank 0 and distribute it over `comm`.

    Parameters
    ----------
    path
        The .msh file (any gmsh-readable version with physical groups).
    comm
        Communicator of the mesh.
    required
        Facet (physical curve) names that must be present.

    Raises
    ------
    MeshError
        If the file is missing or unreadable, has no physical groups or no physical surface, or lacks a
        required facet group (the message names the missing groups and lists those present).
    """
    path = pathlib.Path(path)
    required = tuple(required)
    error, facet_names, cell_names = None, {}, {}
    if comm.rank == 0:
        if not path.is_file():
            error = f"mesh file {path} not found (absolute: {path.resolve()}); check the path"
        else:
            _start_gmsh()
            try:
                gmsh.model.add("comove_load")
                gmsh.merge(str(path))
                facet_names, cell_names = _groups_of_current_model(path, required)
            except MeshError as err:
                error = str(err)
            except Exception as err:
                error = f"gmsh cannot read {path}: {err}"
            if error is not None:
                gmsh.finalize()
    error, facet_names, cell_names = comm.bcast((error, facet_names, cell_names), root=0)
    if error is not None:
        raise MeshError(error)
    # dolfinx 0.5.2's gmshio.read_from_msh is broken (NameError: 'msh' on the reading rank,
    # 'partitioner' elsewhere), so do what it should: merge on rank 0, then model_to_mesh everywhere.
    try:
        mesh, cell_tags, facet_tags = compat.model_to_mesh(gmsh.model, comm, 0, gdim=2)
    finally:
        if comm.rank == 0:
            gmsh.finalize()
    fix_coordinate_element(mesh)
    mesh.name = "mesh"
    cell_tags.name, facet_tags.name = "cell_tags", "facet_tags"
    return MeshData(mesh, cell_tags, facet_tags, facet_names, path, cell_names)


def _structured(curves: list[int], counts: list[int]) -> int:
    """Plane surface bounded by the 4 oriented `curves`, transfinite with `counts` elements per curve."""
    loop = gmsh.model.geo.addCurveLoop(curves)
    surface = gmsh.model.geo.addPlaneSurface([loop])
    for curve, n in zip(curves, counts):
        gmsh.model.geo.mesh.setTransfiniteCurve(abs(curve), n + 1)
    gmsh.model.geo.mesh.setTransfiniteSurface(surface, _ARRANGEMENT)
    return surface


def rectangle(L: float, H: float, size: float, order: int = 2, x0: float = 0.0, y0: float = 0.0,
              comm: MPI.Comm = MPI.COMM_WORLD, cache_dir: str | os.PathLike = "meshes") -> MeshData:
    """Structured triangles on [x0, x0+L] x [y0, y0+H]; facet groups "left", "right", "bottom", "top".

    Parameters
    ----------
    L, H
        Length (along x) and depth (along y).
    size
        Target element edge: nx = ceil(L/size) by ny = max(ceil(H/size), 2) cells, each cut into two
        triangles with alternating diagonals. At least two cells through the depth keep a thin P2
        beam from being too stiff: the beam (H = 0.5) gets 2 layers for size >= 0.25 and 4 for
        size 0.125; the elastica cantilever (H = 0.25) 2 for size >= 0.125 and 4 for 0.0625.
    order
        Geometry order, 1 or 2 (2 suits P2 displacements and writes them exactly to XDMF).
    x0, y0
        Lower-left corner.
    comm, cache_dir
        Communicator of the mesh; folder of the cached .msh files (created if missing).

    Returns
    -------
    MeshData
        Facet tags left = 1, right = 2, bottom = 3, top = 4; cells "body" = BODY_TAG.
    """
    _positive(L=L, H=H, size=size)
    order = _check_order(order)
    nx, ny = math.ceil(L / size), max(math.ceil(H / size), 2)
    params = dict(L=float(L), H=float(H), size=float(size), order=order, x0=float(x0), y0=float(y0))

    def construct() -> None:
        geo = gmsh.model.geo
        p = [geo.addPoint(x, y, 0.0) for x, y in
             [(x0, y0), (x0 + L, y0), (x0 + L, y0 + H), (x0, y0 + H)]]
        bottom, right, top, left = (geo.addLine(p[i], p[(i + 1) % 4]) for i in range(4))
        surface = _structured([bottom, right, top, left], [nx, ny, nx, ny])
        geo.synchronize()
        _add_group(2, [surface], BODY_TAG, "body")
        for tag, (name, curve) in enumerate(
                [("left", left), ("right", right), ("bottom", bottom), ("top", top)], start=1):
            _add_group(1, [curve], tag, name)

    return _build("rectangle", params, construct, comm, cache_dir)


def plate_section(R: float = 10.0, t: float = 2.0, z_support: float = 0.25, size: float = 0.25,
                  order: int = 2, comm: MPI.Comm = MPI.COMM_WORLD,
                  cache_dir: str | os.PathLike = "meshes") -> MeshData:
    """Axisymmetric plate section 0 <= r <= R (x), 0 <= z <= t (y), structured in two stacked strips.

    Parameters
    ----------
    R, t
        Plate radius and thickness.
    z_support
        Height (0 < z_support < t) at which the rim face r = R is split: the lower strip
        0 <= z <= z_support carries the rim support.
    size
        Target element edge: ceil(R/size) cells along r, max(ceil(z_support/size), 1) and
        max(ceil((t - z_support)/size), 1) through the two strips.
    order, comm, cache_dir
        As for `rectangle`.

    Returns
    -------
    MeshData
        Facet tags axis (r = 0) = 1, bottom (z = 0, the contact face) = 2, top (z = t, loaded) = 3,
        rim_support (r = R, z <= z_support) = 4, rim (r = R, z >= z_support) = 5.
    """
    _positive(R=R, t=t, z_support=z_support, size=size)
    order = _check_order(order)
    if not z_support < t:
        raise ValueError(f"z_support must lie strictly between 0 and t = {t}, got {z_support!r}")
    nr = math.ceil(R / size)
    n_low, n_up = max(math.ceil(z_support / size), 1), max(math.ceil((t - z_support) / size), 1)
    params = dict(R=float(R), t=float(t), z_support=float(z_support), size=float(size), order=order)

    def construct() -> None:
        geo = gmsh.model.geo
        p00, pR0 = geo.addPoint(0.0, 0.0, 0.0), geo.addPoint(R, 0.0, 0.0)
        pRs, p0s = geo.addPoint(R, z_support, 0.0), geo.addPoint(0.0, z_support, 0.0)
        pRt, p0t = geo.addPoint(R, t, 0.0), geo.addPoint(0.0, t, 0.0)
        bottom, rim_support = geo.addLine(p00, pR0), geo.addLine(pR0, pRs)
        middle, axis_low = geo.addLine(pRs, p0s), geo.addLine(p0s, p00)
        rim, top, axis_up = geo.addLine(pRs, pRt), geo.addLine(pRt, p0t), geo.addLine(p0t, p0s)
        low = _structured([bottom, rim_support, middle, axis_low], [nr, n_low, nr, n_low])
        up = _structured([-middle, rim, top, axis_up], [nr, n_up, nr, n_up])
        geo.synchronize()
        _add_group(2, [low, up], BODY_TAG, "body")
        for tag, (name, curves) in enumerate(
                [("axis", [axis_low, axis_up]), ("bottom", [bottom]), ("top", [top]),
                 ("rim_support", [rim_support]), ("rim", [rim])], start=1):
            _add_group(1, curves, tag, name)

    return _build("plate_section", params, construct, comm, cache_dir)


def annulus_sector(r_in: float, r_out: float, size: float, order: int = 2, angle: float = math.pi / 2,
                   comm: MPI.Comm = MPI.COMM_WORLD,
                   cache_dir: str | os.PathLike = "meshes") -> MeshData:
    """Structured sector r_in <= r <= r_out, 0 <= theta <= angle of an annulus centred at the origin.

    Parameters
    ----------
    r_in, r_out
        Inner and outer radius (r_in < r_out).
    size
        Target element edge: n_r = max(ceil((r_out - r_in)/size), 2) cells through the wall and
        n_theta = ceil(angle (r_in + r_out)/2 / size) along the arcs.
    order, comm, cache_dir
        As for `rectangle`; with order 2 the mid-side nodes of the arcs lie on the true circles.
    angle
        Opening angle, 0 < angle < pi (one gmsh arc per circle); pi/2 gives the quarter x, y >= 0.

    Returns
    -------
    MeshData
        Facet tags inner = 1, outer = 2, xsym (the radial edge at theta = angle, on x = 0 for the
        quarter) = 3, ysym (the radial edge on y = 0) = 4.
    """
    _positive(r_in=r_in, r_out=r_out, size=size, angle=angle)
    order = _check_order(order)
    if not r_in < r_out:
        raise ValueError(f"r_in must be smaller than r_out, got r_in={r_in!r}, r_out={r_out!r}")
    if not angle < math.pi:
        raise ValueError(f"angle must lie in (0, pi), got {angle!r}")
    n_r = max(math.ceil((r_out - r_in) / size), 2)
    n_theta = max(math.ceil(angle * 0.5 * (r_in + r_out) / size), 1)
    params = dict(r_in=float(r_in), r_out=float(r_out), size=float(size), order=order, angle=float(angle))

    def construct() -> None:
        geo = gmsh.model.geo
        # exact zeros keep the "xsym" edge of the quarter on x = 0 (cos(pi/2) is 6e-17)
        c, s = (0.0 if abs(v) < 1e-14 else v for v in (math.cos(angle), math.sin(angle)))
        centre = geo.addPoint(0.0, 0.0, 0.0)
        a_in, a_out = geo.addPoint(r_in, 0.0, 0.0), geo.addPoint(r_out, 0.0, 0.0)
        b_out, b_in = geo.addPoint(r_out * c, r_out * s, 0.0), geo.addPoint(r_in * c, r_in * s, 0.0)
        ysym, outer = geo.addLine(a_in, a_out), geo.addCircleArc(a_out, centre, b_out)
        xsym, inner = geo.addLine(b_out, b_in), geo.addCircleArc(b_in, centre, a_in)
        surface = _structured([ysym, outer, xsym, inner], [n_r, n_theta, n_r, n_theta])
        geo.synchronize()
        _add_group(2, [surface], BODY_TAG, "body")
        for tag, (name, curve) in enumerate(
                [("inner", inner), ("outer", outer), ("xsym", xsym), ("ysym", ysym)], start=1):
            _add_group(1, [curve], tag, name)

    return _build("annulus_sector", params, construct, comm, cache_dir)


def quarter_disc(R: float, size: float, size_contact: float, contact_zone: float, order: int = 2,
                 growth: float = 0.25, comm: MPI.Comm = MPI.COMM_WORLD,
                 cache_dir: str | os.PathLike = "meshes") -> MeshData:
    """Hertz body: the part x >= 0, y <= R of the disc of radius R centred at (0, R), touching y = 0 at 0.

    Parameters
    ----------
    R
        Disc radius.
    size, size_contact
        Element size far from the contact and within `contact_zone` of the origin (size_contact <=
        size); in between it grows linearly by `growth` per unit distance (unstructured triangles).
    contact_zone
        Radius of the refined zone around the origin.
    order, comm, cache_dir
        As for `rectangle`; with order 2 the mid-side nodes of the arc lie on the true circle.

    Returns
    -------
    MeshData
        Facet tags top (the flat edge y = R, loaded) = 1, xsym (x = 0) = 2, contact (the arc) = 3.
    """
    _positive(R=R, size=size, size_contact=size_contact, contact_zone=contact_zone, growth=growth)
    order = _check_order(order)
    if size_contact > size:
        raise ValueError(f"size_contact must not exceed size = {size}, got {size_contact!r}")
    params = dict(R=float(R), size=float(size), size_contact=float(size_contact),
                  contact_zone=float(contact_zone), order=order, growth=float(growth))

    def construct() -> None:
        geo = gmsh.model.geo
        origin, centre, corner = (geo.addPoint(x, y, 0.0, size) for x, y in [(0, 0), (0, R), (R, R)])
        xsym, top = geo.addLine(origin, centre), geo.addLine(centre, corner)
        contact = geo.addCircleArc(corner, centre, origin)
        surface = geo.addPlaneSurface([geo.addCurveLoop([xsym, top, contact])])
        geo.synchronize()
        fields = gmsh.model.mesh.field
        distance = fields.add("Distance")
        fields.setNumbers(distance, "PointsList", [origin])
        threshold = fields.add("Threshold")
        fields.setNumber(threshold, "InField", distance)
        fields.setNumber(threshold, "SizeMin", size_contact)
        fields.setNumber(threshold, "SizeMax", size)
        fields.setNumber(threshold, "DistMin", contact_zone)
        fields.setNumber(threshold, "DistMax", contact_zone + (size - size_contact) / growth)
        fields.setAsBackgroundMesh(threshold)
        for option in ("MeshSizeExtendFromBoundary", "MeshSizeFromPoints", "MeshSizeFromCurvature"):
            gmsh.option.setNumber(f"Mesh.{option}", 0)
        _add_group(2, [surface], BODY_TAG, "body")
        for tag, (name, curve) in enumerate([("top", top), ("xsym", xsym), ("contact", contact)], start=1):
            _add_group(1, [curve], tag, name)

    return _build("quarter_disc", params, construct, comm, cache_dir)


def from_dolfinx(mesh: dolfinx.mesh.Mesh, facet_tags: dolfinx.mesh.MeshTags, names: dict[str, int],
                 cell_tags: dolfinx.mesh.MeshTags | None = None) -> MeshData:
    """A mesh made with dolfinx, with its facet tags and a name for each tag value used."""
    if mesh.geometry.dim != 2 or mesh.topology.dim != 2:
        raise MeshError("the mesh must be 2D (gdim = tdim = 2)")
    present = set(np.unique(facet_tags.values).tolist())
    present = set().union(*mesh.comm.allgather(present))
    missing = {k: v for k, v in names.items() if v not in present}
    if missing:
        raise MeshError(f"no facet carries the tag value of {missing}: tag those facets or drop the names")
    return MeshData(mesh, cell_tags, facet_tags, dict(names), pathlib.Path("<dolfinx mesh>"))

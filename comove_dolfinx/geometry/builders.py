"""The Gmsh builders of the scenes' bodies (cached .msh files, see geometry/__init__.py)."""
from __future__ import annotations

import math
import os

import numpy as np
from mpi4py import MPI

from .gmsh_session import gmsh
from ..checks import mesh_size_error, number
from .meshes import _ARRANGEMENT, BODY_TAG, MeshData, MeshError, add_group, build_cached


def _positive(**values: float) -> None:
    """Raise MeshError unless every keyword value is a finite number > 0 (not a bool, not a string)."""
    for name, value in values.items():
        if number(name, value, gt=0):
            raise MeshError(f"{name} must be a finite number > 0, got {value!r}")


def _check_order(order: int) -> int:
    """Return the geometry order as an int; MeshError unless it is 1 or 2."""
    if isinstance(order, bool) or order not in (1, 2):
        raise MeshError(f"order must be 1 or 2, got {order!r}")
    return int(order)


def _not_too_fine(builder: str, params: dict) -> None:
    """MeshError when the mesh would have more cells than checks.MAX_CELLS (estimated from the
    geometry and sizes before gmsh runs: beyond that gmsh runs out of memory)."""
    why = mesh_size_error(builder, params)
    if why is not None:
        raise MeshError(f"{builder}: {why}")


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
    params = dict(L=float(L), H=float(H), size=float(size), order=order, x0=float(x0), y0=float(y0))
    _not_too_fine("rectangle", params)
    nx, ny = math.ceil(L / size), max(math.ceil(H / size), 2)

    def construct() -> None:
        geo = gmsh.model.geo
        p = [geo.addPoint(x, y, 0.0) for x, y in
             [(x0, y0), (x0 + L, y0), (x0 + L, y0 + H), (x0, y0 + H)]]
        bottom, right, top, left = (geo.addLine(p[i], p[(i + 1) % 4]) for i in range(4))
        surface = _structured([bottom, right, top, left], [nx, ny, nx, ny])
        geo.synchronize()
        add_group(2, [surface], BODY_TAG, "body")
        for tag, (name, curve) in enumerate(
                [("left", left), ("right", right), ("bottom", bottom), ("top", top)], start=1):
            add_group(1, [curve], tag, name)

    return build_cached("rectangle", params, construct, comm, cache_dir)


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
        raise MeshError(f"z_support must lie strictly between 0 and t = {t}, got {z_support!r}")
    params = dict(R=float(R), t=float(t), z_support=float(z_support), size=float(size), order=order)
    _not_too_fine("plate_section", params)
    nr = math.ceil(R / size)
    n_low, n_up = max(math.ceil(z_support / size), 1), max(math.ceil((t - z_support) / size), 1)

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
        add_group(2, [low, up], BODY_TAG, "body")
        for tag, (name, curves) in enumerate(
                [("axis", [axis_low, axis_up]), ("bottom", [bottom]), ("top", [top]),
                 ("rim_support", [rim_support]), ("rim", [rim])], start=1):
            add_group(1, curves, tag, name)

    return build_cached("plate_section", params, construct, comm, cache_dir)


def annulus_sector(r_in: float, r_out: float, size: float, order: int = 2, angle: float = math.pi / 2,
                   comm: MPI.Comm = MPI.COMM_WORLD,
                   cache_dir: str | os.PathLike = "meshes", quadrilaterals: bool = False) -> MeshData:
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
    quadrilaterals
        The grid's cells as quadrilaterals (9-node ones at order 2) instead of triangles: the
        section of ``tube_sector(..., hexahedra=True)`` at the same size and angle, whose bricks
        are this grid extruded along z.

    Returns
    -------
    MeshData
        Facet tags inner = 1, outer = 2, xsym (the radial edge at theta = angle, on x = 0 for the
        quarter) = 3, ysym (the radial edge on y = 0) = 4.
    """
    _positive(r_in=r_in, r_out=r_out, size=size, angle=angle)
    order = _check_order(order)
    if not r_in < r_out:
        raise MeshError(f"r_in must be smaller than r_out, got r_in={r_in!r}, r_out={r_out!r}")
    if not angle < math.pi:
        raise MeshError(f"angle must lie in (0, pi), got {angle!r}")
    if not isinstance(quadrilaterals, bool):
        raise MeshError(f"quadrilaterals must be True or False, got {quadrilaterals!r}")
    params = dict(r_in=float(r_in), r_out=float(r_out), size=float(size), order=order, angle=float(angle),
                  **({"quadrilaterals": True} if quadrilaterals else {}))
    _not_too_fine("annulus_sector", params)
    n_r = max(math.ceil((r_out - r_in) / size), 2)
    n_theta = max(math.ceil(angle * 0.5 * (r_in + r_out) / size), 1)

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
        if quadrilaterals:
            geo.mesh.setRecombine(2, surface)
        geo.synchronize()
        add_group(2, [surface], BODY_TAG, "body")
        for tag, (name, curve) in enumerate(
                [("inner", inner), ("outer", outer), ("xsym", xsym), ("ysym", ysym)], start=1):
            add_group(1, [curve], tag, name)

    return build_cached("annulus_sector", params, construct, comm, cache_dir)


def _disc_outline(R: float, size: float, half: bool) -> tuple:
    """The geometry of :func:`quarter_disc` (not synchronized): (the point at the origin, the surface,
    the top curves, the contact arcs, the curve on x = 0 or None for the half disc)."""
    geo = gmsh.model.geo
    origin, centre, corner = (geo.addPoint(x, y, 0.0, size) for x, y in [(0, 0), (0, R), (R, R)])
    top = geo.addLine(centre, corner)
    contact = geo.addCircleArc(corner, centre, origin)
    if half:
        left = geo.addPoint(-R, R, 0.0, size)
        top_left, contact_left = geo.addLine(left, centre), geo.addCircleArc(origin, centre, left)
        loop = [top_left, top, contact, contact_left]
        tops, contacts, xsym = [top_left, top], [contact, contact_left], None
    else:
        xsym = geo.addLine(origin, centre)
        loop, tops, contacts = [xsym, top, contact], [top], [contact]
    surface = geo.addPlaneSurface([geo.addCurveLoop(loop)])
    return origin, surface, tops, contacts, xsym


def _refine_towards(point: int, size: float, size_contact: float, contact_zone: float,
                    growth: float) -> None:
    """Element size ``size_contact`` within ``contact_zone`` of the gmsh ``point``, growing linearly
    by ``growth`` per unit distance to ``size`` beyond (the background field of the current model,
    which alone sets the sizes)."""
    fields = gmsh.model.mesh.field
    distance = fields.add("Distance")
    fields.setNumbers(distance, "PointsList", [point])
    threshold = fields.add("Threshold")
    fields.setNumber(threshold, "InField", distance)
    fields.setNumber(threshold, "SizeMin", size_contact)
    fields.setNumber(threshold, "SizeMax", size)
    fields.setNumber(threshold, "DistMin", contact_zone)
    fields.setNumber(threshold, "DistMax", contact_zone + (size - size_contact) / growth)
    fields.setAsBackgroundMesh(threshold)
    for option in ("MeshSizeExtendFromBoundary", "MeshSizeFromPoints", "MeshSizeFromCurvature"):
        gmsh.option.setNumber(f"Mesh.{option}", 0)


def quarter_disc(R: float, size: float, size_contact: float, contact_zone: float, order: int = 2,
                 growth: float = 0.25, comm: MPI.Comm = MPI.COMM_WORLD,
                 cache_dir: str | os.PathLike = "meshes", half: bool = False) -> MeshData:
    """Hertz body: the part x >= 0, y <= R of the disc of radius R centred at (0, R), touching y = 0 at 0
    (with ``half``, the whole lower half y <= R).

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
    half
        The half disc -R <= x <= R, y <= R (a cylinder that slides: no symmetry about x = 0).

    Returns
    -------
    MeshData
        Facet tags top (the flat edge y = R, loaded) = 1, xsym (x = 0) = 2, contact (the arc) = 3;
        the half disc has top = 1 and contact = 3 (two arcs, from x = R and from x = -R to the origin).
    """
    _positive(R=R, size=size, size_contact=size_contact, contact_zone=contact_zone, growth=growth)
    order = _check_order(order)
    if size_contact > size:
        raise MeshError(f"size_contact must not exceed size = {size}, got {size_contact!r}")
    if not isinstance(half, bool):
        raise MeshError(f"half must be True or False, got {half!r}")
    params = dict(R=float(R), size=float(size), size_contact=float(size_contact),
                  contact_zone=float(contact_zone), order=order, growth=float(growth))
    if half:                    # only then, so that the quarter's cache names stay as they were
        params["half"] = True

    def construct() -> None:
        origin, surface, tops, contacts, xsym = _disc_outline(R, size, half)
        gmsh.model.geo.synchronize()
        _refine_towards(origin, size, size_contact, contact_zone, growth)
        add_group(2, [surface], BODY_TAG, "body")
        for tag, (name, curves) in enumerate([("top", tops), ("xsym", [xsym]), ("contact", contacts)],
                                             start=1):
            if curves != [None]:
                add_group(1, curves, tag, name)

    _not_too_fine("quarter_disc", params)
    return build_cached("quarter_disc", params, construct, comm, cache_dir)


def necking_bar_grid(R: float = 6.413, L: float = 53.334, reduction: float = 0.018, n_r: int = 5,
                     n_z: int = 40, grading: float = 3.0) -> tuple[np.ndarray, np.ndarray]:
    """The vertex grid of :func:`necking_bar`: axial positions z_j (n_z + 1) and radii r_ij
    ((n_z + 1) x (n_r + 1)), r_ij = (i / n_r) R(z_j), R(z) the tapered radius. The builder's Gmsh mesh
    has these vertices (transfinite interpolation of the same boundary points); an independent code can
    mesh the bar with them."""
    q = _progression(grading, n_z)
    j = np.arange(n_z + 1)
    z = 0.5 * L * (j / n_z if q == 1.0 else (q ** j - 1.0) / (q ** n_z - 1.0))
    radius = R * (1.0 - reduction * (1.0 - z / (0.5 * L)))
    return z, radius[:, None] * np.arange(n_r + 1)[None, :] / n_r


def _progression(grading: float, n_z: int) -> float:
    """The ratio of consecutive cell lengths along z of :func:`necking_bar` with ``grading``."""
    return grading ** (1.0 / (n_z - 1)) if n_z > 1 else 1.0


def _check_necking_bar(n_r, n_z, reduction, grading) -> None:
    """ValueError unless the cell counts are integers >= 1, 0 <= reduction < 1 and grading >= 1."""
    for name, n in (("n_r", n_r), ("n_z", n_z)):
        if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 1:
            raise ValueError(f"{name} must be an integer >= 1, got {n!r}")
    if not (isinstance(reduction, (int, float, np.number)) and 0.0 <= reduction < 1.0):
        raise ValueError(f"reduction must be a number in [0, 1), got {reduction!r}")
    if grading < 1.0:
        raise ValueError(f"grading must be >= 1 (cells longest at the end), got {grading!r}")


def _necking_bar_outline(R: float, L: float, reduction: float, n_r: int, n_z: int,
                         grading: float) -> tuple:
    """The transfinite geometry of :func:`necking_bar` (not synchronized): (the surface, its curves
    (neck, surface, end, axis), all pointing to +r or +z)."""
    geo = gmsh.model.geo
    h, r_neck = 0.5 * L, R * (1.0 - reduction)
    p = [geo.addPoint(x, y, 0.0) for x, y in [(0.0, 0.0), (r_neck, 0.0), (R, h), (0.0, h)]]
    neck, surface = geo.addLine(p[0], p[1]), geo.addLine(p[1], p[2])
    end, axis = geo.addLine(p[3], p[2]), geo.addLine(p[0], p[3])
    body = geo.addPlaneSurface([geo.addCurveLoop([neck, surface, -end, -axis])])
    for curve, n in ((neck, n_r), (end, n_r)):
        geo.mesh.setTransfiniteCurve(curve, n + 1)
    for curve in (surface, axis):
        geo.mesh.setTransfiniteCurve(curve, n_z + 1, "Progression", _progression(grading, n_z))
    geo.mesh.setTransfiniteSurface(body, _ARRANGEMENT, [p[0], p[1], p[2], p[3]])
    return body, (neck, surface, end, axis)


def necking_bar(R: float = 6.413, L: float = 53.334, reduction: float = 0.018, n_r: int = 5,
                n_z: int = 40, grading: float = 3.0, order: int = 2, comm: MPI.Comm = MPI.COMM_WORLD,
                cache_dir: str | os.PathLike = "meshes") -> MeshData:
    """The quarter of the axial section of a round tensile bar with a neck at its centre (axisymmetric:
    x = r, y = z), structured triangles.

    The bar of length L and radius R is modelled on 0 <= z <= L/2 (its centre, the neck, at z = 0, a
    plane of symmetry) and 0 <= r <= R(z); the radius tapers linearly from R (1 - reduction) at the
    neck to R at the end z = L/2, the imperfection that starts the neck there (Simo 1988: R = 6.413,
    L = 53.334, reduction 1.8 %).

    Parameters
    ----------
    R, L
        Radius at the end and length of the whole bar (in the user's units; the benchmark's are mm).
    reduction
        Relative reduction of the radius at the neck, 0 <= reduction < 1.
    n_r, n_z
        Cells across the radius (uniform) and along the half-length, each cell cut into two
        triangles with alternating diagonals.
    grading
        Ratio of the longest cell (at the end) to the shortest (at the neck) along z, >= 1: lengths
        in geometric progression.
    order, comm, cache_dir
        As for `rectangle`.

    Returns
    -------
    MeshData
        Facet tags axis (r = 0) = 1, neck (z = 0, the symmetry plane) = 2, end (z = L/2, pulled) = 3,
        surface (the free outer surface) = 4; cells "body" = BODY_TAG. The vertices are those of
        :func:`necking_bar_grid`.
    """
    _positive(R=R, L=L, grading=grading)
    order = _check_order(order)
    _check_necking_bar(n_r, n_z, reduction, grading)
    params = dict(R=float(R), L=float(L), reduction=float(reduction), n_r=int(n_r), n_z=int(n_z),
                  grading=float(grading), order=order)

    def construct() -> None:
        body, (neck, surface, end, axis) = _necking_bar_outline(R, L, reduction, n_r, n_z, grading)
        gmsh.model.geo.synchronize()
        add_group(2, [body], BODY_TAG, "body")
        for tag, (name, curve) in enumerate(
                [("axis", axis), ("neck", neck), ("end", end), ("surface", surface)], start=1):
            add_group(1, [curve], tag, name)

    _not_too_fine("necking_bar", params)
    return build_cached("necking_bar", params, construct, comm, cache_dir)

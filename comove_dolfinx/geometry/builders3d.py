"""The Gmsh builders of 3D bodies (tetrahedra, or for ``box`` and ``tube_sector`` hexahedra, with
named faces; cached .msh files, see geometry/__init__.py)."""
from __future__ import annotations

import math
import os

from mpi4py import MPI

from .builders import _check_order, _not_too_fine, _positive, _structured
from .gmsh_session import gmsh
from .meshes import BODY_TAG, MeshData, MeshError, add_group, build_cached


def box(Lx: float, Ly: float, Lz: float, size: float, order: int = 2, x0: float = 0.0, y0: float = 0.0,
        z0: float = 0.0, comm: MPI.Comm = MPI.COMM_WORLD, cache_dir: str | os.PathLike = "meshes",
        hexahedra: bool = False) -> MeshData:
    """Structured tetrahedra (or hexahedra) on [x0, x0+Lx] x [y0, y0+Ly] x [z0, z0+Lz], with named faces.

    The face z = z0 is meshed as ``rectangle(Lx, Ly, size)`` meshes its rectangle, and its
    triangles are extruded in layers along z, each prism cut into three tetrahedra: every section
    z = const of the mesh is that 2D mesh (a plane-strain comparison meets the same discretisation).
    With ``hexahedra=True`` the face is a grid of nx x ny quadrilaterals and the extrusion makes
    nx x ny x nz bricks (order 2: Gmsh's 27-node hexahedra).

    Parameters
    ----------
    Lx, Ly, Lz
        Edge lengths along x, y and z.
    size
        Target element edge: nx = ceil(Lx/size), ny = max(ceil(Ly/size), 2) and
        nz = max(ceil(Lz/size), 1) cells along the edges.
    order
        Geometry order, 1 or 2.
    x0, y0, z0
        The corner with the smallest coordinates.
    comm, cache_dir
        As for ``rectangle``.
    hexahedra
        Bricks instead of tetrahedra.

    Returns
    -------
    MeshData
        Facet tags left (x = x0) = 1, right (x = x0+Lx) = 2, front (y = y0) = 3, back (y = y0+Ly) = 4,
        bottom (z = z0) = 5, top (z = z0+Lz) = 6; cells "body" = BODY_TAG (gdim = tdim = 3).
    """
    _positive(Lx=Lx, Ly=Ly, Lz=Lz, size=size)
    order = _check_order(order)
    params = dict(Lx=float(Lx), Ly=float(Ly), Lz=float(Lz), size=float(size), order=order,
                  x0=float(x0), y0=float(y0), z0=float(z0), **_hexahedra(hexahedra))
    _not_too_fine("box", params)
    nx, ny, nz = math.ceil(Lx / size), max(math.ceil(Ly / size), 2), max(math.ceil(Lz / size), 1)

    def construct() -> None:
        geo = gmsh.model.geo
        p = [geo.addPoint(x, y, z0) for x, y in
             [(x0, y0), (x0 + Lx, y0), (x0 + Lx, y0 + Ly), (x0, y0 + Ly)]]
        front, right, back, left = (geo.addLine(p[i], p[(i + 1) % 4]) for i in range(4))
        bottom = _structured([front, right, back, left], [nx, ny, nx, ny])
        if hexahedra:
            geo.mesh.setRecombine(2, bottom)
        # extrude: [top face, volume, the faces swept by front, right, back, left]
        out = geo.extrude([(2, bottom)], 0.0, 0.0, Lz, numElements=[nz], recombine=bool(hexahedra))
        geo.synchronize()
        add_group(3, [out[1][1]], BODY_TAG, "body")
        faces = {"left": out[5][1], "right": out[3][1], "front": out[2][1], "back": out[4][1],
                 "bottom": bottom, "top": out[0][1]}
        for tag, name in enumerate(("left", "right", "front", "back", "bottom", "top"), start=1):
            add_group(2, [faces[name]], tag, name)

    return build_cached("box", params, construct, comm, cache_dir, dim=3)


def _hexahedra(hexahedra) -> dict:
    """The parameter to hash for hexahedra (none for tetrahedra: their cache names stay as they
    were); MeshError unless True or False."""
    if not isinstance(hexahedra, bool):
        raise MeshError(f"hexahedra must be True or False, got {hexahedra!r}")
    return {"hexahedra": True} if hexahedra else {}


def _check_refinement(size: float, size_contact, contact_zone, growth: float) -> dict:
    """The refinement parameters to hash (empty without ``size_contact``); MeshError if unusable."""
    if size_contact is None:
        return {}
    _positive(size_contact=size_contact, contact_zone=contact_zone, growth=growth)
    if size_contact > size:
        raise MeshError(f"size_contact must not exceed size = {size}, got {size_contact!r}")
    return dict(size_contact=float(size_contact), contact_zone=float(contact_zone), growth=float(growth))


def _sizes_near(point: tuple, size: float, refine: dict) -> None:
    """Element size ``size`` everywhere, or (with ``refine``) ``size_contact`` within ``contact_zone``
    of ``point``, growing by ``growth`` per unit distance up to ``size`` (the only size source)."""
    fields = gmsh.model.mesh.field
    for option in ("MeshSizeExtendFromBoundary", "MeshSizeFromPoints", "MeshSizeFromCurvature"):
        gmsh.option.setNumber(f"Mesh.{option}", 0)
    if not refine:
        gmsh.option.setNumber("Mesh.MeshSizeMax", size)
        gmsh.option.setNumber("Mesh.MeshSizeMin", size)
        return
    distance = fields.add("MathEval")
    x, y, z = (repr(float(c)) for c in point)
    fields.setString(distance, "F", f"Sqrt((x - ({x}))^2 + (y - ({y}))^2 + (z - ({z}))^2)")
    fine, zone = refine["size_contact"], refine["contact_zone"]
    threshold = fields.add("Threshold")
    fields.setNumber(threshold, "InField", distance)
    fields.setNumber(threshold, "SizeMin", fine)
    fields.setNumber(threshold, "SizeMax", size)
    fields.setNumber(threshold, "DistMin", zone)
    fields.setNumber(threshold, "DistMax", zone + (size - fine) / refine["growth"])
    fields.setAsBackgroundMesh(threshold)


def _faces_where(dim_tags: list, test) -> list[int]:
    """The OCC faces among ``dim_tags`` whose centre of mass (x, y, z) passes ``test``."""
    return [tag for dim, tag in dim_tags if dim == 2 and test(gmsh.model.occ.getCenterOfMass(2, tag))]


def _tube_groups(volume: int, r_in: float, r_out: float, length: float, angle: float, tol: float) -> None:
    """Physical groups of the tube sector (the OCC ``volume``, synchronized)."""
    faces = gmsh.model.getBoundary([(3, volume)], oriented=False)
    c, s = math.cos(math.pi / 2 - angle), math.sin(math.pi / 2 - angle)
    inside = (lambda m: tol < m[2] < length - tol)           # not an end face
    on_plane = {
        "xsym": lambda m: abs(m[0]) < tol and m[1] > tol and inside(m),
        "side": lambda m: abs(-s * m[0] + c * m[1]) < tol and c * m[0] + s * m[1] > tol and inside(m),
        "zsym": lambda m: abs(m[2]) < tol,
        "end": lambda m: abs(m[2] - length) < tol,
    }
    groups = {name: _faces_where(faces, test) for name, test in on_plane.items()}
    flat = {t for tags in groups.values() for t in tags}
    curved = [tag for dim, tag in faces if tag not in flat]
    radius = {tag: gmsh.model.occ.getMass(2, tag) / (angle * length) for tag in curved}  # area = r angle L
    groups["inner"] = [t for t in curved if radius[t] < 0.5 * (r_in + r_out)]
    groups["outer"] = [t for t in curved if t not in groups["inner"]]
    if abs(angle - math.pi) < 1e-12:
        groups["xsym"] += groups.pop("side")
    elif abs(angle - math.pi / 2) < 1e-12:
        groups["ysym"] = groups.pop("side")
    add_group(3, [volume], BODY_TAG, "body")
    for tag, name in enumerate(n for n in ("inner", "outer", "xsym", "ysym", "side", "zsym", "end")
                               if n in groups):
        add_group(2, groups[name], tag + 1, name)


def _bricks(volume: int, size: float, arc: float, tol: float) -> None:
    """Make the OCC ``volume`` (six four-sided faces) a transfinite grid of hexahedra: every curve
    along z or through the wall (straight) gets ceil(its length / size) cells, every arc
    ceil(``arc`` / size), so that the opposite edges of each face have the same count."""
    mesh = gmsh.model.mesh
    faces = gmsh.model.getBoundary([(3, volume)], oriented=False)
    curves = {abs(c) for _, f in faces for _, c in gmsh.model.getBoundary([(2, f)], oriented=False)}
    for curve in sorted(curves):
        ends = [gmsh.model.getValue(0, p, []) for _, p in gmsh.model.getBoundary([(1, curve)])]
        chord = math.dist(ends[0], ends[1])
        straight = abs(gmsh.model.occ.getMass(1, curve) - chord) < tol
        mesh.setTransfiniteCurve(curve, math.ceil((chord if straight else arc) / size) + 1)
    for _, face in faces:
        mesh.setTransfiniteSurface(face)
        mesh.setRecombine(2, face)
    mesh.setTransfiniteVolume(volume)


def _tube_params(r_in, r_out, length, size, angle, order, grading: tuple, hexahedra) -> tuple[dict, dict]:
    """The parameters of :func:`tube_sector` to hash and those of its refinement (``grading``:
    size_contact, contact_zone, growth), checked (MeshError naming the value)."""
    _positive(r_in=r_in, r_out=r_out, length=length, size=size, angle=angle)
    order = _check_order(order)
    if not r_in < r_out:
        raise MeshError(f"r_in must be smaller than r_out, got r_in={r_in!r}, r_out={r_out!r}")
    if not angle <= math.pi:
        raise MeshError(f"angle must lie in (0, pi] (radians; pi/2 is a quarter), got {angle!r}")
    refine = _check_refinement(size, *grading)
    if hexahedra is True and refine:
        raise MeshError(f"size_contact = {refine['size_contact']!r} grades tetrahedra only: drop it with "
                        "hexahedra=True (the bricks are uniform; a smaller size refines them all)")
    params = dict(r_in=float(r_in), r_out=float(r_out), length=float(length), size=float(size),
                  angle=float(angle), order=order, **refine, **_hexahedra(hexahedra))
    _not_too_fine("tube_sector", params)
    return params, refine


def tube_sector(r_in: float, r_out: float, length: float, size: float, angle: float = math.pi / 2,
                order: int = 2, size_contact: float | None = None, contact_zone: float | None = None,
                growth: float = 0.25, comm: MPI.Comm = MPI.COMM_WORLD,
                cache_dir: str | os.PathLike = "meshes", hexahedra: bool = False) -> MeshData:
    """A sector of a thick-walled tube along z: r_in <= r <= r_out, pi/2 - angle <= theta <= pi/2
    (theta from the x axis), 0 <= z <= length; unstructured tetrahedra, or structured hexahedra.

    The sector always contains the top line x = 0, y = r_out, so a transverse tool pressing along -y
    at z = 0 touches the point (0, r_out, 0): ``angle = pi`` with the symmetry faces x = 0 and z = 0
    is the quarter model of a tube dented there (the half section x >= 0 over half the length),
    ``angle = pi / 2`` the quarter x, y >= 0.

    Parameters
    ----------
    r_in, r_out
        Inner and outer radius (0 < r_in < r_out).
    length
        Length along z.
    size
        Element size (gmsh's target edge length).
    angle
        Opening of the sector in radians, 0 < angle <= pi.
    order
        Geometry order, 1 or 2 (mid-side nodes on the true cylinders).
    size_contact, contact_zone, growth
        With ``size_contact`` (<= size): elements of that size within ``contact_zone`` of
        (0, r_out, 0), growing by ``growth`` per unit distance up to ``size`` (tetrahedra only).
    comm, cache_dir
        As for ``rectangle``.
    hexahedra
        A transfinite grid of bricks instead: ceil(angle (r_in + r_out) / 2 / size) cells around,
        ceil((r_out - r_in) / size) through the wall and ceil(length / size) along z (order 2:
        Gmsh's 27-node hexahedra, their nodes on the true cylinders). Where the wall takes two
        cells or more, the section is ``annulus_sector(..., quadrilaterals=True)``'s grid.

    Returns
    -------
    MeshData
        Facet tags, numbered from 1 in this order: inner (r = r_in), outer (r = r_out), xsym (the
        radial face on x = 0, y > 0), the other radial face (theta = pi/2 - angle): "ysym" for
        angle = pi/2 (on y = 0), part of "xsym" for angle = pi (on x = 0, y < 0), "side" otherwise;
        zsym (z = 0), end (z = length). Cells "body" = BODY_TAG.
    """
    params, refine = _tube_params(r_in, r_out, length, size, angle, order, (size_contact, contact_zone, growth),
                                  hexahedra)

    def construct() -> None:
        occ = gmsh.model.occ
        turn = [(3, occ.addCylinder(0, 0, 0, 0, 0, length, r, angle=angle)) for r in (r_out, r_in)]
        wall = occ.cut([turn[0]], [turn[1]])[0]
        occ.rotate(wall, 0, 0, 0, 0, 0, 1, math.pi / 2 - angle)
        occ.synchronize()
        _tube_groups(wall[0][1], r_in, r_out, length, angle, 1e-7 * r_out)
        _sizes_near((0.0, r_out, 0.0), size, refine)
        if hexahedra:
            _bricks(wall[0][1], size, angle * 0.5 * (r_in + r_out), 1e-7 * r_out)

    return build_cached("tube_sector", params, construct, comm, cache_dir, dim=3)


def sphere_octant(R: float, size: float, order: int = 2, size_contact: float | None = None,
                  contact_zone: float | None = None, growth: float = 0.25, comm: MPI.Comm = MPI.COMM_WORLD,
                  cache_dir: str | os.PathLike = "meshes") -> MeshData:
    """The octant x, y, z >= 0 of the solid sphere of radius R centred at the origin; unstructured
    tetrahedra, refined near the pole (0, 0, R) where a plane z = const touches it (Hertz).

    Parameters
    ----------
    R
        Radius.
    size
        Element size (gmsh's target edge length).
    order
        Geometry order, 1 or 2 (mid-side nodes on the true sphere).
    size_contact, contact_zone, growth
        With ``size_contact`` (<= size): elements of that size within ``contact_zone`` of the pole
        (0, 0, R), growing by ``growth`` per unit distance up to ``size``.
    comm, cache_dir
        As for ``rectangle``.

    Returns
    -------
    MeshData
        Facet tags xsym (x = 0) = 1, ysym (y = 0) = 2, zsym (z = 0) = 3, outer (the sphere) = 4;
        cells "body" = BODY_TAG.
    """
    _positive(R=R, size=size)
    order = _check_order(order)
    refine = _check_refinement(size, size_contact, contact_zone, growth)
    params = dict(R=float(R), size=float(size), order=order, **refine)
    _not_too_fine("sphere_octant", params)

    def construct() -> None:
        occ = gmsh.model.occ
        occ.addSphere(0, 0, 0, R, 1, 0.0, math.pi / 2, math.pi / 2)
        occ.synchronize()
        faces, tol = gmsh.model.getBoundary([(3, 1)], oriented=False), 1e-7 * R
        groups = {name: _faces_where(faces, lambda m, k=k: abs(m[k]) < tol)
                  for k, name in enumerate(("xsym", "ysym", "zsym"))}
        flat = {t for tags in groups.values() for t in tags}
        groups["outer"] = [tag for dim, tag in faces if tag not in flat]
        add_group(3, [1], BODY_TAG, "body")
        for tag, name in enumerate(("xsym", "ysym", "zsym", "outer"), start=1):
            add_group(2, groups[name], tag, name)
        _sizes_near((0.0, 0.0, R), size, refine)

    return build_cached("sphere_octant", params, construct, comm, cache_dir, dim=3)


def _plate_groups(volumes: list, R: float, t: float, z_support: float) -> None:
    """Physical groups of the quarter plate (its OCC ``volumes``, synchronized)."""
    faces, tol = gmsh.model.getBoundary([(3, v) for v in volumes], combined=True, oriented=False), 1e-7 * R
    on_plane = {"top": lambda m: abs(m[2] - t) < tol, "bottom": lambda m: abs(m[2]) < tol,
                "xsym": lambda m: abs(m[0]) < tol, "ysym": lambda m: abs(m[1]) < tol}
    groups = {name: _faces_where(faces, test) for name, test in on_plane.items()}
    flat = {tag for tags in groups.values() for tag in tags}
    curved = [(dim, tag) for dim, tag in faces if tag not in flat]
    groups["rim_support"] = _faces_where(curved, lambda m: m[2] < z_support)
    groups["rim"] = [tag for dim, tag in curved if tag not in groups["rim_support"]]
    add_group(3, volumes, BODY_TAG, "body")
    for tag, name in enumerate(("top", "bottom", "rim_support", "rim", "xsym", "ysym"), start=1):
        add_group(2, groups[name], tag, name)


def _sizes_near_plate(R: float, z_support: float, size: float, refine: dict) -> None:
    """Element size ``size``, or (with ``refine``) ``size_contact`` on the disc z = 0, r <=
    ``contact_radius`` and ``size_rim`` on the rim support (r = R, z <= z_support), each growing by
    ``growth`` per unit distance from there up to ``size``."""
    _sizes_near((0.0, 0.0, 0.0), size, {})
    if not refine:
        return
    terms = [repr(size)]
    r = "Sqrt(x^2 + y^2)"
    if "size_contact" in refine:
        disc = f"Sqrt(Max({r} - {refine['contact_radius']!r}, 0)^2 + z^2)"
        terms.append(f"{refine['size_contact']!r} + {refine['growth']!r} * {disc}")
    if "size_rim" in refine:
        rim = f"Sqrt(({R!r} - {r})^2 + Max(z - {z_support!r}, 0)^2)"
        terms.append(f"{refine['size_rim']!r} + {refine['growth']!r} * {rim}")
    fields = gmsh.model.mesh.field
    field = fields.add("MathEval")
    expression = terms[0]
    for term in terms[1:]:
        expression = f"Min({expression}, {term})"
    fields.setString(field, "F", expression)
    fields.setAsBackgroundMesh(field)
    gmsh.option.setNumber("Mesh.MeshSizeMin", min(refine.get(k, size) for k in ("size_contact", "size_rim")))


def _plate_refinement(size: float, size_contact, contact_radius, size_rim, growth: float) -> dict:
    """The refinement parameters of plate_quarter to hash (empty without refinement); MeshError if
    unusable."""
    if size_contact is not None and contact_radius is None:
        raise MeshError("size_contact needs contact_radius, the radius of the refined disc on the bottom face")
    refine = _check_refinement(size, size_contact, contact_radius, growth)
    if refine:
        refine["contact_radius"] = refine.pop("contact_zone")
    if size_rim is not None:
        _positive(size_rim=size_rim, growth=growth)
        if size_rim > size:
            raise MeshError(f"size_rim must not exceed size = {size}, got {size_rim!r}")
        refine.update(size_rim=float(size_rim), growth=float(growth))
    return refine


def plate_quarter(R: float = 10.0, t: float = 2.0, z_support: float = 0.25, size: float = 0.5,
                  order: int = 2, size_contact: float | None = None, contact_radius: float | None = None,
                  size_rim: float | None = None, growth: float = 0.25, comm: MPI.Comm = MPI.COMM_WORLD,
                  cache_dir: str | os.PathLike = "meshes") -> MeshData:
    """The quarter x, y >= 0 of the thick circular plate r <= R, 0 <= z <= t (the 3D body of the
    axisymmetric ``plate_section``); unstructured tetrahedra, the rim split at z = z_support.

    Parameters
    ----------
    R, t
        Plate radius and thickness.
    z_support
        Height (0 < z_support < t) at which the rim r = R is split: the lower part carries the
        rim support.
    size
        Element size (gmsh's target edge length).
    order
        Geometry order, 1 or 2 (mid-side nodes on the true cylinder).
    size_contact, contact_radius, size_rim, growth
        With ``size_contact`` (<= size): elements of that size on the bottom face within
        ``contact_radius`` of the axis (where the plate meets a base below it); with ``size_rim``
        (<= size): elements of that size on the rim support; each growing by ``growth`` per unit
        distance from there up to ``size``.
    comm, cache_dir
        As for ``rectangle``.

    Returns
    -------
    MeshData
        Facet tags top (z = t) = 1, bottom (z = 0) = 2, rim_support (r = R, z <= z_support) = 3,
        rim (r = R, z >= z_support) = 4, xsym (x = 0) = 5, ysym (y = 0) = 6; cells "body" = BODY_TAG.
    """
    _positive(R=R, t=t, z_support=z_support, size=size)
    order = _check_order(order)
    if not z_support < t:
        raise MeshError(f"z_support must lie strictly between 0 and t = {t}, got {z_support!r}")
    refine = _plate_refinement(size, size_contact, contact_radius, size_rim, growth)
    params = dict(R=float(R), t=float(t), z_support=float(z_support), size=float(size), order=order, **refine)
    _not_too_fine("plate_quarter", params)

    def construct() -> None:
        occ = gmsh.model.occ
        low = occ.addCylinder(0, 0, 0, 0, 0, z_support, R, angle=math.pi / 2)
        up = occ.addCylinder(0, 0, z_support, 0, 0, t - z_support, R, angle=math.pi / 2)
        pieces = occ.fragment([(3, low)], [(3, up)])[0]
        occ.synchronize()
        _plate_groups([tag for dim, tag in pieces if dim == 3], R, t, z_support)
        _sizes_near_plate(R, z_support, size, refine)

    return build_cached("plate_quarter", params, construct, comm, cache_dir, dim=3)

"""The Gmsh builders of 3D bodies (tetrahedra with named faces; cached .msh files, see
geometry/__init__.py)."""
from __future__ import annotations

import math
import os

from mpi4py import MPI

from .builders import _check_order, _not_too_fine, _positive, _structured
from .gmsh_session import gmsh
from .meshes import BODY_TAG, MeshData, add_group, build_cached


def box(Lx: float, Ly: float, Lz: float, size: float, order: int = 2, x0: float = 0.0, y0: float = 0.0,
        z0: float = 0.0, comm: MPI.Comm = MPI.COMM_WORLD, cache_dir: str | os.PathLike = "meshes") -> MeshData:
    """Structured tetrahedra on [x0, x0+Lx] x [y0, y0+Ly] x [z0, z0+Lz], with named faces.

    The face z = z0 is meshed as ``rectangle(Lx, Ly, size)`` meshes its rectangle, and its
    triangles are extruded in layers along z, each prism cut into three tetrahedra: every section
    z = const of the mesh is that 2D mesh (a plane-strain comparison meets the same discretisation).

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

    Returns
    -------
    MeshData
        Facet tags left (x = x0) = 1, right (x = x0+Lx) = 2, front (y = y0) = 3, back (y = y0+Ly) = 4,
        bottom (z = z0) = 5, top (z = z0+Lz) = 6; cells "body" = BODY_TAG (gdim = tdim = 3).
    """
    _positive(Lx=Lx, Ly=Ly, Lz=Lz, size=size)
    order = _check_order(order)
    params = dict(Lx=float(Lx), Ly=float(Ly), Lz=float(Lz), size=float(size), order=order,
                  x0=float(x0), y0=float(y0), z0=float(z0))
    _not_too_fine("box", params)
    nx, ny, nz = math.ceil(Lx / size), max(math.ceil(Ly / size), 2), max(math.ceil(Lz / size), 1)

    def construct() -> None:
        geo = gmsh.model.geo
        p = [geo.addPoint(x, y, z0) for x, y in
             [(x0, y0), (x0 + Lx, y0), (x0 + Lx, y0 + Ly), (x0, y0 + Ly)]]
        front, right, back, left = (geo.addLine(p[i], p[(i + 1) % 4]) for i in range(4))
        bottom = _structured([front, right, back, left], [nx, ny, nx, ny])
        # extrude: [top face, volume, the faces swept by front, right, back, left]
        out = geo.extrude([(2, bottom)], 0.0, 0.0, Lz, numElements=[nz])
        geo.synchronize()
        add_group(3, [out[1][1]], BODY_TAG, "body")
        faces = {"left": out[5][1], "right": out[3][1], "front": out[2][1], "back": out[4][1],
                 "bottom": bottom, "top": out[0][1]}
        for tag, name in enumerate(("left", "right", "front", "back", "bottom", "top"), start=1):
            add_group(2, [faces[name]], tag, name)

    return build_cached("box", params, construct, comm, cache_dir, dim=3)

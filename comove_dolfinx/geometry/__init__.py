"""Gmsh builders for the 2D bodies of the scenes, cached as .msh files and loaded distributed.

Every builder makes a triangle mesh in the (x, y) plane (gdim = 2; for the axisymmetric plate x is the
radius r and y the axial coordinate z) with straight-sided (order 1) or curved (order 2, mid-side nodes on
the true arcs) triangles; :func:`box`, :func:`tube_sector`, :func:`sphere_octant` and :func:`plate_quarter` make tetrahedra
in 3D (gdim = 3, named faces instead of curves, for the model "solid"; order 2 puts the mid-edge nodes
on the true cylinders and sphere), :func:`box` and :func:`tube_sector` with ``hexahedra=True``
structured hexahedra (Gmsh's 8-node bricks, or its 27-node ones at order 2). Lengths are in the user's units (the scenes use cm).

Physical groups: one surface group "body" (cell tag ``BODY_TAG``) and one named curve group per boundary
part; their tag values, distinct per name and numbered from 1 in the order listed by each builder, are in
``MeshData.tags`` and are used as ``ds(data.ds_id("top"))`` with
``ufl.Measure("ds", domain=data.mesh, subdomain_data=data.facet_tags)``.

Caching: rank 0 builds the mesh once and writes ``<cache_dir>/<builder>_<hash>.msh``, where the hash
covers every parameter (order included) and the gmsh version; the file is written under a temporary name
and renamed, so a concurrent reader never sees half a file. Later calls, in any process, reuse the file,
through its arrays (``<builder>_<hash>.npz`` beside it, mesh_arrays.py): a mesh in the cache is read
without gmsh, which is imported only to build a mesh (or to read a cached one the first time).

Gmsh runs on rank 0 only: the builders call ``gmsh.initialize``/``gmsh.finalize`` there, so do not call
them from inside a gmsh session of your own. For a session of your own (meshing a .geo script, as
demos/demo_seal.py does), ``gmsh_session.start()``/``stop()`` keep Python's Ctrl-C handler, which
gmsh's own calls replace by the system's default (the process then dies at Ctrl-C without a word).
"""
from .builders import annulus_sector, necking_bar, necking_bar_grid, plate_section, quarter_disc, rectangle
from .builders3d import box, plate_quarter, sphere_octant, tube_sector
from .meshes import (
           BODY_TAG,
           MeshData,
           MeshError,
           fix_coordinate_element,
           from_dolfinx,
           load_msh,
)

__all__ = ["BODY_TAG", "MeshData", "MeshError", "annulus_sector", "box", "fix_coordinate_element", "from_dolfinx",
           "load_msh", "necking_bar", "necking_bar_grid", "plate_quarter", "plate_section", "quarter_disc", "rectangle",
           "sphere_octant", "tube_sector"]

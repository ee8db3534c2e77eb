"""Mesh data with named boundaries: reading .msh files, wrapping dolfinx meshes, the builders' cache.

The builders' cache holds, beside each ``<builder>_<hash>.msh``, its arrays (``.npz``: the nodes, the
cells and facets of the physical groups with their tags, the groups' names), which a later run
reads with NumPy and hands to dolfinx as its gmsh reader would: a run whose mesh is in the cache
never loads gmsh.
"""
from __future__ import annotations

import hashlib
import json
import os
import pathlib
from dataclasses import dataclass, field
from typing import Callable, Iterable

import dolfinx
import numpy as np
from mpi4py import MPI

from .. import compat
from . import mesh_arrays
from .gmsh_session import gmsh
from .gmsh_session import start as _start_gmsh
from .gmsh_session import stop as _stop_gmsh
from .gmsh_session import version as _gmsh_version

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
        The mesh (gdim = 2; gdim = 3 for a 3D mesh of tetrahedra or hexahedra), already passed through
        `fix_coordinate_element`.
    cell_tags, facet_tags : dolfinx.mesh.MeshTags
        Tags of the physical surfaces and curves of the .msh file (in 3D: volumes and surfaces).
    tags : dict[str, int]
        Facet (curve; surface in 3D) physical-group name -> tag value.
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


def _cache_path(builder: str, params: dict, cache_dir: str | os.PathLike) -> pathlib.Path:
    """File name <builder>_<10-hex hash of parameters, gmsh version and cache format>.msh."""
    key = json.dumps({"builder": builder, "params": params, "gmsh": _gmsh_version(),
                      "format": _CACHE_FORMAT}, sort_keys=True)
    digest = hashlib.sha1(key.encode()).hexdigest()[:10]
    return pathlib.Path(cache_dir) / f"{builder}_{digest}.msh"


def add_group(dim: int, entities: list[int], tag: int, name: str) -> None:
    """Add the physical group `tag` of dimension `dim` with the given name."""
    gmsh.model.addPhysicalGroup(dim, entities, tag)  # gmsh 4.8: no name argument yet
    gmsh.model.setPhysicalName(dim, tag, name)


def build_cached(builder: str, params: dict, construct: Callable[[], None], comm: MPI.Comm,
                 cache_dir: str | os.PathLike, dim: int = 2) -> MeshData:
    """Write the mesh on rank 0 unless its cache file exists, then read it on every rank.

    `construct` creates the geometry, the physical groups and the mesh-size settings of the current
    gmsh model (and synchronizes); this function meshes it, raises its order (``params["order"]``)
    and writes the file under a temporary name, renamed into place. A gmsh failure on rank 0 is
    raised on every rank (MeshError). The builders of this package and the verification cases'
    meshes use it. ``dim``: the dimension meshed, 2 (triangles) or 3 (tetrahedra, or the hexahedra
    that ``construct`` asks for with transfinite, recombined entities). The mesh's
    arrays are read from the ``.npz`` beside the ``.msh`` (written at the first read, with gmsh),
    so that gmsh is loaded only to build a mesh or to read one the first time.
    """
    path = _cache_path(builder, params, cache_dir)
    error = None
    if comm.rank == 0 and not path.exists():
        error = _build(builder, params, construct, path, dim)
    error = comm.bcast(error, root=0)  # also the barrier: no rank reads before the file exists
    if error is not None:
        raise MeshError(error)
    arrays = mesh_arrays.read(path) if comm.rank == 0 else None
    if comm.rank == 0 and arrays is None:
        arrays, error = _arrays_with_gmsh(path, ())
        if error is None:
            mesh_arrays.write(path, arrays)
    return _distribute(path, arrays, error, comm)


def _build(builder: str, params: dict, construct: Callable[[], None], path: pathlib.Path, dim: int):
    """Mesh the model that ``construct`` makes and write it to ``path`` (rank 0); the error, or None."""
    tmp = path.with_name(f".{path.stem}.{os.getpid()}.tmp.msh")  # gmsh wants the .msh suffix
    _start_gmsh()
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        gmsh.model.add(builder)
        construct()
        gmsh.model.mesh.generate(dim)
        gmsh.model.mesh.setOrder(params["order"])  # order 2: new nodes on the true curves
        gmsh.write(str(tmp))
        os.replace(tmp, path)
    except Exception as err:  # gmsh raises plain Exception
        return f"building {path} with gmsh failed: {err}"
    finally:
        _stop_gmsh()
        if tmp.exists():
            tmp.unlink()
    return None


def _groups_of_current_model(path: pathlib.Path, required: Iterable[str]) -> tuple[dict, dict, int]:
    """Facet and cell physical groups (name -> tag) of the merged file and its dimension (2, or 3
    with physical volumes); MeshError if unusable."""
    groups = gmsh.model.getPhysicalGroups()
    if not groups:
        raise MeshError(f"{path} has no physical groups; tag the body surface and the boundary curves "
                        "(Physical Surface / Physical Curve) before saving the mesh")
    top = max(dim for dim, _ in groups)
    if top not in (2, 3):
        raise MeshError(f"{path}: the highest physical group dimension is {top}; comove_dolfinx reads "
                        "2D meshes with a physical surface for the body (and curves for boundaries), "
                        "or 3D ones with a physical volume (and surfaces)")
    names: dict[int, dict[str, int]] = {top - 1: {}, top: {}}
    for dim, tag in groups:
        if dim in names:
            names[dim][gmsh.model.getPhysicalName(dim, tag) or str(tag)] = tag
    # model_to_mesh asserts one element type per entity on rank 0 only: check here to avoid a deadlock
    for dim in (top - 1, top):
        entities = [e for d, tag in groups if d == dim for e in gmsh.model.getEntitiesForPhysicalGroup(d, tag)]
        types = {t for e in entities for t in gmsh.model.mesh.getElementTypes(dim, e)}
        if len(types) > 1:
            raise MeshError(f"{path} mixes element types {sorted(types)} in its {dim}D physical groups; "
                            "dolfinx needs one cell type (all triangles or all quadrilaterals; in 3D all "
                            "tetrahedra or all hexahedra)")
    z = gmsh.model.mesh.getNodes()[1][2::3]
    if top == 2 and z.size and np.abs(z).max() > 0:
        raise MeshError(f"{path} is not in the plane z = 0 (max |z| = {np.abs(z).max():g}); "
                        "comove_dolfinx reads 2D (x, y) meshes")
    missing = [name for name in required if name not in names[top - 1]]
    if missing:
        raise MeshError(f"{path}: facet group(s) {missing} not found; present: {sorted(names[top - 1])}. "
                        "Add them as named physical curves (surfaces in 3D) or fix the names asked for")
    return names[top - 1], names[top], top


def _arrays_with_gmsh(path: pathlib.Path, required: Iterable[str]) -> tuple[dict | None, str | None]:
    """(the arrays of the .msh file, None) read with gmsh on this rank, or (None, the error)."""
    _start_gmsh()
    try:
        gmsh.model.add("comove_load")
        gmsh.merge(str(path))
        facet_names, cell_names, dim = _groups_of_current_model(path, required)
        return mesh_arrays.from_model(gmsh, dim, facet_names, cell_names), None
    except MeshError as err:
        return None, str(err)
    except Exception as err:  # gmsh raises plain Exception
        return None, f"gmsh cannot read {path}: {err}"
    finally:
        _stop_gmsh()


def _distribute(path: pathlib.Path, arrays: dict | None, error: str | None, comm: MPI.Comm) -> MeshData:
    """The mesh of the arrays that rank 0 holds (mesh_arrays.py), distributed over ``comm`` as
    dolfinx's gmsh reader distributes it; MeshError on every rank if rank 0 has ``error``."""
    head = None
    if comm.rank == 0 and error is None:
        head = {k: (arrays[k].shape[1] if arrays[k].ndim == 2 else int(arrays[k])) for k in
                ("dim", "cells", "cells_type", "facets", "facets_type") if k in arrays}
        head["names"] = mesh_arrays.names(arrays)
    error, head = comm.bcast((error, head), root=0)
    if error is not None:
        raise MeshError(error)
    if comm.rank != 0:
        arrays = {"x": np.empty((0, 3)), "cells": np.empty((0, head["cells"]), dtype=np.int64),
                  "cells_values": np.empty(0, dtype=np.int32)}
        if "facets" in head:
            arrays.update(facets=np.empty((0, head["facets"]), dtype=np.int64),
                          facets_values=np.empty(0, dtype=np.int32))
    mesh, cell_tags, facet_tags = compat.mesh_from_gmsh_arrays(
        comm, head["cells_type"], arrays["x"], arrays["cells"], arrays["cells_values"],
        arrays.get("facets"), arrays.get("facets_values"), gdim=head["dim"])
    fix_coordinate_element(mesh)
    mesh.name = "mesh"
    cell_tags.name, facet_tags.name = "cell_tags", "facet_tags"
    facet_names, cell_names = head["names"]
    return MeshData(mesh, cell_tags, facet_tags, facet_names, path, cell_names)


def load_msh(path: str | os.PathLike, comm: MPI.Comm = MPI.COMM_WORLD,
             required: Iterable[str] = ()) -> MeshData:
    """Read a 2D (or 3D, with a physical volume) gmsh .msh file on rank 0 and distribute it over
    `comm`.

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
    error, facet_names, cell_names, dim = None, {}, {}, 2
    if comm.rank == 0:
        if not path.is_file():
            error = f"mesh file {path} not found (absolute: {path.resolve()}); check the path"
        else:
            _start_gmsh()
            try:
                gmsh.model.add("comove_load")
                gmsh.merge(str(path))
                facet_names, cell_names, dim = _groups_of_current_model(path, required)
            except MeshError as err:
                error = str(err)
            except Exception as err:
                error = f"gmsh cannot read {path}: {err}"
            if error is not None:
                _stop_gmsh()
    error, facet_names, cell_names, dim = comm.bcast((error, facet_names, cell_names, dim), root=0)
    if error is not None:
        raise MeshError(error)
    # dolfinx 0.5.2's gmshio.read_from_msh is broken (NameError: 'msh' on the reading rank,
    # 'partitioner' elsewhere), so do what it should: merge on rank 0, then model_to_mesh everywhere.
    try:
        mesh, cell_tags, facet_tags = compat.model_to_mesh(gmsh.model, comm, 0, gdim=dim)
    finally:
        if comm.rank == 0:
            _stop_gmsh()
    fix_coordinate_element(mesh)
    mesh.name = "mesh"
    cell_tags.name, facet_tags.name = "cell_tags", "facet_tags"
    return MeshData(mesh, cell_tags, facet_tags, facet_names, path, cell_names)


def from_dolfinx(mesh: dolfinx.mesh.Mesh, facet_tags: dolfinx.mesh.MeshTags, names: dict[str, int],
                 cell_tags: dolfinx.mesh.MeshTags | None = None) -> MeshData:
    """A mesh made with dolfinx, with its facet tags and a name for each tag value used (2D, or 3D
    for the model "solid")."""
    if mesh.geometry.dim != mesh.topology.dim or mesh.topology.dim not in (2, 3):
        raise MeshError("the mesh must be 2D (gdim = tdim = 2) or 3D (gdim = tdim = 3)")
    present = set(np.unique(facet_tags.values).tolist())
    present = set().union(*mesh.comm.allgather(present))
    missing = {k: v for k, v in names.items() if v not in present}
    if missing:
        raise MeshError(f"no facet carries the tag value of {missing}: tag those facets or drop the names")
    return MeshData(mesh, cell_tags, facet_tags, dict(names), pathlib.Path("<dolfinx mesh>"))

"""The arrays of a cached gmsh mesh in a NumPy file beside it, so that later runs read the mesh
without gmsh.

``<builder>_<hash>.npz`` holds what dolfinx's gmsh reader takes from the model of
``<builder>_<hash>.msh``: the nodes in the order of their gmsh tags, the cells of the physical
groups of the highest dimension and the facets of those one dimension lower (gmsh's node order,
numbered from 0) with their group tags, in the order of the groups and their entities; and the
groups' names. It records the size and modification time of the ``.msh`` it was made from and the
layout's version: a ``.msh`` written again (a rebuilt cache) or a layout of another version makes
it stale, and it is made again from the ``.msh``. It is written under a temporary name and
renamed into place, so a concurrent reader never sees half a file.
"""
from __future__ import annotations

import json
import os
import pathlib
import zipfile

import numpy as np

LAYOUT = 1
"""Version of the file's layout; a file of another version is made again."""


def from_model(gmsh, top: int, facet_names: dict, cell_names: dict) -> dict:
    """The arrays of the current gmsh model (``top``: its highest physical-group dimension, whose
    groups have one element type each: meshes.py checks it) and the groups' names."""
    tags, coords, _ = gmsh.model.mesh.getNodes()
    order = np.argsort(tags)
    arrays = {"x": coords.reshape(-1, 3)[order], "dim": np.int64(top),
              "names": np.array(json.dumps({"facets": facet_names, "cells": cell_names})),
              "layout": np.int64(LAYOUT)}
    for key, dim in (("cells", top), ("facets", top - 1)):
        blocks, values, types = [], [], set()
        for group_dim, tag in gmsh.model.getPhysicalGroups():
            if group_dim != dim:
                continue
            for entity in gmsh.model.getEntitiesForPhysicalGroup(dim, tag):
                for etype, etags, enodes in zip(*gmsh.model.mesh.getElements(dim, entity)):
                    n = gmsh.model.mesh.getElementProperties(etype)[3]
                    blocks.append(np.asarray(enodes, dtype=np.int64).reshape(-1, n) - 1)
                    values.append(np.full(len(etags), tag, dtype=np.int32))
                    types.add(int(etype))
        if blocks:
            arrays[key], arrays[f"{key}_values"] = np.concatenate(blocks), np.concatenate(values)
            arrays[f"{key}_type"] = np.int64(types.pop())
    return arrays


def path_of(msh: pathlib.Path) -> pathlib.Path:
    """The arrays' file of the cached mesh ``msh``."""
    return msh.with_suffix(".npz")


def _stamp(msh: pathlib.Path) -> np.ndarray:
    st = msh.stat()
    return np.array([st.st_size, st.st_mtime_ns], dtype=np.int64)


def write(msh: pathlib.Path, arrays: dict) -> None:
    """Write the arrays of ``msh`` beside it (temporary name, renamed into place). A cache folder
    that cannot take the file costs only the next run's reading with gmsh again."""
    target = path_of(msh)
    tmp = target.with_name(f".{target.stem}.{os.getpid()}.tmp.npz")
    try:
        np.savez(tmp, stamp=_stamp(msh), **arrays)
        os.replace(tmp, target)
    except OSError:
        pass
    finally:
        if tmp.exists():
            tmp.unlink()


def read(msh: pathlib.Path) -> dict | None:
    """The arrays of ``msh``, or None if its file is missing, unreadable, stale or of another
    layout (the caller reads the ``.msh`` with gmsh then)."""
    try:
        with np.load(path_of(msh), allow_pickle=False) as f:
            arrays = {k: f[k] for k in f.files}
        fresh = np.array_equal(arrays.pop("stamp"), _stamp(msh)) and int(arrays["layout"]) == LAYOUT
    except (OSError, KeyError, ValueError, zipfile.BadZipFile):
        return None
    return arrays if fresh else None


def names(arrays: dict) -> tuple[dict, dict]:
    """(facet group name -> tag, cell group name -> tag) of the arrays."""
    both = json.loads(str(arrays["names"]))
    return both["facets"], both["cells"]

"""The builders' cache read without gmsh: the arrays kept beside each cached .msh give the mesh that
dolfinx's own gmsh reader gives (points, cells, tags, names; the same partition on two ranks), a
changed parameter or a rewritten .msh makes them again, and the command's run of a scene whose mesh
is in the cache never imports gmsh."""
import shutil
import textwrap

import launch
import numpy as np
import pytest
from mpi4py import MPI

from comove_dolfinx import compat, geometry
from comove_dolfinx.geometry import mesh_arrays


def _arrays(md):
    """This rank's mesh as arrays: node coordinates with their input numbering, cells (as input
    node numbers), cell and facet tags (as the input nodes of their entities, with the values)."""
    mesh = md.mesh
    tdim = mesh.topology.dim
    inputs = np.asarray(mesh.geometry.input_global_indices)
    out = {"x": mesh.geometry.x, "inputs": inputs, "cells": inputs[compat.geometry_dofs(mesh)]}
    for name, tags in (("cell", md.cell_tags), ("facet", md.facet_tags)):
        dim = tags.dim
        mesh.topology.create_connectivity(dim, 0)
        c2v = mesh.topology.connectivity(dim, 0)
        verts = [np.sort(c2v.links(e)) for e in tags.indices]
        out[name] = (np.array(verts), tags.values)
        assert dim == (tdim if name == "cell" else tdim - 1)
    return out


def _same(a, b):
    np.testing.assert_array_equal(a["x"], b["x"])
    np.testing.assert_array_equal(a["inputs"], b["inputs"])
    np.testing.assert_array_equal(a["cells"], b["cells"])
    for name in ("cell", "facet"):
        np.testing.assert_array_equal(a[name][0], b[name][0])
        np.testing.assert_array_equal(a[name][1], b[name][1])


@pytest.mark.mpi
@pytest.mark.parametrize("build", [
    lambda d: geometry.annulus_sector(1.6, 2.0, 0.2, order=2, cache_dir=d),
    lambda d: geometry.rectangle(2.0, 1.0, 0.5, order=1, cache_dir=d),
    lambda d: geometry.box(1.0, 0.5, 0.5, 0.5, order=2, cache_dir=d)])
def test_the_cached_arrays_give_the_mesh_of_dolfinx_gmsh_reader(mpi_tmp, build):
    """Built (arrays made from the .msh with gmsh) and read again (from the arrays alone): on every
    rank the same nodes, cells and tags as dolfinx's gmsh reader makes of the .msh (load_msh), so
    also the same partition on two ranks."""
    first = build(mpi_tmp)
    assert mesh_arrays.path_of(first.path).exists()
    again = build(mpi_tmp)
    reference = geometry.load_msh(first.path)
    for md in (first, again):
        _same(_arrays(md), _arrays(reference))
        assert md.tags == reference.tags and md.cell_names == reference.cell_names
        assert md.tags and md.mesh.geometry.dim == reference.mesh.geometry.dim


@pytest.mark.mpi
def test_a_changed_parameter_builds_a_new_mesh(mpi_tmp):
    """Another mesh size is another cache entry (its .msh and arrays), with the cells that size
    gives: 2 x 1 at size 0.5 has 4 x 2 squares of two triangles, at size 0.25 four times as many."""
    coarse = geometry.rectangle(2.0, 1.0, 0.5, order=1, cache_dir=mpi_tmp)
    fine = geometry.rectangle(2.0, 1.0, 0.25, order=1, cache_dir=mpi_tmp)
    assert fine.path != coarse.path and mesh_arrays.path_of(fine.path).exists()
    count = [MPI.COMM_WORLD.allreduce(m.mesh.topology.index_map(2).size_local) for m in (coarse, fine)]
    assert count == [16, 64]


def test_a_rewritten_msh_makes_its_arrays_again(tmp_path):
    """Arrays older than their .msh (the .msh written again) are made again from it: the mesh read
    is the new file's."""
    comm = MPI.COMM_SELF
    md = geometry.rectangle(2.0, 1.0, 0.5, order=1, comm=comm, cache_dir=tmp_path / "a")
    other = geometry.rectangle(2.0, 1.0, 0.25, order=1, comm=comm, cache_dir=tmp_path / "b")
    shutil.copyfile(other.path, md.path)                  # same name, another mesh
    again = geometry.rectangle(2.0, 1.0, 0.5, order=1, comm=comm, cache_dir=tmp_path / "a")
    assert again.mesh.topology.index_map(2).size_local == 64
    assert mesh_arrays.read(md.path) is not None          # made again, and fresh


RUN = """
import sys
from comove_dolfinx import cli
code = cli.main(sys.argv[1:])
print("EXIT", code, "GMSH", "gmsh" in sys.modules)
"""


def test_a_run_of_a_cached_mesh_does_not_import_gmsh(tmp_path):
    """The command's first run of a scene builds its mesh (gmsh imported); the second finds it in
    the cache and never imports gmsh."""
    script = tmp_path / "run.py"
    script.write_text(textwrap.dedent(RUN))
    args = [script, "run", "elastica", "--no-progress", "--overwrite", "--out", tmp_path / "out",
            "--set", "n_increments=2", "--set", "size=0.5"]
    seen = []
    for _ in range(2):
        p = launch.run(args, cwd=tmp_path)
        line = [x for x in p.stdout.splitlines() if x.startswith("EXIT")]
        assert line, p.stdout + p.stderr
        seen.append(line[0])
    assert seen == ["EXIT 0 GMSH True", "EXIT 0 GMSH False"]

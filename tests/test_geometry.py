"""Gmsh builders: areas and boundary lengths against closed forms, curved edges, the cache, errors.

Tests marked mpi also run under ``mpirun -n 2``; they build into one folder shared by the ranks.
"""
import math
import os
import subprocess
import sys
import textwrap

import gmsh
import numpy as np
import pytest
import ufl
from dolfinx import fem
from mpi4py import MPI

from comove_dolfinx import compat, geometry

R_IN, R_OUT = 4.849, 5.715  # the ring scene


def integral(md, name=None):
    """Area of the mesh (name None) or length of the facet group `name`, summed over ranks."""
    one = fem.Constant(md.mesh, 1.0)
    if name is None:
        expr = one * ufl.dx(domain=md.mesh)
    else:
        ds = ufl.Measure("ds", domain=md.mesh, subdomain_data=md.facet_tags)
        expr = one * ds(md.ds_id(name))
    return md.mesh.comm.allreduce(fem.assemble_scalar(fem.form(expr)), op=MPI.SUM)


def build(kind, cache, order=2):
    """One small mesh of each builder and its exact area and group lengths."""
    if kind == "rectangle":
        md = geometry.rectangle(3.0, 0.5, 0.25, order=order, x0=-1.0, y0=2.0, cache_dir=cache)
        return md, 1.5, dict(left=0.5, right=0.5, bottom=3.0, top=3.0)
    if kind == "plate":
        md = geometry.plate_section(10.0, 2.0, 0.25, 0.5, order=order, cache_dir=cache)
        return md, 20.0, dict(axis=2.0, bottom=10.0, top=10.0, rim_support=0.25, rim=1.75)
    if kind == "annulus":
        md = geometry.annulus_sector(R_IN, R_OUT, 0.3, order=order, cache_dir=cache)
        return md, math.pi / 4 * (R_OUT**2 - R_IN**2), dict(
            inner=math.pi / 2 * R_IN, outer=math.pi / 2 * R_OUT, xsym=R_OUT - R_IN, ysym=R_OUT - R_IN)
    if kind == "half_disc":
        md = geometry.quarter_disc(2.0, 0.4, 0.05, 0.3, order=order, cache_dir=cache, half=True)
        return md, 2 * math.pi, dict(top=4.0, contact=2 * math.pi)
    md = geometry.quarter_disc(2.0, 0.4, 0.05, 0.3, order=order, cache_dir=cache)
    return md, math.pi, dict(top=2.0, xsym=2.0, contact=math.pi)


@pytest.mark.mpi
@pytest.mark.parametrize("kind", ["rectangle", "plate", "annulus", "disc", "half_disc"])
def test_area_and_boundary_lengths(kind, mpi_tmp):
    md, area, lengths = build(kind, mpi_tmp)
    assert md.mesh.geometry.dim == 2 and compat.geometry_degree(md.mesh) == 2
    assert set(md.tags) == set(lengths) and len(set(md.tags.values())) == len(lengths)
    assert md.cell_names == {"body": geometry.BODY_TAG}
    assert integral(md) == pytest.approx(area, rel=1e-12 if kind in ("rectangle", "plate") else 1e-5)
    for name, exact in lengths.items():
        curved = name in ("inner", "outer", "contact")
        assert integral(md, name) == pytest.approx(exact, rel=1e-6 if curved else 1e-12), name


@pytest.mark.mpi
def test_curved_edges_order_2_beat_order_1(mpi_tmp):
    exact = math.pi / 4 * (R_OUT**2 - R_IN**2)
    err = {order: abs(integral(build("annulus", mpi_tmp, order)[0]) - exact) / exact for order in (1, 2)}
    assert err[2] < 1e-5 and err[1] > 1e-4 > 100 * err[2]


@pytest.mark.mpi
def test_order_2_nodes_lie_on_the_arcs(mpi_tmp):
    md = build("annulus", mpi_tmp)[0]
    for name, radius in (("inner", R_IN), ("outer", R_OUT)):
        facets = md.facet_tags.find(md.ds_id(name))
        f_to_c = md.mesh.topology.connectivity(1, 2)
        cells = np.unique([c for f in facets for c in f_to_c.links(f)]).astype(np.int32)
        nodes = np.unique(compat.geometry_dofs(md.mesh)[cells])
        r = np.linalg.norm(md.mesh.geometry.x[nodes, :2], axis=1)
        near = np.abs(r - radius) < 0.05  # the next row of nodes is a third of the wall away
        assert np.allclose(r[near], radius, rtol=0, atol=1e-12), name
        assert near.sum() >= 2 * len(facets) + min(len(facets), 1)  # vertices and mid-side nodes


def test_thin_beam_gets_two_layers(tmp_path):
    md = geometry.rectangle(10.0, 0.25, 0.5, order=1, comm=MPI.COMM_SELF, cache_dir=tmp_path)
    assert md.mesh.topology.index_map(2).size_local == 20 * 2 * 2  # nx = 20, ny = max(1, 2)


@pytest.mark.mpi
def test_cache_is_reused(mpi_tmp):
    first = geometry.rectangle(2.0, 1.0, 0.5, cache_dir=mpi_tmp / "nested" / "cache")
    stamp = first.path.stat().st_mtime_ns
    second = geometry.rectangle(2, 1, 0.5, cache_dir=mpi_tmp / "nested" / "cache")
    assert second.path == first.path and second.path.stat().st_mtime_ns == stamp
    assert first.path.name.startswith("rectangle_")
    other = geometry.rectangle(2.0, 1.0, 0.5, order=1, cache_dir=mpi_tmp / "nested" / "cache")
    assert other.path != first.path  # the order is part of the key
    names = [first.path.name, other.path.name]       # each .msh with its arrays (.npz) beside it
    names += [n.replace(".msh", ".npz") for n in names]
    assert sorted(p.name for p in first.path.parent.iterdir()) == sorted(names)


@pytest.mark.mpi
def test_load_msh_errors_name_the_problem(mpi_tmp):
    missing = mpi_tmp / "nowhere.msh"
    with pytest.raises(geometry.MeshError, match="nowhere.msh"):
        geometry.load_msh(missing)
    md = geometry.rectangle(1.0, 1.0, 0.5, cache_dir=mpi_tmp)
    with pytest.raises(geometry.MeshError, match="contact_face") as info:
        geometry.load_msh(md.path, required=("top", "contact_face"))
    assert "bottom" in str(info.value)  # the groups present are listed
    with pytest.raises(geometry.MeshError, match="'lid'"):
        md.ds_id("lid")
    assert geometry.load_msh(md.path, required=["top"]).tags == md.tags


@pytest.mark.mpi
def test_load_msh_without_physical_groups(mpi_tmp):
    path = mpi_tmp / "plain.msh"
    if MPI.COMM_WORLD.rank == 0:
        gmsh.initialize(readConfigFiles=False)
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.occ.addRectangle(0, 0, 0, 1, 1)
        gmsh.model.occ.synchronize()
        gmsh.model.mesh.generate(2)
        gmsh.write(str(path))
        gmsh.finalize()
    MPI.COMM_WORLD.barrier()
    with pytest.raises(geometry.MeshError, match="no physical groups"):
        geometry.load_msh(path)


@pytest.mark.parametrize("call, word", [
    (lambda: geometry.rectangle(0.0, 1.0, 0.1), "L"),
    (lambda: geometry.rectangle(1.0, 1.0, -0.1), "size"),
    (lambda: geometry.rectangle(1.0, 1.0, 0.1, order=3), "order"),
    (lambda: geometry.annulus_sector(2.0, 1.0, 0.1), "r_in"),
    (lambda: geometry.plate_section(10.0, 2.0, 2.0, 0.25), "z_support"),
    (lambda: geometry.plate_section(10.0, 2.0, 0.0, 0.25), "z_support"),
    (lambda: geometry.quarter_disc(1.0, 0.1, 0.2, 0.3), "size_contact"),
    (lambda: geometry.quarter_disc(1.0, 0.1, 0.01, float("nan")), "contact_zone"),
    (lambda: geometry.quarter_disc(1.0, 0.1, 0.01, 0.3, half=1), "half"),
])
def test_invalid_input(call, word):
    with pytest.raises(ValueError, match=word):
        call()


JIT_SCRIPT = textwrap.dedent("""
    import logging, sys
    logging.disable(logging.INFO)
    from mpi4py import MPI            # ahead of dolfinx (the PyPI wheel needs MPI loaded first)
    import ufl
    from dolfinx import fem
    from comove_dolfinx import compat, geometry
    md = geometry.rectangle(1.0, 1.0, 0.5, comm=MPI.COMM_SELF, cache_dir=sys.argv[1])
    V = compat.function_space(md.mesh, "Lagrange", 2, (2,))
    u, v = ufl.TrialFunction(V), ufl.TestFunction(V)
    fem.form(ufl.inner(u, v) * ufl.dx)   # the first compilation used to change the mesh's element
    fem.form(ufl.div(v) * ufl.ds)        # and with it the cache key of this one
""")


def test_form_cache_is_warm_in_a_second_process(tmp_path):
    env = dict(os.environ, XDG_CACHE_HOME=str(tmp_path / "xdg"))
    env.pop("OMPI_COMM_WORLD_SIZE", None)
    counts = []
    for _ in range(2):
        subprocess.run([sys.executable, "-c", JIT_SCRIPT, str(tmp_path / "meshes")], env=env, check=True,
                       capture_output=True, timeout=120)
        counts.append(len(list((tmp_path / "xdg" / "fenics").iterdir())))
    assert counts[0] > 0 and counts[1] == counts[0]

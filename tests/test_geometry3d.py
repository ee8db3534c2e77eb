"""The 3D Gmsh builders: named faces where they belong, volumes against the closed forms, the
cache, the input refusals, 3D .msh files of one's own, and elastic runs against closed forms
(a sphere under uniform pressure is in uniform hydrostatic stress; Lame's thick tube)."""
import math

import numpy as np
import pytest
from mpi4py import MPI

from comove_dolfinx import compat, geometry
from comove_dolfinx.geometry import MeshError
from comove_dolfinx.loads import Fixed, Pressure
from comove_dolfinx.mechanics.body import Body
from comove_dolfinx.mechanics.material_data import Elastic
from comove_dolfinx.mechanics.model import Model
from comove_dolfinx.solver import IncrementalSolver, NewtonSettings, StepSettings


@pytest.fixture(scope="module")
def cache(tmp_path_factory):
    return str(tmp_path_factory.mktemp("meshes3d"))


def _volume(md):
    import ufl
    from dolfinx import fem
    local = fem.assemble_scalar(compat.form(1.0 * ufl.dx(domain=md.mesh)))
    return md.mesh.comm.allreduce(local, op=MPI.SUM)


def _face_nodes(md, name):
    """Coordinates of the geometry nodes (vertices and, at order 2, mid-edge nodes) on a named face."""
    from dolfinx import fem
    V = compat.function_space(md.mesh, "Lagrange", compat.geometry_degree(md.mesh))
    facets = md.facet_tags.indices[md.facet_tags.values == md.ds_id(name)]
    dofs = fem.locate_dofs_topological(V, 2, facets)
    return V.tabulate_dof_coordinates()[dofs]


def _tube_volume(r_in, r_out, length, angle):
    return 0.5 * angle * (r_out ** 2 - r_in ** 2) * length


# -- named faces ------------------------------------------------------------------------------------
@pytest.mark.parametrize("angle", [math.pi / 2, 2.0, math.pi])
def test_tube_sector_faces(cache, angle):
    """Every node of a named face lies on its plane or cylinder (order 2: the mid-edge nodes too)."""
    r_in, r_out, L = 1.0, 1.5, 2.0
    md = geometry.tube_sector(r_in, r_out, L, 0.3, angle=angle, cache_dir=cache)
    assert md.mesh.topology.dim == 3 and compat.cell_name(md.mesh) == "tetrahedron"
    theta0 = math.pi / 2 - angle
    other = {math.pi / 2: "ysym", math.pi: "xsym"}.get(angle, "side")
    assert set(md.tags) == {"inner", "outer", "xsym", "zsym", "end", other}
    r = {name: np.hypot(*_face_nodes(md, name)[:, :2].T) for name in ("inner", "outer")}
    assert np.allclose(r["inner"], r_in, atol=1e-9) and np.allclose(r["outer"], r_out, atol=1e-9)
    assert np.allclose(_face_nodes(md, "zsym")[:, 2], 0.0) and np.allclose(_face_nodes(md, "end")[:, 2], L)
    x = _face_nodes(md, "xsym")
    if angle == math.pi:        # both radial faces, on x = 0 above and below the axis
        assert np.allclose(x[:, 0], 0.0, atol=1e-9) and x[:, 1].min() < -r_in + 1e-9 < r_in < x[:, 1].max() + 1e-9
    else:
        assert np.allclose(x[:, 0], 0.0, atol=1e-9) and x[:, 1].min() > r_in - 1e-9
        s = _face_nodes(md, other)
        assert np.allclose(-math.sin(theta0) * s[:, 0] + math.cos(theta0) * s[:, 1], 0.0, atol=1e-9)
    nodes = md.mesh.geometry.x
    assert np.hypot(nodes[:, 0], nodes[:, 1]).min() > r_in - 1e-9
    assert (np.arctan2(nodes[:, 1], nodes[:, 0]) >= theta0 - 1e-9).all()


def test_plate_quarter_faces(cache):
    """The quarter plate's faces on their planes and cylinder, the rim split at z_support; with
    size_rim and size_contact the cells there are that small, those away are not."""
    from dolfinx import mesh as dmesh
    R, t, zs = 3.0, 1.0, 0.25
    md = geometry.plate_quarter(R, t, zs, 0.4, size_rim=0.1, size_contact=0.1, contact_radius=1.0,
                                cache_dir=cache)
    assert md.tags == {"top": 1, "bottom": 2, "rim_support": 3, "rim": 4, "xsym": 5, "ysym": 6}
    for name, axis, value in (("top", 2, t), ("bottom", 2, 0.0), ("xsym", 0, 0.0), ("ysym", 1, 0.0)):
        assert np.allclose(_face_nodes(md, name)[:, axis], value, atol=1e-9), name
    low, up = _face_nodes(md, "rim_support"), _face_nodes(md, "rim")
    assert np.allclose(np.hypot(low[:, 0], low[:, 1]), R, atol=1e-9) and np.allclose(np.hypot(up[:, 0], up[:, 1]), R)
    assert low[:, 2].max() < zs + 1e-9 and up[:, 2].min() > zs - 1e-9
    assert _volume(md) == pytest.approx(math.pi * R * R * t / 4, rel=1e-6)
    cells = np.arange(md.mesh.topology.index_map(3).size_local, dtype=np.int32)
    h, x = compat.cell_sizes(md.mesh, cells), dmesh.compute_midpoints(md.mesh, 3, cells)
    r = np.hypot(x[:, 0], x[:, 1])
    assert np.median(h[(r < 0.9) & (x[:, 2] < 0.1)]) < 2 * 0.1 and np.median(h[(R - r < 0.1) & (x[:, 2] < zs)]) < 2 * 0.1
    assert np.median(h[(r > 1.5) & (r < 2.0) & (x[:, 2] > 0.6)]) > 0.3


def test_sphere_octant_faces(cache):
    R = 2.0
    md = geometry.sphere_octant(R, 0.5, cache_dir=cache)
    assert md.tags == {"xsym": 1, "ysym": 2, "zsym": 3, "outer": 4}
    for axis, name in enumerate(("xsym", "ysym", "zsym")):
        x = _face_nodes(md, name)
        assert len(x) and np.allclose(x[:, axis], 0.0, atol=1e-9), name
    assert np.allclose(np.linalg.norm(_face_nodes(md, "outer"), axis=1), R, atol=1e-9)
    assert md.mesh.geometry.x.min() > -1e-9


def test_refinement_near_the_contact_point(cache):
    """With size_contact the cells near the touching point are that small, those away are not (cell
    sizes as circumdiameters: sqrt(3/2) = 1.22 times the edge of a regular tetrahedron)."""
    from dolfinx import mesh as dmesh
    md = geometry.sphere_octant(1.0, 0.3, size_contact=0.04, contact_zone=0.1, cache_dir=cache)
    cells = np.arange(md.mesh.topology.index_map(3).size_local, dtype=np.int32)
    h = compat.cell_sizes(md.mesh, cells)
    d = np.linalg.norm(dmesh.compute_midpoints(md.mesh, 3, cells) - [0.0, 0.0, 1.0], axis=1)
    assert np.median(h[d < 0.1]) < 2 * 0.04 and np.median(h[d > 0.8]) > 0.25
    tube = geometry.tube_sector(1.0, 1.5, 2.0, 0.3, angle=math.pi, size_contact=0.05, contact_zone=0.15,
                                cache_dir=cache)
    cells = np.arange(tube.mesh.topology.index_map(3).size_local, dtype=np.int32)
    h = compat.cell_sizes(tube.mesh, cells)
    d = np.linalg.norm(dmesh.compute_midpoints(tube.mesh, 3, cells) - [0.0, 1.5, 0.0], axis=1)
    assert np.median(h[d < 0.15]) < 2 * 0.05 and np.median(h[d > 1.0]) > 0.25


# -- volumes ------------------------------------------------------------------------------------------
def test_volumes_against_closed_forms(cache):
    """Curved (order 2) cells give the volume to a small error; straight ones (order 1) cut the
    curved faces' chords and underestimate it, less so on finer meshes."""
    tube = _tube_volume(1.0, 1.5, 1.0, math.pi / 2)
    sphere = math.pi / 6.0
    errors = {}
    for order in (1, 2):
        for size in (0.4, 0.2):
            errors[("tube", order, size)] = _volume(geometry.tube_sector(
                1.0, 1.5, 1.0, size, order=order, cache_dir=cache)) / tube - 1.0
            errors[("sphere", order, size)] = _volume(geometry.sphere_octant(
                1.0, size, order=order, cache_dir=cache)) / sphere - 1.0
    print({k: f"{v:.2e}" for k, v in errors.items()})
    for body in ("tube", "sphere"):
        coarse, fine = errors[(body, 1, 0.4)], errors[(body, 1, 0.2)]
        assert coarse < fine < 0 and fine / coarse < 0.35, (body, coarse, fine)    # O(h^2): 1/4
        assert abs(errors[(body, 2, 0.2)]) < 1e-4 and abs(errors[(body, 2, 0.2)]) < 0.05 * abs(fine), body


# -- cache --------------------------------------------------------------------------------------------
def test_cache_reuses_the_file(cache):
    first = geometry.sphere_octant(1.0, 0.45, cache_dir=cache)
    stamp = first.path.stat().st_mtime_ns
    again = geometry.sphere_octant(1.0, 0.45, cache_dir=cache)
    assert again.path == first.path and again.path.stat().st_mtime_ns == stamp
    assert np.array_equal(again.mesh.geometry.x, first.mesh.geometry.x)
    assert geometry.sphere_octant(1.0, 0.45, order=1, cache_dir=cache).path != first.path
    tube = geometry.tube_sector(1.0, 1.5, 1.0, 0.45, cache_dir=cache)
    assert geometry.tube_sector(1.0, 1.5, 1.0, 0.45, angle=math.pi, cache_dir=cache).path != tube.path


# -- refusals -----------------------------------------------------------------------------------------
@pytest.mark.parametrize("call, message", [
    (lambda c: geometry.tube_sector(1.5, 1.0, 1.0, 0.2, cache_dir=c),
     r"^r_in must be smaller than r_out, got r_in=1\.5, r_out=1\.0$"),
    (lambda c: geometry.tube_sector(1.0, 1.5, 1.0, -0.2, cache_dir=c),
     r"^size must be a finite number > 0, got -0\.2$"),
    (lambda c: geometry.tube_sector(1.0, 1.5, 0.0, 0.2, cache_dir=c),
     r"^length must be a finite number > 0, got 0\.0$"),
    (lambda c: geometry.tube_sector(1.0, 1.5, 1.0, 0.2, angle=4.0, cache_dir=c),
     r"^angle must lie in \(0, pi\] \(radians; pi/2 is a quarter\), got 4\.0$"),
    (lambda c: geometry.tube_sector(1.0, 1.5, 1.0, 0.2, order=3, cache_dir=c), r"^order must be 1 or 2, got 3$"),
    (lambda c: geometry.tube_sector(1.0, 1.5, 1.0, 0.2, size_contact=0.3, contact_zone=0.1, cache_dir=c),
     r"^size_contact must not exceed size = 0\.2, got 0\.3$"),
    (lambda c: geometry.tube_sector(1.0, 1.5, 1.0, 0.2, size_contact=0.1, cache_dir=c),
     r"^contact_zone must be a finite number > 0, got None$"),
    (lambda c: geometry.sphere_octant(0.0, 0.2, cache_dir=c), r"^R must be a finite number > 0, got 0\.0$"),
    (lambda c: geometry.sphere_octant(1.0, "0.2", cache_dir=c), r"^size must be a finite number > 0, got '0\.2'$"),
    (lambda c: geometry.sphere_octant(1.0, 0.001, cache_dir=c),
     r"^sphere_octant: size = 0\.001 would make about .* cells, more than the 5000000 a mesh may have here "
     r"\(the memory runs out\): give size >= 0\.00[0-9]+$"),
    (lambda c: geometry.tube_sector(10.0, 15.0, 100.0, 1.0, size_contact=1e-4, contact_zone=1.0, cache_dir=c),
     r"^tube_sector: size = 1\.0, size_contact = 0\.0001 would make about .* cells, more than the 5000000 .*: "
     r"give size_contact >= [0-9.]+$"),
    (lambda c: geometry.plate_quarter(10.0, 2.0, 2.0, 0.5, cache_dir=c),
     r"^z_support must lie strictly between 0 and t = 2\.0, got 2\.0$"),
    (lambda c: geometry.plate_quarter(10.0, 2.0, 0.25, 0.5, size_rim=0.6, cache_dir=c),
     r"^size_rim must not exceed size = 0\.5, got 0\.6$"),
    (lambda c: geometry.plate_quarter(10.0, 2.0, 0.25, 0.5, size_contact=0.2, cache_dir=c),
     r"^size_contact needs contact_radius, the radius of the refined disc on the bottom face$"),
    (lambda c: geometry.plate_quarter(10.0, 2.0, 0.25, 0.5, size_rim=1e-4, cache_dir=c),
     r"^plate_quarter: size = 0\.5, size_rim = 0\.0001 would make about .* cells, more than the 5000000 .*: "
     r"give size_rim >= [0-9.]+$"),
])
def test_bad_input_is_refused_before_gmsh(tmp_path, call, message):
    with pytest.raises(MeshError, match=message):
        call(str(tmp_path))
    assert not any(tmp_path.iterdir())             # nothing meshed, nothing written


# -- a .msh of one's own ------------------------------------------------------------------------------
def test_load_msh_reads_a_3d_file_with_physical_surfaces(tmp_path):
    """A cylinder made and tagged through gmsh's API (not the builders) reads back with its named faces."""
    from comove_dolfinx.geometry.gmsh_session import gmsh, start, stop
    path = tmp_path / "can.msh"
    if MPI.COMM_WORLD.rank == 0:
        start()
        try:
            occ = gmsh.model.occ
            vol = occ.addCylinder(0, 0, 0, 0, 0, 2.0, 0.5)
            occ.synchronize()
            faces = [tag for _, tag in gmsh.model.getBoundary([(3, vol)], oriented=False)]
            z = {tag: occ.getCenterOfMass(2, tag)[2] for tag in faces}
            named = {"base": [t for t in faces if abs(z[t]) < 1e-9], "lid": [t for t in faces if abs(z[t] - 2) < 1e-9]}
            named["mantle"] = [t for t in faces if t not in named["base"] + named["lid"]]
            gmsh.model.addPhysicalGroup(3, [vol], 7)
            gmsh.model.setPhysicalName(3, 7, "steel")
            for tag, (name, group) in enumerate(named.items(), start=11):
                gmsh.model.addPhysicalGroup(2, group, tag)
                gmsh.model.setPhysicalName(2, tag, name)
            gmsh.option.setNumber("Mesh.MeshSizeMax", 0.3)
            gmsh.model.mesh.generate(3)
            gmsh.model.mesh.setOrder(2)
            gmsh.write(str(path))
        finally:
            stop()
    MPI.COMM_WORLD.barrier()
    md = geometry.load_msh(path, required=("base", "lid", "mantle"))
    assert md.tags == {"base": 11, "lid": 12, "mantle": 13} and md.cell_names == {"steel": 7}
    assert md.mesh.geometry.dim == 3 and compat.geometry_degree(md.mesh) == 2
    assert np.allclose(_face_nodes(md, "lid")[:, 2], 2.0)
    assert np.allclose(np.hypot(*_face_nodes(md, "mantle")[:, :2].T), 0.5)
    assert abs(_volume(md) / (math.pi * 0.25 * 2.0) - 1.0) < 1e-3
    with pytest.raises(MeshError, match=r"facet group\(s\) \['rim'\] not found; present: \['base', 'lid', 'mantle'\]"):
        geometry.load_msh(path, required=("rim",))


# -- elastic runs against closed forms ---------------------------------------------------------------
def _solve(md, items, E=1000.0, nu=0.3):
    m = Model(Body(md, "solid", Elastic(E, nu), update="sr_log"), items)
    m.finalize()
    res = IncrementalSolver(m, StepSettings(n_increments=2), NewtonSettings(rtol=1e-12, atol=1e-12)).run()
    assert res.completed, res.message
    return m


def test_sphere_octant_under_pressure_is_hydrostatic(cache):
    """A follower pressure p on the whole sphere (the octant with its symmetry supports) leaves it in
    the homogeneous stress -p I (any isotropic law; the P2 space holds the uniform contraction):
    exactly on straight cells (polynomial integrands, exact quadrature); on curved cells the
    quadrature of their rational integrands errs, less on finer meshes."""
    p, errors = 5.0, {}
    for order, size in [(1, 0.4), (2, 0.4), (2, 0.25)]:
        md = geometry.sphere_octant(1.0, size, order=order, cache_dir=cache)
        m = _solve(md, [Fixed("xsym", 0), Fixed("ysym", 1), Fixed("zsym", 2), Pressure("outer", p)])
        s = m.cauchy_stress()
        errors[(order, size)] = max(np.abs(s[:, :3] + p).max(), np.abs(s[:, 3:]).max()) / p
    print("sphere: max |sigma + p I| / p:", {k: f"{v:.2e}" for k, v in errors.items()})
    assert errors[(1, 0.4)] < 1e-10
    assert errors[(2, 0.4)] < 1e-3 and errors[(2, 0.25)] < (0.25 / 0.4) ** 2 * errors[(2, 0.4)]


def test_tube_sector_under_internal_pressure_is_lame(cache):
    """Internal pressure p on the quarter tube with u_z = 0 on both ends (plane strain): the radial
    displacement of Lame's solution, u_r = (1 + nu) p a^2 / (E (b^2 - a^2)) ((1 - 2 nu) r + b^2 / r),
    at small load (p / E = 1e-4), at every node."""
    E, nu, p, a, b = 1000.0, 0.3, 0.1, 1.0, 1.5
    md = geometry.tube_sector(a, b, 0.5, 0.15, cache_dir=cache)
    m = _solve(md, [Fixed("xsym", 0), Fixed("ysym", 1), Fixed("zsym", 2), Fixed("end", 2),
                    Pressure("inner", p)], E, nu)
    x = m.V.tabulate_dof_coordinates()
    u = m.u.x.array.reshape(-1, 3)[: len(x)]
    r = np.hypot(x[:, 0], x[:, 1])
    exact = (1 + nu) * p * a * a / (E * (b * b - a * a)) * ((1 - 2 * nu) * r + b * b / r)
    err = np.abs((x[:, 0] * u[:, 0] + x[:, 1] * u[:, 1]) / r - exact).max() / exact.max()
    print(f"tube: max |u_r - Lame| / max u_r = {err:.2e}")
    assert err < 2e-3 and np.abs(u[:, 2]).max() < 2e-3 * exact.max()      # no exact plane strain on tetrahedra


def test_cell_estimates_are_the_builders_counts(cache):
    """The count the size check uses is within 15 % of the tetrahedra gmsh makes (uniform and
    refined meshes), so the limit refuses what would be too large and little else."""
    from comove_dolfinx.checks import mesh_cells
    cases = [("tube_sector", dict(r_in=1.0, r_out=1.5, length=2.0, size=0.1)),
             ("sphere_octant", dict(R=1.0, size=0.08)),
             ("sphere_octant", dict(R=50.0, size=8.0, size_contact=0.8, contact_zone=12.0, growth=0.25)),
             ("plate_quarter", dict(R=10.0, t=2.0, z_support=0.25, size=0.5)),
             ("plate_quarter", dict(R=10.0, t=2.0, z_support=0.25, size=0.5, size_rim=0.125, size_contact=0.25,
                                    contact_radius=4.5))]
    for name, params in cases:
        md = getattr(geometry, name)(**params, cache_dir=cache)
        n = md.mesh.topology.index_map(3).size_global
        assert abs(mesh_cells(name, params) / n - 1.0) < 0.15, (name, params, mesh_cells(name, params), n)

"""Output of physical components on the convected base (kinematics.fibre_stress, io.FibreStress):
the stress along a material fibre follows the fibre through a rigid rotation, and the hoop stress of an
elastic tube under internal pressure is Lame's."""
import numpy as np
import pytest
import ufl
from mpi4py import MPI

import comove_dolfinx as cm
from comove_dolfinx import geometry
from comove_dolfinx.io import FibreStress
from comove_dolfinx.loads import Fixed, Pressure
from comove_dolfinx.mechanics.body import Body
from comove_dolfinx.mechanics.material_data import Elastic
from comove_dolfinx.mechanics.model import Model
from comove_dolfinx.solver import IncrementalSolver, StepSettings


def test_fibre_stress_follows_a_rigid_rotation(tmp_path):
    """A block pre-stressed with sigma0, turned by 90 degrees in three rigid S-R increments: the normal
    stress along the material fibres that started along x and y is still sigma0_xx and sigma0_yy,
    although the Cartesian components have swapped."""
    md = geometry.rectangle(1.0, 1.0, 0.5, order=2, comm=MPI.COMM_SELF, cache_dir=str(tmp_path))
    m = Model(Body(md, "plane_strain", Elastic(1000.0, 0.3), update="sr"))
    m.finalize()
    s0 = np.array([50.0, -20.0, 10.0, 30.0])                 # xx, yy, zz, xy
    m.sigma_n.x.array[:] = np.tile(s0, m.rule.size)
    along_x, along_y = FibreStress(m, "fx", (1.0, 0.0)), FibreStress(m, "fy", (0.0, 1.0))
    for a in np.radians([30.0, 60.0, 90.0]):
        Q = np.array([[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]]) - np.eye(2)
        m.u.interpolate(lambda x: Q @ x[:2])
        m.evaluate_stress()
        m.commit()
    sig = m.cauchy_stress()
    assert sig[:, 1] == pytest.approx(s0[0], abs=1e-10)      # the x-fibre now points along y
    assert along_x.values() == pytest.approx(s0[0], abs=1e-10)
    assert along_y.values() == pytest.approx(s0[1], abs=1e-10)


@pytest.mark.mpi
def test_hoop_stress_of_a_pressurised_tube_is_lame(mpi_tmp):
    """Elastic tube a = 1, b = 2, plane strain, internal pressure p = 1e-4 E (strains ~1e-4, so the
    geometric change is negligible): the cell averages of the hoop stress along the circumferential
    fibre match the cell averages of Lame's sigma_theta = p a^2 (1 + b^2/r^2) / (b^2 - a^2) within
    0.3 % (P2 elements, stress error O(h^2); measured 0.11 %), and the radial fibre carries
    sigma_r = p a^2 (1 - b^2/r^2) / (b^2 - a^2) to 0.1 % of the largest hoop stress (measured 0.03 %)."""
    a, b, E = 1.0, 2.0, 1000.0
    p = 1e-4 * E
    md = geometry.annulus_sector(a, b, 0.2, order=2, comm=MPI.COMM_WORLD, cache_dir=str(mpi_tmp))
    m = Model(Body(md, "plane_strain", Elastic(E, 0.3)),
              [Fixed("xsym", component=0), Fixed("ysym", component=1), Pressure("inner", p)])
    m.finalize()
    assert IncrementalSolver(m, StepSettings(n_increments=1, max_cutbacks=0)).run().completed
    x = m.x
    r = ufl.sqrt(x[0] ** 2 + x[1] ** 2)
    hoop = FibreStress(m, "hoop", (-x[1] / r, x[0] / r)).values()
    radial = FibreStress(m, "radial", (x[0] / r, x[1] / r)).values()
    pts = m.rule.evaluate(m.rule.expression(x))
    rq = np.hypot(pts[:, 0], pts[:, 1])
    k = p * a ** 2 / (b ** 2 - a ** 2)
    hoop_exact = m.rule.cell_average(k * (1 + b ** 2 / rq ** 2))
    radial_exact = m.rule.cell_average(k * (1 - b ** 2 / rq ** 2))
    np.testing.assert_allclose(hoop, hoop_exact, rtol=3e-3)          # measured 1.1e-3
    np.testing.assert_allclose(radial, radial_exact, atol=1e-3 * k * (1 + b ** 2 / a ** 2))  # 2.8e-4


def _pvd(folder):
    """The (time, file) pairs of a results.pvd, read as XML."""
    import xml.etree.ElementTree as ET
    root = ET.parse(folder / "results.pvd").getroot()
    return [(float(d.get("timestep")), folder / d.get("file")) for d in root.iter("DataSet")]


@pytest.mark.mpi
def test_cell_averages_are_true_averages_on_curved_cells(mpi_tmp):
    """On an annulus sector meshed with curved (P2) cells, the cell averages of x times the cells'
    areas add up to the integral of x over the mesh (assembled by dolfinx at a higher degree): the
    average weighs each point with |det J|, not with the reference weights alone (4.6e-4 off)."""
    from dolfinx import fem

    from comove_dolfinx import compat
    from comove_dolfinx.mechanics.quadrature import QuadratureRule
    msh = geometry.annulus_sector(1.0, 2.0, 0.4, order=2, cache_dir=mpi_tmp).mesh
    rule = QuadratureRule(msh, 4)                       # x det J (degree 2 + 2) exactly
    x = ufl.SpatialCoordinate(msh)
    avg = rule.cell_average(rule.evaluate(rule.expression(x))[:, 0])
    dx8 = ufl.dx(domain=msh, metadata={"quadrature_degree": 8})
    V0 = compat.function_space(msh, "DG", 0, ())
    n = rule.num_cells_local
    area = fem.assemble_vector(compat.form(ufl.TestFunction(V0) * dx8)).array[compat.cell_dofs(V0, n)]
    total = msh.comm.allreduce(float(avg[:n] @ area.ravel()), op=MPI.SUM)
    exact = msh.comm.allreduce(fem.assemble_scalar(compat.form(x[0] * dx8)), op=MPI.SUM)
    assert total == pytest.approx(exact, rel=1e-12)


@pytest.mark.parametrize("n", [1, 2])
def test_vtk_keeps_every_p2_node_and_all_fields_in_one_dataset(tmp_path, n):
    """The elastica's results read back with meshio: one .vtu per converged increment, listed in the
    .pvd with increasing times; each a 6-node triangle mesh with every P2 node (vertices + edges of
    the mesh) holding every field (so ParaView warps and colours one dataset); the tip node's
    displacement equal to the history's, on one rank and on two."""
    import meshio

    from test_elastica import _cli, read_history
    out = tmp_path / "run"
    p = _cli(["run", "elastica", "--no-progress", "--out", str(out), "--set", "n_increments=3",
              "--set", "lam=2", "--set", "size=0.25"], n=n)
    assert p.returncode == 0, p.stdout + p.stderr
    hist = read_history(out / "history.csv")
    steps = _pvd(out)
    assert len(steps) == len(hist) and all(a[0] < b[0] for a, b in zip(steps, steps[1:]))
    m = meshio.read(steps[-1][1])
    cells = m.cells_dict["triangle6"]
    vertices = len(np.unique(cells[:, :3]))
    # Euler on a triangulated rectangle: edges = vertices + cells - 1, and a node on every vertex and edge
    assert len(m.points) == 2 * vertices + len(cells) - 1 > 2 * vertices
    assert set(m.point_data) == {"displacement"}
    assert set(m.cell_data) == {"cauchy_stress_cell_avg", "von_mises_cell_avg", "fibre_stress_cell_avg"}
    assert m.cell_data["cauchy_stress_cell_avg"][0].shape == (len(cells), 9)
    tip = np.argmin(np.linalg.norm(m.points[:, :2] - [10.0, 0.125], axis=1))
    u = m.point_data["displacement"][tip]
    assert u[:2] == pytest.approx([hist[-1]["tip_ux"], hist[-1]["tip_uy"]], rel=1e-9) and u[2] == 0.0


def _pressed_block(tmp_path, writer, q=20.0):
    """A 2 x 1 block pressed by a follower pressure q onto a frictionless plane in two increments,
    written by ``writer``; returns q."""
    md = geometry.rectangle(2.0, 1.0, 0.25, order=2, comm=MPI.COMM_SELF, cache_dir=str(tmp_path))
    c = cm.Contact("bottom", cm.Plane((0.0, 0.0), (0.0, 1.0)), method="penalty", gamma0=10.0)
    res = cm.Job(cm.Body(md, "plane_stress", cm.Elastic(1000.0, 0.3)),
                 [cm.Fixed("left", component=0), cm.Pressure("top", q), c], [cm.Step(2)],
                 writers=[writer]).run()
    assert res.completed
    return q


def test_vtk_contact_pressure_is_the_contact_law(tmp_path):
    """The block of the next test, written as VTK: the contact pressure is q at every node of the
    bottom face (to 1e-8), exactly 0 at every other node, never negative."""
    import meshio

    q = _pressed_block(tmp_path, cm.VTK(tmp_path / "out"))
    steps = _pvd(tmp_path / "out")
    assert len(steps) == 2
    m = meshio.read(steps[-1][1])
    X, p = m.points, m.point_data["contact_pressure"].ravel()
    bottom = np.abs(X[:, 1]) < 1e-12
    assert bottom.sum() == 17                               # 8 P2 edges: 9 vertices + 8 mid-nodes
    np.testing.assert_allclose(p[bottom], q, rtol=1e-8)
    assert np.all(p[~bottom] == 0.0) and np.all(p >= 0.0)


_READ_CONTACT = """
import sys, json, h5py, numpy as np
with h5py.File(sys.argv[1], "r") as f:
    X = f["Mesh/mesh/geometry"][...]
    steps = sorted(f["Function/contact_pressure"].keys(), key=lambda t: float(t.replace("_", ".")))
    p = f["Function/contact_pressure"][steps[-1]][...].ravel()
print(json.dumps({"X": X.tolist(), "p": p.tolist(), "steps": len(steps)}))
"""


def test_xdmf_contact_pressure_is_the_contact_law(tmp_path):
    """A block pressed by a follower pressure q onto a frictionless plane carries q at every point of
    its bottom face: read back from the XDMF file in a process of its own, the contact pressure is q
    at every node of the bottom (to 1e-8) and 0 at every other node."""
    import json
    import subprocess
    import sys

    # the XDMF writer adds every contact item's contact_pressure to its fields
    q = _pressed_block(tmp_path, cm.XDMF(tmp_path / "results.xdmf"))
    r = subprocess.run([sys.executable, "-c", _READ_CONTACT, str(tmp_path / "results.h5")],
                       capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    data = json.loads(r.stdout)
    X, p = np.array(data["X"]), np.array(data["p"])
    assert data["steps"] == 2
    bottom = np.abs(X[:, 1]) < 1e-12
    assert bottom.sum() == 17                               # 8 P2 edges: 9 vertices + 8 mid-nodes
    np.testing.assert_allclose(p[bottom], q, rtol=1e-8)
    assert np.abs(p[~bottom]).max() < 1e-12 * q             # zero up to the writer's round-off


def test_vtu_files_read_back_with_meshio(tmp_path):
    """The .vtu writer's files, read by meshio (an independent reader): the points, the quadratic
    triangles and every point and cell array bit for bit, with meshio's shapes ((n,) for a scalar
    cell array, (n, 1) for a one-column point array); two files of one grid keep their own fields."""
    import meshio

    from comove_dolfinx.io import vtu
    rng = np.random.default_rng(1)
    points, cells = rng.random((40, 3)), rng.integers(0, 40, (12, 6))
    grid = vtu.Grid(points, "triangle6", cells)
    for k in range(2):
        point = {"displacement": rng.random((40, 3)), "contact_pressure": rng.random((40, 1))}
        cell = {"cauchy_stress_cell_avg": rng.random((12, 9)), "von_mises_cell_avg": rng.random(12)}
        grid.write(tmp_path / f"r{k}.vtu", point, cell)
        m = meshio.read(tmp_path / f"r{k}.vtu")
        assert np.array_equal(m.points, points) and np.array_equal(m.cells_dict["triangle6"], cells)
        for name, v in point.items():
            assert m.point_data[name].shape == v.shape and np.array_equal(m.point_data[name], v)
        for name, v in cell.items():
            assert m.cell_data[name][0].shape == v.shape and np.array_equal(m.cell_data[name][0], v)


def test_the_collection_is_valid_after_every_dataset_and_never_replaced(tmp_path):
    """io/pvd.py: after each dataset the .pvd parses and lists exactly the datasets given so far,
    in order (a file name with XML's special characters escaped), and after the first write the
    file keeps its inode: the later datasets are written into it, not by replacing it."""
    from comove_dolfinx.io.pvd import Collection
    path = tmp_path / "results.pvd"
    col, entries, inodes = Collection(path), [], set()
    for k, name in enumerate(["a_00000.vtu", "b&<c>_00001.vtu", "a_00002.vtu"]):
        entries.append((0.125 * (k + 1), name))
        col.add(entries)
        assert _pvd(tmp_path) == [(t, tmp_path / f) for t, f in entries]
        inodes.add(path.stat().st_ino)
    assert len(inodes) == 1
    assert not list(tmp_path.glob(".*tmp"))

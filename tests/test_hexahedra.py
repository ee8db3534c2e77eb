"""3D bodies on hexahedra (Q1 and Q2, Gmsh's 8- and 27-node bricks): the builders' meshes, patch
tests against the closed form, tetrahedra and hexahedra converging to each other, a Taylor test of the
3D residual, the VTK output read back, and a restart to the uninterrupted history (also on two
ranks)."""
import math
import shutil

import numpy as np
import pytest
from mpi4py import MPI

import comove_dolfinx as cm
from comove_dolfinx import compat, geometry
from comove_dolfinx.geometry import MeshError
from comove_dolfinx.mechanics.body import Body
from comove_dolfinx.mechanics.model import Model
from comove_dolfinx.solver import IncrementalSolver, NewtonSettings, StepSettings
from comove_dolfinx.taylor import taylor_test
from states import one_correction_into
from test_output3d import _bent_block as _bent_block_of
from test_output3d import _closed_form, _same_history

# a displacement gradient with six distinct strain components and a rotation part
G = np.array([[2.0e-3, 1.2e-3, -0.4e-3], [0.2e-3, -0.6e-3, 0.9e-3], [0.8e-3, -0.3e-3, 1.1e-3]])
E, NU = 1000.0, 0.3
BOX_FACES = ("left", "right", "front", "back", "bottom", "top")
TUBE_FACES = ("inner", "outer", "xsym", "ysym", "zsym", "end")


@pytest.fixture(scope="module")
def cache(tmp_path_factory):
    return str(tmp_path_factory.mktemp("hexmeshes"))


def _volume(md) -> float:
    import ufl
    from dolfinx import fem
    return md.mesh.comm.allreduce(fem.assemble_scalar(fem.form(1.0 * ufl.dx(domain=md.mesh))), op=MPI.SUM)


# -- the builders -------------------------------------------------------------------------------------
@pytest.mark.parametrize("order", [1, 2])
def test_box_of_hexahedra(cache, order):
    """nx x ny x nz bricks (27 geometry nodes each at order 2) filling the box once, each named face
    on its plane; the builder's .msh read again by load_msh (with gmsh) gives the same mesh."""
    from dolfinx import mesh as dmesh
    md = geometry.box(1.0, 0.5, 0.25, 0.25, order=order, cache_dir=cache, hexahedra=True)
    assert compat.cell_name(md.mesh) == "hexahedron"
    assert compat.geometry_dofs(md.mesh).shape[1] == {1: 8, 2: 27}[order]
    n = md.mesh.comm.allreduce(md.mesh.topology.index_map(3).size_local, op=MPI.SUM)
    assert n == 4 * 2 * 1 and _volume(md) == pytest.approx(0.125, rel=1e-12)
    where = {"left": (0, 0.0), "right": (0, 1.0), "front": (1, 0.0), "back": (1, 0.5), "bottom": (2, 0.0),
             "top": (2, 0.25)}
    for name, (axis, value) in where.items():
        f = md.facet_tags.indices[md.facet_tags.values == md.tags[name]]
        assert np.allclose(dmesh.compute_midpoints(md.mesh, 2, f)[:, axis], value), name
    again = geometry.load_msh(md.path, comm=MPI.COMM_SELF)
    assert compat.cell_name(again.mesh) == "hexahedron" and again.tags == md.tags
    assert again.mesh.topology.index_map(3).size_local == 8 and _volume(again) == pytest.approx(0.125)


def test_tube_sector_of_hexahedra(cache):
    """The quarter tube as bricks: the tetrahedral builder's face names, 8 x 2 x 4 cells (around,
    through, along), nodes of the curved faces on the true cylinders; the volume's error is that of
    the chords at order 1 (4.1e-3 relative here) and far smaller at order 2 (the 27-node bricks)."""
    from dolfinx import mesh as dmesh
    exact = 0.25 * math.pi * (1.5 ** 2 - 1.0 ** 2) * 1.0
    errors = []
    for order in (1, 2):
        md = geometry.tube_sector(1.0, 1.5, 1.0, 0.25, order=order, cache_dir=cache, hexahedra=True)
        assert sorted(md.tags) == sorted(TUBE_FACES) and compat.cell_name(md.mesh) == "hexahedron"
        assert md.mesh.comm.allreduce(md.mesh.topology.index_map(3).size_local, op=MPI.SUM) == 8 * 2 * 4
        r = np.hypot(*md.mesh.geometry.x[:, :2].T)
        for name, radius in (("inner", 1.0), ("outer", 1.5)):
            f = md.facet_tags.indices[md.facet_tags.values == md.tags[name]]
            assert np.allclose(np.hypot(*dmesh.compute_midpoints(md.mesh, 2, f)[:, :2].T), radius, atol=0.02)
            near = np.abs(r - radius) < 0.05        # (the next nodes inward lie 0.125 away)
            assert near.sum() >= 4 * order and np.allclose(r[near], radius, rtol=0, atol=1e-9), name
        errors.append(abs(_volume(md) / exact - 1.0))
    assert 1e-3 < errors[0] < 1e-2 and errors[1] < 1e-3 * errors[0], errors


def test_hexahedra_refusals(cache):
    with pytest.raises(MeshError, match="hexahedra must be True or False, got 'yes'"):
        geometry.box(1.0, 1.0, 1.0, 0.5, cache_dir=cache, hexahedra="yes")
    with pytest.raises(MeshError, match="size_contact = 0.1 grades tetrahedra only"):
        geometry.tube_sector(1.0, 1.5, 1.0, 0.25, size_contact=0.1, contact_zone=0.3, cache_dir=cache,
                             hexahedra=True)


PROBLEM = """
[mesh]
builder = "box"
Lx = 1.0
Ly = 0.5
Lz = 0.5
size = 0.25
hexahedra = {flag}

[body]
kind = "solid"
material = {{ E = 1000.0, nu = 0.3 }}

[[items]]
type = "fixed"
boundary = "left"
"""


def test_a_problem_file_asks_for_hexahedra(tmp_path):
    """``hexahedra = true`` in [mesh] builds bricks; a value that is not a boolean is refused in one
    line naming it."""
    from comove_dolfinx import problem
    from comove_dolfinx.problem_schema import ProblemError
    path = tmp_path / "block.toml"
    path.write_text(PROBLEM.format(flag="true"))
    data = problem.read(path)
    data["mesh"]["cache_dir"] = str(tmp_path)
    assert compat.cell_name(problem.build(data, MPI.COMM_WORLD).body.mesh.mesh) == "hexahedron"
    path.write_text(PROBLEM.format(flag='"yes"'))
    with pytest.raises(ProblemError, match=r"\[mesh\]: hexahedra = 'yes': give true or false"):
        problem.read(path)


# -- patch tests ----------------------------------------------------------------------------------------
def _patch(md, faces, degree, update="small_strain", material=None, grad=G, n=1):
    """Every face held at u = t grad X: (the model, the stress at every quadrature point)."""
    m = Model(Body(md, "solid", material or cm.Elastic(E, NU), update=update, degree=degree),
              [cm.Displacement(face, field=lambda x, t: t * (grad @ x)) for face in faces])
    m.finalize()
    res = IncrementalSolver(m, StepSettings(n_increments=n), NewtonSettings(rtol=1e-13, atol=1e-13)).run()
    assert res.completed, res.message
    return m, m.cauchy_stress()


PATCHES = [("box", 1, 1), ("box", 2, 2), ("box", 2, 1), ("tube", 1, 1), ("tube", 2, 2)]


@pytest.mark.parametrize("builder,order,degree", PATCHES, ids=[f"{b}-order{o}-q{d}" for b, o, d in PATCHES])
def test_patch_test(cache, builder, order, degree):
    """A linear displacement on every face (bricks of the box; curved, distorted ones of the quarter
    tube): the discrete solution is that field, so the stress is the closed form's at every
    quadrature point, to round-off (also with a Q1 displacement on the box's 27-node bricks, which
    are affine; on curved 27-node bricks a Q1 displacement cannot hold a linear field)."""
    md = geometry.box(1.0, 0.5, 0.5, 0.25, order=order, cache_dir=cache, hexahedra=True) if builder == "box" else \
        geometry.tube_sector(1.0, 1.5, 0.5, 0.25, order=order, cache_dir=cache, hexahedra=True)
    m, s = _patch(md, BOX_FACES if builder == "box" else TUBE_FACES, degree)
    sigma, _ = _closed_form(False)
    vec = np.array([sigma[0, 0], sigma[1, 1], sigma[2, 2], sigma[0, 1], sigma[1, 2], sigma[0, 2]])
    assert s.shape[1] == 6 and m.rule.npts == {1: 8, 2: 27}[degree]
    np.testing.assert_allclose(s, np.tile(vec, (len(s), 1)), rtol=0, atol=1e-9 * np.abs(vec).max())
    X = m.V.tabulate_dof_coordinates()
    u = m.u.x.array.reshape(-1, 3)
    np.testing.assert_allclose(u, X @ G.T, rtol=0, atol=1e-12)


def test_patch_test_j2_finite_strain(cache):
    """The J2 uniaxial stretch to 1.2 (sr_log, 8 increments) on Q2 bricks: the radial return of a
    proportional path is exact, sigma = (sigma_y0 + H eps) / (1 + H / E), eps the sum of the
    increments' Pade logarithms, at every point."""
    sy, H, n = 8.0, 200.0, 8
    md = geometry.box(1.0, 0.25, 0.25, 0.125, cache_dir=cache, hexahedra=True)
    items = [cm.Fixed("left", 0), cm.Fixed("front", 1), cm.Fixed("bottom", 2),
             cm.Displacement("right", 0.2, component=0)]
    m = Model(Body(md, "solid", cm.J2(E, 0.3, cm.Hardening.linear(sy, H)), update="sr_log"), items)
    m.finalize()
    assert IncrementalSolver(m, StepSettings(n_increments=n), NewtonSettings(rtol=1e-13, atol=1e-13)).run().completed
    lam = 1.0 + 0.2 * np.arange(n + 1) / n
    ratio = lam[1:] / lam[:-1] - 1.0
    eps = np.sum(2.0 * ratio / (2.0 + ratio))
    sigma = (sy + H * eps) / (1.0 + H / E)
    np.testing.assert_allclose(m.cauchy_stress()[:, 0], sigma, rtol=1e-10, atol=0)
    np.testing.assert_allclose(m.p.x.array, eps - sigma / E, rtol=1e-9, atol=0)


@pytest.mark.parametrize("degree", [1, 2])
def test_compression_on_a_frictionless_plane(cache, degree):
    """A block of bricks pressed onto a plane (Nitsche, frictionless) by its top face moved down by
    d: uniform compression, so the contact force is E d / H times the area, the contact area is the
    bottom face and the peak of the nodal pressure is E d / H (small strain, the sides free)."""
    d, H = 0.01, 0.5
    md = geometry.box(1.0, 0.5, H, 0.25, order=degree, cache_dir=cache, hexahedra=True)
    c = cm.Contact("bottom", cm.Plane((0.0, 0.0, 0.0), (0.0, 0.0, 1.0)), method="nitsche", gamma0=10.0)
    items = [cm.Fixed("left", 0), cm.Fixed("front", 1), cm.Displacement("top", -d, component=2), c]
    body = cm.Body(md, "solid", cm.Elastic(E, NU), update="small_strain", degree=degree)
    res = cm.Job(body, items, [cm.Step(2)], [cm.ContactForce(c, "P", component=2), cm.ContactArea(c, "A"),
                                             cm.ContactPeak(c, "p0")]).run()
    assert res.completed, res.message
    assert res.last["P"] == pytest.approx(E * d / H * 0.5, rel=1e-9)
    assert res.last["A"] == pytest.approx(0.5, rel=1e-12)
    assert res.last["p0"] == pytest.approx(E * d / H, rel=1e-9)


# -- tetrahedra against hexahedra -----------------------------------------------------------------------
def _cantilever(cache, size, hexahedra, comm=MPI.COMM_WORLD):
    """A J2 cantilever 1 x 0.5 x 0.25 (P2/Q2, sr_log) clamped on its left face, under an end traction
    and a follower pressure on its upper face: (tip deflection, vertical reaction, plastic strain, dofs)."""
    md = geometry.box(1.0, 0.5, 0.25, size, comm=comm, cache_dir=cache, hexahedra=hexahedra)
    material = cm.J2(E, NU, cm.Hardening((0.0, 0.05, 0.2), (15.0, 20.0, 22.0)))
    items = [cm.Fixed("left"), cm.Traction("right", (0.0, -1.3, 0.0)), cm.Pressure("back", 0.5)]
    job = cm.Job(cm.Body(md, "solid", material, update="sr_log"), items, [cm.Step(4)],
                 [cm.NodeDisplacement("tip", (1.0, 0.5, 0.0)), cm.Reaction("left", "clamp", dim=3),
                  cm.MaxPlasticStrain()])
    res = job.run()
    assert res.completed, res.message
    return res.last["tip_uy"], res.last["clamp_fy"], res.last["max_plastic_strain"], res


def test_tetrahedra_and_hexahedra_converge_to_each_other(cache):
    """The same partly plastic cantilever on P2 tetrahedra and Q2 bricks: their tip deflections and
    their reactions (the follower pressure's resultant turns with the face) differ by the
    discretisation error, which falls as the mesh is refined (measured: deflections 8.7e-3, 7.8e-4,
    2.8e-4 apart at sizes 0.25, 0.125, 0.0625; reactions 1.1e-4, 6.4e-5, 2.2e-5)."""
    diffs, reactions = [], []
    for size in (0.25, 0.125):
        tet, hexa = (_cantilever(cache, size, h) for h in (False, True))
        assert abs(tet[0]) > 0.02 and tet[2] > 0.0 and hexa[2] > 0.0
        diffs.append(abs(hexa[0] / tet[0] - 1.0))
        reactions.append(abs(hexa[1] / tet[1] - 1.0))
    assert diffs[0] < 1.5e-2 and diffs[1] < 0.2 * diffs[0], diffs
    assert reactions[0] < 5e-4 and reactions[1] < 0.8 * reactions[0], reactions


# -- Taylor test ------------------------------------------------------------------------------------------
def _taylor_state(cache, degree, contact=None):
    """A J2 block of bricks sheared and compressed between its bottom (held) and its top (moved), a
    follower pressure and a dead traction on two faces and a body force; with ``contact`` its bottom
    pressed onto a plane with friction instead: two converged increments, then one Newton
    correction into the next."""
    md = geometry.box(1.0, 0.5, 0.5, 0.25, order=degree, cache_dir=cache, hexahedra=True)
    material = cm.J2(1000.0, 0.3, cm.Hardening((0.0, 0.05, 0.2), (15.0, 20.0, 22.0)))
    items = [cm.Displacement("top", (0.06, 0.03, -0.06)), cm.Pressure("right", 5.0),
             cm.Traction("left", (2.0, -1.0, 0.5)), cm.BodyForce((2.0, -10.0, 3.0))]
    if contact is None:
        items.append(cm.Fixed("bottom"))
    else:
        items.append(cm.Contact("bottom", cm.Plane((0.0, 0.0, 0.0), (0.0, 0.0, 1.0)), method=contact,
                                gamma0=10.0, mu=0.1))
    m = Model(Body(md, "solid", material, update="sr_log", degree=degree), items)
    m.finalize()
    one_correction_into(m)
    assert m.comm.allreduce(int(np.sum(m.p.x.array > m.p_n.x.array)), op=MPI.SUM) > 0, "no point yields"
    return m


TAYLOR = [dict(degree=2), dict(degree=1), dict(degree=2, contact="penalty"), dict(degree=2, contact="nitsche")]


@pytest.mark.parametrize("case", TAYLOR, ids=["-".join(map(str, c.values())) for c in TAYLOR])
def test_jacobian_is_exact_on_hexahedra(cache, case):
    result = taylor_test(_taylor_state(cache, **case), h0=1e-4, n=8)
    assert np.all(np.abs(result.orders[-3:] - 2.0) < 0.15), str(result)


# -- output, restart, ranks ------------------------------------------------------------------------------
@pytest.mark.parametrize("order", [1, 2])
def test_vtk_of_hexahedra(tmp_path, order):
    """Read back with meshio: 8-node bricks (VTK_HEXAHEDRON) or 27-node ones
    (VTK_TRIQUADRATIC_HEXAHEDRON), each cell's nodes at VTK's own parametric coordinates of its
    type (asked of VTK) in the brick; the points are the reference nodes, the displacement at each
    is G X, every cell's stress is the closed form's."""
    import meshio
    cells_vtk = pytest.importorskip("vtkmodules.vtkCommonDataModel")
    md = geometry.box(1.0, 0.5, 0.5, 0.25, order=order, comm=MPI.COMM_SELF, cache_dir=str(tmp_path),
                      hexahedra=True)
    items = [cm.Displacement(face, field=lambda x, t: t * (G @ x)) for face in BOX_FACES]
    body = cm.Body(md, "solid", cm.Elastic(E, NU), degree=order, update="small_strain")
    assert cm.Job(body, items, [cm.Step(2)], writers=[cm.VTK(tmp_path / "out")]).run().completed
    m = meshio.read(tmp_path / "out" / "results_00001.vtu")
    kind = {1: "hexahedron", 2: "hexahedron27"}[order]
    assert list(m.cells_dict) == [kind]
    cells, X = m.cells_dict[kind], m.points
    assert cells.shape == (4 * 2 * 2, {1: 8, 2: 27}[order])
    cell = {1: cells_vtk.vtkHexahedron, 2: cells_vtk.vtkTriQuadraticHexahedron}[order]()
    p = cell.GetParametricCoords()
    ref = np.array([p[i] for i in range(3 * cells.shape[1])]).reshape(-1, 3)
    low, high = X[cells[:, 0]], X[cells[:, 6]]          # VTK's vertices 0 and 6: opposite corners
    np.testing.assert_allclose(X[cells], low[:, None, :] + ref[None, :, :] * (high - low)[:, None, :], atol=1e-12)
    assert np.prod(high - low, axis=1).sum() == pytest.approx(0.25, rel=1e-12)   # the bricks fill the box
    np.testing.assert_allclose(m.point_data["displacement"], X @ G.T, atol=1e-12)
    sigma, _ = _closed_form(False)
    np.testing.assert_allclose(m.cell_data["cauchy_stress_cell_avg"][0], np.tile(sigma.ravel(), (len(cells), 1)),
                               rtol=0, atol=1e-8 * np.abs(sigma).max())


def _bent_block(*args, **kwargs):
    """test_output3d's plastic block on Q2 bricks."""
    return _bent_block_of(*args, hexahedra=True, **kwargs)


@pytest.mark.mpi
def test_a_run_on_hexahedra_restarts_to_the_uninterrupted_history(mpi_tmp):
    """Stopped after increment 3, then restarted from its checkpoint: the history and Newton's
    iterations are those of the run that was not stopped, to 1e-12, on however many ranks the test
    runs (and on one rank from the checkpoint of several)."""
    full = _bent_block(mpi_tmp).run()
    assert full.completed and len(full) == 5 and full["max_plastic_strain"][-1] > 0.0
    folder = mpi_tmp / "checkpoint"
    with pytest.raises(RuntimeError, match="stopped by the test"):
        _bent_block(mpi_tmp, folder, stop_after=3).run()
    comm = MPI.COMM_WORLD
    kept = mpi_tmp / "checkpoint_3"
    if comm.rank == 0:
        shutil.copytree(folder, kept)
    comm.barrier()
    _same_history(_bent_block(mpi_tmp, folder).run(restart=folder), full)
    if comm.size > 1:
        try:
            if comm.rank == 0:
                _same_history(_bent_block(mpi_tmp, comm=MPI.COMM_SELF).run(restart=kept), full)
        finally:
            comm.barrier()


@pytest.mark.mpi
def test_hexahedra_on_two_ranks_are_the_serial_run(mpi_tmp):
    """The J2 block of bricks distributed over the ranks and, on every rank, on its own (COMM_SELF):
    the same Newton iterations and history to 1e-9 of each column."""
    par = _bent_block(mpi_tmp).run()
    ser = _bent_block(mpi_tmp, comm=MPI.COMM_SELF).run()
    assert par.completed and ser.completed and par.newton_its == ser.newton_its
    for col in ("clamp_fx", "clamp_fy", "clamp_fz", "tip_ux", "tip_uy", "tip_uz", "max_plastic_strain"):
        r = np.asarray(ser[col], float)
        np.testing.assert_allclose(par[col], r, rtol=0, atol=1e-9 * np.abs(r).max(), err_msg=col)

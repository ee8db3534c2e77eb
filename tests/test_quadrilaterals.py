"""2D bodies on quadrilaterals (Q1 and Q2, Gmsh's 4- and 9-node quadrangles): the contact's nodal
pressure field against the closed form of uniform compression, det F checked at every node of the
quadrilateral (an inverted corner that a triangle's nodes would miss), the VTK output read back."""
import numpy as np
import pytest
import ufl
from dolfinx import fem
from mpi4py import MPI

from comove_dolfinx import compat
from comove_dolfinx.contact import Contact, Plane
from comove_dolfinx.geometry.gmsh_session import gmsh
from comove_dolfinx.geometry.meshes import BODY_TAG, add_group, build_cached
from comove_dolfinx.loads import Displacement, Fixed
from comove_dolfinx.mechanics.body import Body
from comove_dolfinx.mechanics.material_data import Elastic
from comove_dolfinx.mechanics.model import Model
from comove_dolfinx.solver import IncrementalSolver, NewtonSettings, StepSettings

E, NU = 1000.0, 0.3


@pytest.fixture(scope="module")
def cache(tmp_path_factory):
    return MPI.COMM_WORLD.bcast(str(tmp_path_factory.mktemp("quadmeshes")), root=0)


def quad_rectangle(L: float, H: float, nx: int, ny: int, order: int, cache: str):
    """[0, L] x [0, H] as an nx x ny grid of quadrilaterals (order 2: 9-node ones), with the edges
    "left", "right", "bottom", "top"."""
    def construct() -> None:
        geo = gmsh.model.geo
        p = [geo.addPoint(x, y, 0.0) for x, y in [(0.0, 0.0), (L, 0.0), (L, H), (0.0, H)]]
        bottom, right, top, left = (geo.addLine(p[i], p[(i + 1) % 4]) for i in range(4))
        surface = geo.addPlaneSurface([geo.addCurveLoop([bottom, right, top, left])])
        for curve, n in ((bottom, nx), (top, nx), (left, ny), (right, ny)):
            geo.mesh.setTransfiniteCurve(curve, n + 1)
        geo.mesh.setTransfiniteSurface(surface)
        geo.mesh.setRecombine(2, surface)
        geo.synchronize()
        add_group(2, [surface], BODY_TAG, "body")
        for tag, (name, curve) in enumerate([("left", left), ("right", right), ("bottom", bottom),
                                             ("top", top)], start=1):
            add_group(1, [curve], tag, name)

    params = dict(L=float(L), H=float(H), nx=nx, ny=ny, order=order)
    return build_cached("quad_rectangle", params, construct, MPI.COMM_WORLD, cache)


@pytest.mark.parametrize("degree", [1, 2])
def test_the_mesh_is_of_quadrilaterals(cache, degree):
    md = quad_rectangle(1.0, 0.5, 4, 2, degree, cache)
    assert compat.cell_name(md.mesh) == "quadrilateral"
    assert compat.geometry_degree(md.mesh) == degree
    assert md.mesh.comm.allreduce(md.mesh.topology.index_map(2).size_local, op=MPI.SUM) == 8


@pytest.mark.mpi
@pytest.mark.parametrize("side", ["bottom", "top"])
@pytest.mark.parametrize("degree", [1, 2])
def test_compression_on_a_frictionless_plane_gives_the_uniform_pressure_at_every_node(cache, degree, side):
    """A block (plane strain, small strain) pressed onto a plane (Nitsche, frictionless, consistent)
    by its opposite edge moved towards it by d, its sides free: uniaxial stress with eps_zz = 0, so
    the contact pressure is E d / (H (1 - nu^2)) everywhere, and the nodal pressure field holds it
    at every node of the contact boundary (the corners of Q1, the vertices and edge midpoints of
    Q2), with either edge in contact (the corners at every place in the cells' vertex order)."""
    d, L, H = 0.01, 1.0, 0.5
    md = quad_rectangle(L, H, 4, 2, degree, cache)
    y0, sign = (0.0, 1.0) if side == "bottom" else (H, -1.0)
    c = Contact(side, Plane((0.0, y0), (0.0, sign)), method="nitsche", gamma0=10.0)
    pushed = "top" if side == "bottom" else "bottom"
    m = Model(Body(md, "plane_strain", Elastic(E, NU), update="small_strain", degree=degree),
              [Fixed("left", component=0), Displacement(pushed, -sign * d, component=1), c])
    m.finalize()
    res = IncrementalSolver(m, StepSettings(n_increments=1), NewtonSettings(rtol=1e-12, atol=1e-12)).run()
    assert res.completed, res.message
    p = E * d / (H * (1.0 - NU ** 2))
    assert sign * c.force()[1] == pytest.approx(p * L, rel=1e-9)
    X, values = c.boundary_values("pressure")
    assert len(X) == 4 * degree + 1                      # every node of the contact edge
    np.testing.assert_allclose(values, p, rtol=1e-9)
    field = c.pressure.x.array                           # zero away from the contact boundary
    off = ~np.isclose(c.pressure.function_space.tabulate_dof_coordinates()[:, 1], y0)
    assert np.all(field[off] == 0.0)


def _bilinear_corner_motion(V, corner: np.ndarray, move: np.ndarray, L: float = 1.0):
    """The displacement that moves the vertex ``corner`` of the square [0, L]^2 by ``move``, the
    other three vertices held: ``move`` times that corner's bilinear hat function (exact in Q1, Q2)."""
    def u(x):
        hat = np.ones(x.shape[1])
        for k in range(2):
            hat *= x[k] / L if corner[k] > 0 else 1.0 - x[k] / L
        return np.outer(move, hat)
    f = fem.Function(V)
    f.interpolate(u)
    return f


@pytest.mark.parametrize("degree", [1, 2])
def test_det_F_is_checked_at_every_node_of_the_quadrilateral(cache, degree):
    """One square cell [0, 1]^2 whose vertex at the reference point (1, 1) moves by 0.8 of the side
    towards the opposite vertex, the other three held (u = that motion times the vertex's hat
    function x y in reference coordinates): det F = 1 - 0.8 (x + y), -0.6 at that vertex, where the
    cell folds, but 1, 0.2, 0.2 at the reference triangle's vertices (0, 0), (1, 0), (0, 1) and 0.2,
    0.6, 0.6 at its P2 midpoints (0.5, 0.5), (0, 0.5), (0.5, 0): the check at the quadrilateral's
    own nodes finds the fold; at half the motion, det F = 1 - 0.4 (x + y) >= 0.2, it finds none."""
    md = quad_rectangle(1.0, 1.0, 1, 1, degree, cache)
    m = Model(Body(md, "plane_strain", Elastic(E, NU), update="sr", degree=degree), [Fixed("left")])
    m.finalize()
    # the physical vertex at the cell's reference (1, 1): its fourth geometry node
    corner = md.mesh.geometry.x[compat.geometry_dofs(md.mesh)[0, 3], :2]
    m.u.x.array[:] = _bilinear_corner_motion(m.u.function_space, corner, -0.8 * np.sign(corner - 0.5)).x.array
    # at the triangle's reference nodes the map does not fold
    detF = ufl.det(ufl.Identity(2) + ufl.grad(m.u))
    tri = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]] + ([[0.5, 0.5], [0.0, 0.5], [0.5, 0.0]] if degree == 2 else []))
    at_tri = compat.evaluate(compat.expression(detF, tri), md.mesh, np.array([0], dtype=np.int32)).ravel()
    np.testing.assert_allclose(np.sort(at_tri), np.sort([1.0, 0.2, 0.2] + ([0.2, 0.6, 0.6] if degree == 2 else [])),
                               rtol=1e-10)
    message = m.folded_at_nodes()
    assert message is not None and message.startswith(f"det F = {1.0 - 0.8 * 2:.3g} <= 0 at a node")
    # unfolded: half that motion keeps det F > 0 at every node
    m.u.x.array[:] *= 0.5
    assert m.folded_at_nodes() is None


@pytest.mark.parametrize("degree", [1, 2])
def test_vtk_of_quadrilaterals(cache, tmp_path, degree):
    """Read back with meshio: 4-node quadrilaterals (VTK_QUAD) or 9-node ones
    (VTK_BIQUADRATIC_QUAD), each cell's nodes at VTK's own parametric coordinates of its type (asked
    of VTK) in the rectangle; the points are the reference nodes, the displacement at each is G X
    (a homogeneous deformation, which Q1 and Q2 hold exactly)."""
    import meshio
    cells_vtk = pytest.importorskip("vtkmodules.vtkCommonDataModel")
    import comove_dolfinx as cm
    G = np.array([[2.0e-3, 1.2e-3], [-0.6e-3, 0.9e-3]])
    md = quad_rectangle(1.0, 0.5, 4, 2, degree, cache)
    items = [cm.Displacement(edge, field=lambda x, t: t * (G @ x[:2])) for edge in ("left", "right", "bottom", "top")]
    body = cm.Body(md, "plane_strain", cm.Elastic(E, NU), degree=degree, update="small_strain")
    folder = MPI.COMM_WORLD.bcast(str(tmp_path / "out"), root=0)
    assert cm.Job(body, items, [cm.Step(2)], writers=[cm.VTK(folder)]).run().completed
    if MPI.COMM_WORLD.rank != 0:
        return
    m = meshio.read(f"{folder}/results_00001.vtu")
    kind = {1: "quad", 2: "quad9"}[degree]
    assert list(m.cells_dict) == [kind]
    cells, X = m.cells_dict[kind], m.points
    assert cells.shape == (8, {1: 4, 2: 9}[degree])
    cell = {1: cells_vtk.vtkQuad, 2: cells_vtk.vtkBiQuadraticQuad}[degree]()
    p = cell.GetParametricCoords()
    ref = np.array([p[i] for i in range(3 * cells.shape[1])]).reshape(-1, 3)
    low, high = X[cells[:, 0]], X[cells[:, 2]]          # VTK's vertices 0 and 2: opposite corners
    np.testing.assert_allclose(X[cells], low[:, None, :] + ref[None, :, :] * (high - low)[:, None, :], atol=1e-12)
    assert np.prod((high - low)[:, :2], axis=1).sum() == pytest.approx(0.5, rel=1e-10)   # they fill the rectangle
    np.testing.assert_allclose(m.point_data["displacement"][:, :2], X[:, :2] @ G.T, atol=1e-12)
    assert np.all(m.point_data["displacement"][:, 2] == 0.0)


@pytest.mark.parametrize("kind", ["plane_strain", "axisymmetric"])
@pytest.mark.parametrize("degree", [1, 2])
def test_the_default_rule_leaves_only_the_rigid_motions_without_stiffness(cache, degree, kind):
    """The stiffness of a free 2 x 1 block of quadrilaterals (small strain, no support) has exactly
    the rigid motions in its kernel: 3 in the plane (two translations and the rotation), 1 in
    axisymmetry (the axial translation). A rule with too few points (1 point on Q1, 2 x 2 on Q2)
    leaves further modes without stiffness (the hourglass modes), which this count finds."""
    md = quad_rectangle(1.0, 0.5, 2, 1, degree, cache)
    md.mesh.geometry.x[:, 0] += 0.5 if kind == "axisymmetric" else 0.0     # off the axis r = 0
    m = Model(Body(md, kind, Elastic(E, NU), update="small_strain", degree=degree))
    m.finalize()
    m.evaluate_stress(True)
    A = compat.create_matrix(m.jacobian_form)
    compat.assemble_matrix(A, m.jacobian_form)
    K = A.convert("dense").getDenseArray()
    eig = np.linalg.eigvalsh(0.5 * (K + K.T))
    zero = int(np.sum(np.abs(eig) < 1e-10 * np.abs(eig).max()))
    assert zero == {"plane_strain": 3, "axisymmetric": 1}[kind], eig[:6]

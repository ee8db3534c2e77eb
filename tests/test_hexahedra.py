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
    """The quarter tube as bricks: the tetrahedral builder's face names, 7 x 2 x 4 cells (around,
    through, along), nodes of the curved faces on the true cylinders; the volume's error is that of
    the chords at order 1 (4.1e-3 relative here) and far smaller at order 2 (the 27-node bricks)."""
    from dolfinx import mesh as dmesh
    exact = 0.25 * math.pi * (1.5 ** 2 - 1.0 ** 2) * 1.0
    errors = []
    for order in (1, 2):
        md = geometry.tube_sector(1.0, 1.5, 1.0, 0.25, order=order, cache_dir=cache, hexahedra=True)
        assert sorted(md.tags) == sorted(TUBE_FACES) and compat.cell_name(md.mesh) == "hexahedron"
        assert md.mesh.comm.allreduce(md.mesh.topology.index_map(3).size_local, op=MPI.SUM) == 10 * 2 * 4
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

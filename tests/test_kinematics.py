"""Co-moving kinematics: S-R decomposition, Christoffel symbols, convected derivatives, components."""
import numpy as np
import pytest
import ufl
from conftest import evaluate
from dolfinx import fem
from mpi4py import MPI

from comove_dolfinx import compat
from comove_dolfinx.mechanics import kinematics as kin


def _const(msh, A):
    return fem.Constant(msh, np.asarray(A, dtype=float))


def test_sr_vectors_2d(unit_mesh):
    """docs/theory.md section 2.5: F = [[1.1, 0.3], [-0.2, 0.95]]."""
    F = np.array([[1.1, 0.3], [-0.2, 0.95]])
    S, R, c = kin.sr_decomposition(_const(unit_mesh, F - np.eye(2)))
    assert evaluate(c, unit_mesh) == pytest.approx(0.968246, abs=1e-6)
    np.testing.assert_allclose(evaluate(R, unit_mesh), [[0.968246, 0.25], [-0.25, 0.968246]], atol=1e-6)
    np.testing.assert_allclose(evaluate(S, unit_mesh), [[0.131754, 0.05], [0.05, -0.018246]], atol=1e-6)


def test_sr_vectors_3d(unit_mesh):
    """docs/theory.md section 2.5, the 3D vector; also S + R = F, R^T R = I, S = S^T."""
    F = np.array([[1.05, 0.2, -0.1], [-0.1, 0.98, 0.15], [0.05, -0.25, 1.02]])
    S, R, c = kin.sr_decomposition(_const(unit_mesh, F - np.eye(3)))
    Rv, Sv = evaluate(R, unit_mesh), evaluate(S, unit_mesh)
    assert evaluate(c, unit_mesh) == pytest.approx(0.965337, abs=1e-6)
    np.testing.assert_allclose(Rv, [[0.985689, 0.157632, -0.059735], [-0.142368, 0.968199, 0.205724],
                                    [0.090265, -0.194276, 0.976785]], atol=1e-6)
    np.testing.assert_allclose(Sv, [[0.064311, 0.042368, -0.040265], [0.042368, 0.011801, -0.055724],
                                    [-0.040265, -0.055724, 0.043215]], atol=1e-6)
    np.testing.assert_allclose(Sv + Rv, F, atol=1e-15)
    np.testing.assert_allclose(Rv.T @ Rv, np.eye(3), atol=1e-15)
    np.testing.assert_allclose(Sv, Sv.T, atol=1e-15)


@pytest.mark.parametrize("deg", [1.0, 30.0, 60.0, 89.0])
def test_rigid_increment_gives_zero_strain(unit_mesh, deg):
    """A rigid rotation up to 90 degrees: S = 0 and R = Q to round-off (docs/theory.md section 2.3(4))."""
    a = np.radians(deg)
    n = np.array([1.0, -2.0, 0.5]) / np.linalg.norm([1.0, -2.0, 0.5])
    K = np.array([[0, -n[2], n[1]], [n[2], 0, -n[0]], [-n[1], n[0], 0]])
    Q = np.eye(3) + np.sin(a) * K + (1 - np.cos(a)) * K @ K
    S, R, _ = kin.sr_decomposition(_const(unit_mesh, Q - np.eye(3)))
    assert np.abs(evaluate(S, unit_mesh)).max() < 1e-14
    np.testing.assert_allclose(evaluate(R, unit_mesh), Q, atol=1e-14)


@pytest.mark.parametrize("deg, hoop", [(0.0, 0.0), (17.0, 0.04), (60.0, -0.1), (89.0, 0.0)])
def test_in_plane_split_is_chen_split(unit_mesh, deg, hoop):
    """The one-angle form of the 2D models (docs/theory.md section 2.2) gives the general split of
    the 3x3 embedding: a stretch, a shear and a hoop strain after an in-plane rotation; for the
    rotation alone, R = Q and S = 0 to round-off."""
    a = np.radians(deg)
    Q = np.array([[np.cos(a), -np.sin(a), 0.0], [np.sin(a), np.cos(a), 0.0], [0.0, 0.0, 1.0]])
    stretch = np.array([[1.04, 0.03, 0.0], [0.01, 0.97, 0.0], [0.0, 0.0, 1.0 + hoop]])
    H = _const(unit_mesh, Q @ stretch - np.eye(3))
    general = [evaluate(x, unit_mesh) for x in kin.sr_decomposition(H)]
    plane = [evaluate(x, unit_mesh) for x in kin.sr_decomposition_in_plane(H)]
    if deg > 80.0:         # sin(theta) = 1.0005 > 1: out of range (section 2.3), NaN in both
        assert np.isnan(general[1]).any() and np.isnan(plane[1]).any()
        assert np.isnan(general[0]).any() and np.isnan(plane[0]).any()
    else:
        for g, p in zip(general, plane):
            np.testing.assert_allclose(p, g, rtol=0, atol=1e-14)
        S, R, c = plane
        np.testing.assert_allclose(R.T @ R, np.eye(3), atol=1e-15)
        np.testing.assert_allclose(S + R, Q @ stretch, atol=1e-15)
    S, R, _ = kin.sr_decomposition_in_plane(_const(unit_mesh, Q - np.eye(3)))
    assert np.abs(evaluate(S, unit_mesh)).max() < 1e-14
    np.testing.assert_allclose(evaluate(R, unit_mesh), Q, atol=1e-14)


def test_in_plane_split_vectors(unit_mesh):
    """docs/theory.md section 2.5, the 2D vector in the 3x3 embedding (with a hoop strain, which
    the split leaves in S)."""
    F = np.array([[1.1, 0.3, 0.0], [-0.2, 0.95, 0.0], [0.0, 0.0, 1.02]])
    S, R, c = kin.sr_decomposition_in_plane(_const(unit_mesh, F - np.eye(3)))
    assert evaluate(c, unit_mesh) == pytest.approx(0.968246, abs=1e-6)
    np.testing.assert_allclose(evaluate(R, unit_mesh), [[0.968246, 0.25, 0], [-0.25, 0.968246, 0], [0, 0, 1]],
                               atol=1e-6)
    np.testing.assert_allclose(evaluate(S, unit_mesh), [[0.131754, 0.05, 0], [0.05, -0.018246, 0],
                                                        [0, 0, 0.02]], atol=1e-6)


def _p2_fields(msh):
    V = compat.function_space(msh, "Lagrange", 2, (2,))
    u, v = fem.Function(V), fem.Function(V)
    u.interpolate(lambda x: np.stack([0.3 * x[0] * x[1] + 0.1 * x[1] ** 2, -0.2 * x[0] ** 2 + 0.15 * x[0]]))
    v.interpolate(lambda x: np.stack([0.5 * x[1] ** 2 - 0.2 * x[0], 0.4 * x[0] * x[1] + 0.1]))
    return u, v


def test_christoffel_two_ways(unit_mesh):
    """Gamma from F^-1 grad F equals Gamma from the metric alone, and is symmetric in I, J."""
    u, _ = _p2_fields(unit_mesh)
    for pt in [(0.2, 0.3), (0.6, 0.1)]:
        G1 = evaluate(kin.christoffel(u), unit_mesh, pt)
        G2 = evaluate(kin.christoffel_from_metric(u), unit_mesh, pt)
        assert np.abs(G1).max() > 0.05                       # a curved convected frame
        np.testing.assert_allclose(G1, G2, atol=1e-14)
        np.testing.assert_allclose(G1, G1.transpose(0, 2, 1), atol=1e-14)


def test_covariant_derivative_equals_F_inverse_grad_v(unit_mesh):
    """v^I||_J through the Christoffel symbols equals F^-1 Grad v (docs/theory.md section 1.1)."""
    u, v = _p2_fields(unit_mesh)
    F = ufl.Identity(2) + ufl.grad(u)
    for pt in [(0.2, 0.3), (0.6, 0.1)]:
        a = evaluate(kin.covariant_velocity_gradient(u, v), unit_mesh, pt)
        b = evaluate(kin.convected_velocity_gradient(F, ufl.grad(v)), unit_mesh, pt)
        np.testing.assert_allclose(a, b, atol=1e-14)
        # and the Gamma term matters: the plain gradient of the contravariant components differs
        c = evaluate(ufl.grad(ufl.inv(F) * v), unit_mesh, pt)
        assert np.abs(c - b).max() > 1e-3


def test_strain_rate_is_push_forward_of_metric_rate(unit_mesh):
    """d = sym(Grad v F^-1) = F^-T (1/2 dC/dt) F^-1 with dC/dt = F^T Grad v + Grad v^T F."""
    u, v = _p2_fields(unit_mesh)
    F = ufl.Identity(2) + ufl.grad(u)
    Cdot = F.T * ufl.grad(v) + ufl.grad(v).T * F
    d1 = evaluate(kin.strain_rate(F, ufl.grad(v)), unit_mesh)
    d2 = evaluate(ufl.inv(F).T * (0.5 * Cdot) * ufl.inv(F), unit_mesh)
    np.testing.assert_allclose(d1, d2, atol=1e-14)


def test_physical_components_on_a_rotated_stretched_fibre(unit_mesh):
    """A uniaxial stress s along the convected fibre g_1 = F e_1: every physical component agrees."""
    a, lam, s = np.radians(35.0), 1.3, 7.0
    Q = np.array([[np.cos(a), -np.sin(a), 0], [np.sin(a), np.cos(a), 0], [0, 0, 1]])
    F = Q @ np.diag([lam, 0.9, 1.0])
    sig = Q @ np.diag([s, 0, 0]) @ Q.T
    Fc, Sc = _const(unit_mesh, F), _const(unit_mesh, sig)
    for kind in ("contravariant", "covariant", "mixed"):
        T = evaluate(kin.physical_components(Sc, Fc, kind), unit_mesh)
        np.testing.assert_allclose(T, np.diag([s, 0, 0]), atol=1e-13)
    A = ufl.as_vector([1.0, 0.0, 0.0])
    assert evaluate(kin.fibre_stress(Sc, Fc, A), unit_mesh) == pytest.approx(s, rel=1e-14)


def test_embeddings(unit_mesh):
    """Plane strain F_zz = 1; axisymmetric F_zz = 1 + u_r/r; plane stress needs the thickness stretch."""
    from dolfinx import mesh
    msh = mesh.create_rectangle(MPI.COMM_SELF, [[1.0, 0.0], [2.0, 1.0]], [1, 1])
    V = compat.function_space(msh, "Lagrange", 1, (2,))
    u = fem.Function(V)
    u.interpolate(lambda x: np.stack([0.1 * x[0], 0.0 * x[1]]))     # u_r = 0.1 r: hoop strain 0.1
    x = ufl.SpatialCoordinate(msh)
    axi = kin.Kinematics(kin.AXISYMMETRIC, x)
    assert evaluate(axi.F3(u), msh)[2, 2] == pytest.approx(1.1, rel=1e-14)
    assert evaluate(kin.Kinematics(kin.PLANE_STRAIN, x).F3(u), msh)[2, 2] == 1.0
    with pytest.raises(ValueError, match="thickness stretch"):
        kin.Kinematics(kin.PLANE_STRESS, x).F3(u)
    with pytest.raises(ValueError, match="unknown model"):
        kin.Kinematics("3d", x)


@pytest.mark.parametrize("F22", [1.0, 0.93, 1.2])
def test_cofactor_is_J_F_inverse_transpose(unit_mesh, F22):
    """kinematics.cofactor, the polynomial form of J F^-T of the 3x3 embedding (docs/theory.md
    section 5.1), against det(F) inv(F)^T; F22 = 1 plane strain, else a thickness or hoop stretch."""
    F = np.array([[1.1, 0.3, 0.0], [-0.2, 0.95, 0.0], [0.0, 0.0, F22]])
    got = evaluate(kin.cofactor(_const(unit_mesh, F)), unit_mesh)
    np.testing.assert_allclose(got, np.linalg.det(F) * np.linalg.inv(F).T, rtol=0, atol=1e-15)

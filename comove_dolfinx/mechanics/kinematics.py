"""Co-moving (convected) kinematics in UFL.

The co-moving coordinates are the reference Cartesian positions X, so the convected base vectors
g_I are the columns of F and every tensor is stored in Cartesian components (docs/theory.md section 1.1).

Conventions
-----------
* 2D models live in a 3x3 embedding: indices 0, 1 are in-plane (x, y) or (r, z), index 2 is the
  out-of-plane direction (z in plane strain/stress, the hoop direction theta in axisymmetry).
  The 3D model ``"solid"`` has the full 3x3 gradient ``F = I + Grad u`` of a displacement with three
  components.
  ``F3 = [[F00, F01, 0], [F10, F11, 0], [0, 0, F22]]`` with F22 = 1 (plane strain), 1 + u_r/r
  (axisymmetry) or the thickness stretch given by the constitutive law (plane stress).
* Symmetric tensors are stored as 4-vectors (xx, yy, zz, xy) of tensor components (shear once) in
  the 2D models and as 6-vectors (xx, yy, zz, xy, yz, xz) in 3D (the 4-vector's entries first, then
  the two shears that the 2D models do not have); :func:`to_vec` and :func:`to_tensor` convert
  (:attr:`Kinematics.size` is the length).
* The S-R decomposition (Chen) of a displacement gradient H: F = I + H = S + R with S symmetric
  (a strain, zero for a rigid motion) and R a rotation, in the singularity-free form
  c = sqrt(1 - W:W/2), R = I + W + W.W/(1 + c), S = sym H - W.W/(1 + c), W = skew H
  (docs/theory.md section 2.2). It exists while W:W/2 <= 1 and is applied to increments, where that always holds.
"""
from __future__ import annotations

import ufl

PLANE_STRAIN = "plane_strain"
PLANE_STRESS = "plane_stress"
AXISYMMETRIC = "axisymmetric"
SOLID = "solid"
MODELS = (PLANE_STRAIN, PLANE_STRESS, AXISYMMETRIC, SOLID)


# --------------------------------------------------------------------------------------------
# Storage helpers
# --------------------------------------------------------------------------------------------
def to_vec(T: ufl.core.expr.Expr, size: int = 4) -> ufl.core.expr.Expr:
    """Symmetric 3x3 tensor -> 4-vector (xx, yy, zz, xy), or with ``size`` 6 the 6-vector
    (xx, yy, zz, xy, yz, xz) of the 3D model."""
    if size == 6:
        return ufl.as_vector([T[0, 0], T[1, 1], T[2, 2], T[0, 1], T[1, 2], T[0, 2]])
    return ufl.as_vector([T[0, 0], T[1, 1], T[2, 2], T[0, 1]])


def to_tensor(s: ufl.core.expr.Expr) -> ufl.core.expr.Expr:
    """4-vector (xx, yy, zz, xy) or 6-vector (xx, yy, zz, xy, yz, xz) -> symmetric 3x3 tensor."""
    if s.ufl_shape == (6,):
        return ufl.as_tensor([[s[0], s[3], s[5]], [s[3], s[1], s[4]], [s[5], s[4], s[2]]])
    return ufl.as_tensor([[s[0], s[3], 0], [s[3], s[1], 0], [0, 0, s[2]]])


def embed(A2: ufl.core.expr.Expr, a22) -> ufl.core.expr.Expr:
    """2x2 in-plane block and an out-of-plane scalar -> 3x3 block-diagonal tensor."""
    return ufl.as_tensor([[A2[0, 0], A2[0, 1], 0], [A2[1, 0], A2[1, 1], 0], [0, 0, a22]])


def von_mises(sigma: ufl.core.expr.Expr) -> ufl.core.expr.Expr:
    """Von Mises equivalent stress sqrt(3/2 s:s) of a 3x3 stress."""
    s = ufl.dev(sigma)
    return ufl.sqrt(1.5 * ufl.inner(s, s))


# --------------------------------------------------------------------------------------------
# Embeddings of the 2D models, and the 3D model
# --------------------------------------------------------------------------------------------
class Kinematics:
    """Displacement gradients of a 2D model embedded in 3x3, or of the 3D model.

    Parameters
    ----------
    model:
        ``"plane_strain"``, ``"plane_stress"``, ``"axisymmetric"`` (x = r, y = z) or ``"solid"``
        (3D: the full gradient, unit weight).
    x:
        ``ufl.SpatialCoordinate`` of the reference mesh.
    thickness:
        Out-of-plane thickness b of plane models (forces are per b); ignored in axisymmetry, where
        integrals carry the weight 2 pi r and forces are totals over the circumference.
    """

    def __init__(self, model: str, x, thickness: float = 1.0):
        if model not in MODELS:
            raise ValueError(f"unknown model {model!r}: choose one of {', '.join(MODELS)}")
        self.model = model
        self.x = x
        self.thickness = thickness

    @property
    def axisymmetric(self) -> bool:
        return self.model == AXISYMMETRIC

    @property
    def solid(self) -> bool:
        """The 3D model: a displacement of three components, no embedding."""
        return self.model == SOLID

    @property
    def size(self) -> int:
        """Length of a stored symmetric tensor: 4 (xx, yy, zz, xy) or 6 in 3D (..., yz, xz)."""
        return 6 if self.solid else 4

    @property
    def dim(self) -> int:
        """Number of displacement components: 2, or 3 in 3D."""
        return 3 if self.solid else 2

    def vec(self, T) -> ufl.core.expr.Expr:
        """The stored vector of a symmetric 3x3 tensor T (:func:`to_vec` of this model's size)."""
        return to_vec(T, self.size)

    def weight(self):
        """Volume weight of the integrals: 2 pi r (axisymmetry), the thickness b (plane models) or
        1 (3D)."""
        if self.solid:
            return 1.0
        return 2.0 * ufl.pi * self.x[0] if self.axisymmetric else self.thickness

    def grad3(self, w) -> ufl.core.expr.Expr:
        """3x3 embedded reference gradient of a displacement-like field w (zz: w_r/r or 0); in 3D
        the gradient itself."""
        if self.solid:
            return ufl.grad(w)
        zz = w[0] / self.x[0] if self.axisymmetric else 0
        return embed(ufl.grad(w), zz)

    def F3(self, u, F22=None) -> ufl.core.expr.Expr:
        """Deformation gradient; in plane stress the thickness stretch F22 must be given."""
        if self.model == PLANE_STRESS:
            if F22 is None:
                raise ValueError("plane stress: the thickness stretch F22 comes from the material")
            return embed(ufl.Identity(2) + ufl.grad(u), F22)
        return ufl.Identity(3) + self.grad3(u)


def cofactor(F) -> ufl.core.expr.Expr:
    """J F^-T of the 3x3 embedding F = [[F00, F01, 0], [F10, F11, 0], [0, 0, F22]], written without
    the inverse: [[F22 F11, -F22 F10, 0], [-F22 F01, F22 F00, 0], [0, 0, F00 F11 - F01 F10]], a
    polynomial in F. The nominal stress is P = sigma cof F (docs/theory.md section 5.1), and its
    derivative in F is a product rule, where UFL's derivative of J F^-T goes through the
    inverse's explicit formula (divisions by det F, terms that cancel) in the generated code."""
    a, b, c, d, e = F[0, 0], F[0, 1], F[1, 0], F[1, 1], F[2, 2]
    return ufl.as_tensor([[e * d, -e * c, 0], [-e * b, e * a, 0], [0, 0, a * d - b * c]])


def cofactor3(F) -> ufl.core.expr.Expr:
    """J F^-T of a full 3x3 F, as :func:`cofactor` written without the inverse: the entry (i, j)
    is the signed minor of F_ij, ``F[i+1, j+1] F[i+2, j+2] - F[i+1, j+2] F[i+2, j+1]`` (indices
    mod 3), a quadratic polynomial in F."""
    def minor(i, j):
        i1, i2, j1, j2 = (i + 1) % 3, (i + 2) % 3, (j + 1) % 3, (j + 2) % 3
        return F[i1, j1] * F[i2, j2] - F[i1, j2] * F[i2, j1]
    return ufl.as_tensor([[minor(i, j) for j in range(3)] for i in range(3)])


# --------------------------------------------------------------------------------------------
# Co-moving metric, base and Christoffel symbols
# --------------------------------------------------------------------------------------------
def metric(F):
    """Co-moving metric g_IJ = g_I . g_J = (F^T F)_IJ."""
    return F.T * F


def inverse_metric(F):
    """Contravariant metric g^IJ = (C^-1)_IJ."""
    return ufl.inv(metric(F))


def christoffel(u) -> ufl.core.expr.Expr:
    """Christoffel symbols Gamma^K_IJ = (F^-1)_Kk dF_kI/dX_J of the convected frame (in-plane).

    Needs a displacement whose gradient is not cell-wise constant (P2 or higher) to be non-zero.
    """
    F = ufl.Identity(len(u)) + ufl.grad(u)
    Finv = ufl.inv(F)
    dF = ufl.grad(F)
    K, I, J, k = ufl.indices(4)
    return ufl.as_tensor(Finv[K, k] * dF[k, I, J], (K, I, J))


def christoffel_from_metric(u) -> ufl.core.expr.Expr:
    """The same symbols from the metric alone: 1/2 C^-1_KL (C_LI,J + C_LJ,I - C_IJ,L)."""
    F = ufl.Identity(len(u)) + ufl.grad(u)
    C = metric(F)
    Cinv = ufl.inv(C)
    dC = ufl.grad(C)
    K, I, J, L = ufl.indices(4)
    return ufl.as_tensor(0.5 * Cinv[K, L] * (dC[L, I, J] + dC[L, J, I] - dC[I, J, L]), (K, I, J))


def covariant_velocity_gradient(u, v) -> ufl.core.expr.Expr:
    """v^I||_J = d v^I/d X^J + Gamma^I_KJ v^K with v^I = (F^-1 v)_I the contravariant components."""
    F = ufl.Identity(len(u)) + ufl.grad(u)
    vc = ufl.inv(F) * v
    G = christoffel(u)
    I, J, K = ufl.indices(3)
    return ufl.as_tensor(ufl.grad(vc)[I, J] + G[I, K, J] * vc[K], (I, J))


def convected_velocity_gradient(F, grad_v) -> ufl.core.expr.Expr:
    """The same covariant derivative in closed form: F^-1 Grad v (the Gamma terms cancel)."""
    return ufl.inv(F) * grad_v


def strain_rate(F, grad_v) -> ufl.core.expr.Expr:
    """Eulerian strain rate d = sym(Grad v F^-1) (push-forward of the convected rate 1/2 dC/dt)."""
    return ufl.sym(grad_v * ufl.inv(F))


# --------------------------------------------------------------------------------------------
# S-R decomposition
# --------------------------------------------------------------------------------------------
def sr_decomposition(H):
    """Chen's S-R split of F = I + H into a symmetric strain S and a rotation R.

    Returns
    -------
    (S, R, c):
        the strain, the rotation and c = cos(theta) of the mean local rotation angle.
    """
    n = H.ufl_shape[0]
    W = ufl.skew(H)
    WW = W * W
    c = ufl.sqrt(1.0 - 0.5 * ufl.inner(W, W))
    R = ufl.Identity(n) + W + WW / (1.0 + c)
    S = ufl.sym(H) - WW / (1.0 + c)
    return S, R, c


def sr_decomposition_direction(H, G):
    """The derivative of :func:`sr_decomposition` at H in the direction G = dH, in closed form:
    (dS, dR). With W = skew H, dW = skew G, c = sqrt(1 - W:W/2) and k = 1 / (1 + c),

        dc = -(W:dW) / (2 c),  dk = -k^2 dc,  d(W.W) = dW.W + W.dW,
        dR = dW + k d(W.W) + dk W.W,  dS = sym G - k d(W.W) - dk W.W

    (docs/theory.md section 1.4); defined wherever the split is (c > 0)."""
    W, dW = ufl.skew(H), ufl.skew(G)
    WW, dWW = W * W, dW * W + W * dW
    c = ufl.sqrt(1.0 - 0.5 * ufl.inner(W, W))
    k = 1.0 / (1.0 + c)
    dk = 0.5 * ufl.inner(W, dW) / c * k * k
    dR = dW + k * dWW + dk * WW
    dS = ufl.sym(G) - k * dWW - dk * WW
    return dS, dR


def rotation_axis_angle(R):
    """(unit axis, angle) of a rotation tensor R given as a NumPy 3x3 array: the angle in [0, pi]
    from the trace, the axis from the skew part (for tests and post-processing; NumPy, not UFL)."""
    import numpy as np
    R = np.asarray(R, dtype=float)
    w = 0.5 * np.array([R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]])
    angle = float(np.arctan2(np.linalg.norm(w), 0.5 * (np.trace(R) - 1.0)))
    n = np.linalg.norm(w)
    return (w / n if n > 0 else np.array([0.0, 0.0, 1.0])), angle


def in_plane_angle(H):
    """(sin(theta), cos(theta)) of the S-R split's rotation of a gradient H of the 3x3 embedding:
    w = (H10 - H01) / 2 and c = sqrt(1 - w^2) (NaN out of range, docs/theory.md section 2.3)."""
    w = 0.5 * (H[1, 0] - H[0, 1])
    return w, ufl.sqrt(1.0 - w * w)


def sr_decomposition_in_plane(H):
    """:func:`sr_decomposition` of a gradient of the 3x3 embedding of a 2D model, whose rotation is
    about the out-of-plane axis (H02 = H12 = H20 = H21 = 0): the same split written with the one
    angle, sin(theta) = w = (H10 - H01) / 2 (docs/theory.md section 2.2, 2D and axisymmetry),

        c = sqrt(1 - w^2),  R = [[c, -w, 0], [w, c, 0], [0, 0, 1]],
        S = sym H + w^2 / (1 + c) diag(1, 1, 0),

    (W.W = -w^2 diag(1, 1, 0), and 1 - w^2 / (1 + c) = c). The general form leaves the zero diagonal
    of skew H as differences x - x that the generated code evaluates, with everything they multiply,
    in the stress evaluation and in the Jacobian (docs/performance.md); here every entry that is zero
    in the embedding is a literal zero. Returns (S, R, c)."""
    w, c = in_plane_angle(H)
    k = w * w / (1.0 + c)
    shear = 0.5 * (H[0, 1] + H[1, 0])
    S = ufl.as_tensor([[H[0, 0] + k, shear, 0], [shear, H[1, 1] + k, 0], [0, 0, H[2, 2]]])
    R = ufl.as_tensor([[c, -w, 0], [w, c, 0], [0, 0, 1]])
    return S, R, c


def increment_gradient(F, F_n):
    """Gradient of the increment relative to configuration n: dH = Grad(du) F_n^-1 = F F_n^-1 - I."""
    n = F.ufl_shape[0]
    return F * ufl.inv(F_n) - ufl.Identity(n)


def polar_rotation_3d(F, steps: int = 6):
    """Rotation of the polar decomposition F = R U of a 3x3 F with det F > 0, by Newton's iteration
    for the orthogonal factor with determinant scaling, unrolled ``steps`` times from R_0 = F:
    R_(k+1) = (g R_k + cof(R_k) / (g det R_k)) / 2 with g = det(R_k)^(-1/3) and cof(R) = det(R) R^-T
    (:func:`cofactor3`, no inverse). The iteration converges quadratically for any F with det F > 0;
    6 steps reach round-off for principal stretch ratios up to about 10 (tests/test_solid3d.py
    checks R^T R = I and the symmetry of R^T F)."""
    R = F
    for _ in range(steps):
        J = ufl.det(R)
        g = J ** (-1.0 / 3.0)
        R = 0.5 * (g * R + cofactor3(R) / (g * J))
    return R


def polar_rotation_2d(F):
    """Rotation of the polar decomposition of the in-plane block of F (closed form in 2D).

    tan(theta_p) = (F10 - F01)/(F00 + F11); returned embedded in 3x3 with R22 = 1.
    """
    a = F[0, 0] + F[1, 1]
    b = F[1, 0] - F[0, 1]
    r = ufl.sqrt(a * a + b * b)
    c, s = a / r, b / r
    return ufl.as_tensor([[c, -s, 0], [s, c, 0], [0, 0, 1]])


# --------------------------------------------------------------------------------------------
# Physical components on the convected base
# --------------------------------------------------------------------------------------------
def physical_components(T, F, kind: str = "contravariant"):
    """Physical components of a Cartesian tensor T on the convected base g_I = F e_I (no sums).

    kind = "contravariant": T<IJ> = T^IJ sqrt(C_II C_JJ), T^IJ = (F^-1 T F^-T)_IJ (components on the
    unit base vectors ``g_I / |g_I|``); "covariant": T_IJ / sqrt(C_II C_JJ), T_IJ = (F^T T F)_IJ (projections
    on the unit base vectors); "mixed": T^I_J sqrt(C_II / C_JJ), T^I_J = (F^-1 T F)_IJ.
    """
    C = metric(F)
    n = T.ufl_shape[0]
    Finv = ufl.inv(F)
    if kind == "contravariant":
        comp, scale = Finv * T * Finv.T, lambda i, j: ufl.sqrt(C[i, i] * C[j, j])
    elif kind == "covariant":
        comp, scale = F.T * T * F, lambda i, j: 1.0 / ufl.sqrt(C[i, i] * C[j, j])
    elif kind == "mixed":
        comp, scale = Finv * T * F, lambda i, j: ufl.sqrt(C[i, i] / C[j, j])
    else:
        raise ValueError(f"unknown kind {kind!r}: contravariant, covariant or mixed")
    return ufl.as_tensor([[comp[i, j] * scale(i, j) for j in range(n)] for i in range(n)])


def fibre_stress(sigma, F, A):
    """Normal stress along the convected fibre a = F A of the reference direction A: a.sigma.a / a.a.

    With A = e_I this is the diagonal covariant physical component; e.g. the fibre stress along the
    deformed beam axis (A = e_x) or the hoop stress of the ring (A = e_theta of the reference).
    """
    a = F * A
    return ufl.dot(a, sigma * a) / ufl.dot(a, a)

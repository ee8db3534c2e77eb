"""Material-point tests: validation, closed forms, tangents, isotropy, Chen against J2 and its rate law.

Stored tensors are (xx, yy, zz, xy) with the tensor shear component; see the module docstring.
"""

import numpy as np
import pytest

from comove_dolfinx.mechanics.material_data import (
    MODELS,
    WEIGHT,
    Elastic,
    Hardening,
    MaterialError,
    deviator,
    von_mises,
)
from comove_dolfinx.mechanics.materials import Chen
from comove_dolfinx.mechanics.return_maps import chen_loading_surface, j2_return

# the ring's mild steel (docs/scenes.md), kg/cm^2
STEEL_EL = Elastic(1.89e6, 0.3)
STEEL = Hardening((0.0, 0.01, 0.05, 0.1, 0.2, 0.5), (2800.0, 3000.0, 3600.0, 4000.0, 4500.0, 5300.0))
# a soft, strongly hardening material: slopes H comparable to G make the laws' differences visible
SOFT = Hardening((0.0, 0.05, 0.2, 0.5), (10.0, 60.0, 120.0, 160.0))
FREE = {"plane_stress": [1], "axisymmetric": [1, 2], "plane_strain": [1, 2]}   # uniaxial xx stress


def update(law, model, el, hd):
    """Return f(sig_n, sig_tr, p_n) -> (sig, p, d sig / d sig_tr) for either law."""
    if law == "j2":
        return lambda y, x, p: j2_return(x, p, el, hd, model)[:3]
    chen = Chen(el.E, el.nu, hd)

    def f(y, x, p):
        out = chen.update(y, x, p, model)
        return out.sig, out.p, out.tangent(model)
    return f


def drive(law, model, el, hd, de_steps, free, sig0=None, p0=0.0):
    """One material point along prescribed strain increments; the ``free`` components have zero stress.

    Returns total strain, stress (both (M, 4)) and p (M,) after each increment. The free strains are
    found by Newton's method with the tangent D C of the law.
    """
    C = el.stiffness(model)
    f = update(law, model, el, hd)
    sig = np.zeros((1, 4)) if sig0 is None else np.array(sig0, dtype=float).reshape(1, 4)
    p, eps = np.array([p0]), np.zeros(4)
    out = []
    for de in np.array(de_steps, dtype=float):
        for _ in range(60):
            s, pp, D = f(sig, sig + de @ C.T, p)
            res = s[0, free]
            if np.abs(res).max(initial=0.0) <= 1e-12 * max(1.0, np.abs(s).max()):
                break
            de[free] -= np.linalg.solve((D[0] @ C)[np.ix_(free, free)], res)
        else:
            raise RuntimeError("material driver did not converge")
        sig, p, eps = s, pp, eps + de
        out.append((eps, sig[0], p[0]))
    return (np.array([o[0] for o in out]), np.array([o[1] for o in out]), np.array([o[2] for o in out]))


def uniaxial_closed_form(eps, el, hd):
    """sigma(eps) of monotonic uniaxial stress: eps = sigma/E + p(sigma), p the inverse of the table."""
    s, p = np.array(hd.stress), np.array(hd.strain)
    knots_eps = np.concatenate([[0.0], s / el.E + p, [10.0]])
    knots_sig = np.concatenate([[0.0], s, [s[-1]]])        # flat beyond the last point
    return np.interp(eps, knots_eps, knots_sig)


def rotate(sig, angle):
    """Rotate stored tensors in the plane: Q sig Q^T with Q the rotation by ``angle`` about z."""
    c, s = np.cos(angle), np.sin(angle)
    xx, yy, zz, xy = sig.T
    return np.stack([c * c * xx + s * s * yy - 2 * c * s * xy, s * s * xx + c * c * yy + 2 * c * s * xy,
                     zz, c * s * (xx - yy) + (c * c - s * s) * xy], axis=1)


def random_trial(rng, n, model, y, factor):
    """n random stresses with sigma_eq = factor * y (zz = 0 in plane stress)."""
    sig = rng.normal(size=(n, 4))
    if model == "plane_stress":
        sig[:, 2] = 0.0
    return sig * (factor * y / von_mises(sig))[:, None]


def fd_tangent(f, x, h, skip_zz):
    """Central differences of f (N,4) -> (N,4) with respect to each stored component of x."""
    D = np.zeros((len(x), 4, 4))
    for j in range(4):
        if skip_zz and j == 2:
            continue
        e = np.zeros(4)
        e[j] = h
        D[:, :, j] = (f(x + e) - f(x - e)) / (2 * h)
    return D


def rel_err(D, D_ref):
    """Largest error per point relative to the point's largest entry, or to 1 (the elastic map) if smaller."""
    return np.abs(D - D_ref).max(axis=(1, 2)) / np.maximum(np.abs(D_ref).max(axis=(1, 2)), 1.0)


# ----------------------------------------------------------------------------------------- validation
@pytest.mark.parametrize("E, nu, msg", [
    (0.0, 0.3, r"E = 0.0 must be"), (-2.0, 0.3, r"E = -2.0 must be"),
    (1.0, 0.5, r"nu = 0.5 must be < 0.5 \(incompressible is not supported"),
    (1.0, 0.7, r"nu = 0.7 must be < 0.5"), (1.0, -1.0, r"nu = -1.0 must be > -1"),
    (1.0, -3.0, r"nu = -3.0 must be > -1")])
def test_elastic_rejects_bad_constants(E, nu, msg):
    with pytest.raises(MaterialError, match=msg):
        Elastic(E, nu)


@pytest.mark.parametrize("strain, stress, msg", [
    ((0.0, 0.1, 0.2), (300.0, 400.0, 350.0), r"row 2: stress\[2\] = 350.0 is less than stress\[1\] = 400.0"),
    ((0.01, 0.1), (300.0, 400.0), r"strain\[0\] = 0.01 must be 0"),
    ((0.0, 0.1), (300.0, 400.0, 500.0), r"2 strains but 3 stresses"),
    ((0.0, 0.2, 0.1), (300.0, 400.0, 500.0), r"row 2: strain\[2\] = 0.1 is not greater than strain\[1\] = 0.2"),
    ((0.0, 0.1, 0.1), (300.0, 400.0, 500.0), r"row 2: strain\[2\]"),
    ((0.0,), (-5.0,), r"stress\[0\] = -5.0 must be > 0"),
    ((), (), r"empty")])
def test_hardening_rejects_bad_tables(strain, stress, msg):
    with pytest.raises(MaterialError, match=msg):
        Hardening(strain, stress)


def test_bad_model_and_plane_stress_zz_rejected():
    with pytest.raises(MaterialError, match="model = 'plane'"):
        j2_return(np.zeros((1, 4)), 0.0, STEEL_EL, STEEL, "plane")
    with pytest.raises(MaterialError, match=r"sigma_zz\) = 0"):
        j2_return([[3000.0, 0.0, 100.0, 0.0]], 0.0, STEEL_EL, STEEL, "plane_stress")


def test_elastic_moduli_and_matrices():
    el = Elastic(210.0, 0.3)
    assert el.mu == pytest.approx(210.0 / 2.6)
    assert el.kappa == pytest.approx(el.lmbda + 2.0 / 3.0 * el.mu)
    assert el.lmbda_plane_stress == pytest.approx(210.0 * 0.3 / (1 - 0.09))
    assert np.allclose(el.stiffness("axisymmetric") @ el.compliance(), np.eye(4))
    inplane = [0, 1, 3]
    C_ps = el.stiffness("plane_stress")[np.ix_(inplane, inplane)]
    assert np.allclose(C_ps @ el.compliance()[np.ix_(inplane, inplane)], np.eye(3))


# ----------------------------------------------------------------------------------------- hardening
def test_hardening_table_functions():
    assert np.allclose(STEEL.sigma_y([0.0, 0.005, 0.05, 0.35, 0.5, 2.0]), [2800, 2900, 3600, 4900, 5300, 5300])
    # right-continuous slopes; zero beyond the table
    assert np.allclose(STEEL.slope([0.0, 0.01, 0.0099, 0.5, 3.0]), [20000, 15000, 20000, 0, 0])
    lin = Hardening.linear(250.0, 1000.0)
    assert np.allclose(lin.sigma_y([0.0, 0.5, 7.0]), [250.0, 750.0, 7250.0]) and lin.slope(3.0) == 1000.0
    assert np.allclose(Hardening.perfect(250.0).sigma_y([0.0, 9.0]), 250.0)


def test_solve_dp_is_the_exact_root():
    rng = np.random.default_rng(1)
    p_n = rng.uniform(0.0, 0.6, 1000)
    three_mu = 3.0 * STEEL_EL.mu
    seq = STEEL.sigma_y(p_n) + rng.uniform(0.0, 1e6, 1000)       # returns up to ~0.4 plastic strain
    dp, H = STEEL.solve_dp(seq, p_n, three_mu)
    assert np.all(dp > 0)
    assert np.allclose(seq - three_mu * dp - STEEL.sigma_y(p_n + dp), 0.0, atol=1e-8 * seq.max())
    assert np.array_equal(H, STEEL.slope(p_n + dp + 1e-12))
    assert np.mean(STEEL.slope(p_n) != H) > 0.3                     # many roots beyond a table point
    # a root exactly on a table point takes the slope of the segment that starts there
    # (binary-exact numbers: the residual vanishes exactly at p = 0.25)
    table = Hardening((0.0, 0.25, 0.5), (100.0, 200.0, 250.0))
    dp, H = table.solve_dp(200.0 + 1024.0 * 0.25, 0.0, 1024.0)
    assert dp == 0.25 and H == 200.0


# ----------------------------------------------------------------------------------------- J2
@pytest.mark.parametrize("model", ["plane_stress", "axisymmetric"])
@pytest.mark.parametrize("steps", [400, 7])
def test_j2_uniaxial_stress_follows_the_table(model, steps):
    """Monotonic uniaxial stress against eps = sigma/E + p(sigma).

    The loading is proportional and the table piecewise linear, so the backward-Euler return is exact for
    any step size (each step solves the piecewise-linear consistency equation exactly); only round-off
    and the 1e-12 tolerance of the lateral-stress iteration remain: 1e-9 relative is asserted.
    """
    de = np.zeros((steps, 4))
    de[:, 0] = 0.7 / steps                   # beyond the last table point (eps = 0.5028)
    eps, sig, p = drive("j2", model, STEEL_EL, STEEL, de, FREE[model])
    assert np.allclose(sig[:, 0], uniaxial_closed_form(eps[:, 0], STEEL_EL, STEEL), rtol=1e-9)
    assert np.allclose(p, eps[:, 0] - sig[:, 0] / STEEL_EL.E, rtol=1e-9, atol=1e-14)
    assert np.abs(sig[:, 1:]).max() < 1e-8 * sig[:, 0].max()


@pytest.mark.parametrize("model", MODELS)
def test_j2_tangent_matches_finite_differences(model):
    rng = np.random.default_rng(2)
    n = 400
    p_n = rng.uniform(0.0, 0.6, n)
    p_n[::2] = rng.choice(STEEL.strain[1:], n // 2) - rng.uniform(0.0, 1e-3, n // 2)   # just below a point
    y = STEEL.sigma_y(p_n)
    sig_tr = random_trial(rng, n, model, y, 1.0 + rng.uniform(0.01, 2.0, n))
    f = lambda x: j2_return(x, p_n, STEEL_EL, STEEL, model)[0]     # noqa: E731
    sig, p, D, _ = j2_return(sig_tr, p_n, STEEL_EL, STEEL, model)
    assert np.mean(STEEL.slope(p) != STEEL.slope(p_n)) > 0.2      # returns that cross a table point
    D_fd = fd_tangent(f, sig_tr, 1e-3, model == "plane_stress")
    assert rel_err(D, D_fd).max() < 1e-6
    # elastic points: identity (zz row and column zero in plane stress)
    D_el = j2_return(random_trial(rng, n, model, y, 0.99), p_n, STEEL_EL, STEEL, model)[2]
    eye = np.diag([1.0, 1.0, 0.0, 1.0]) if model == "plane_stress" else np.eye(4)
    assert np.array_equal(D_el, np.broadcast_to(eye, D_el.shape))


@pytest.mark.parametrize("model", MODELS)
def test_j2_lands_on_the_yield_surface(model):
    rng = np.random.default_rng(3)
    p_n = rng.uniform(0.0, 0.7, 500)
    sig_tr = random_trial(rng, 500, model, STEEL.sigma_y(p_n), rng.uniform(1.0, 4.0, 500))
    sig, p, _, deps_p = j2_return(sig_tr, p_n, STEEL_EL, STEEL, model)
    assert np.allclose(von_mises(sig), STEEL.sigma_y(p), rtol=1e-12)
    # plastic incompressibility, plastic work sigma_eq dp = sigma : deps_p, and deps_p = S (sig_tr - sig)
    assert np.allclose(deps_p[:, 2], -(deps_p[:, 0] + deps_p[:, 1]), atol=1e-15)
    work = np.einsum("ni,ni->n", sig * [1, 1, 1, 2], deps_p)
    assert np.allclose(work, von_mises(sig) * (p - p_n), rtol=1e-10)
    inplane = [0, 1, 3] if model == "plane_stress" else [0, 1, 2, 3]
    elastic_part = (sig_tr - sig) @ STEEL_EL.compliance().T
    assert np.allclose(deps_p[:, inplane], elastic_part[:, inplane], rtol=1e-9, atol=1e-14)
    if model == "plane_stress":
        assert np.all(sig[:, 2] == 0.0)


@pytest.mark.parametrize("model", ["plane_strain", "plane_stress"])
@pytest.mark.parametrize("law", ["j2", "chen"])
def test_isotropy_in_plane(model, law):
    rng = np.random.default_rng(4)
    p_n = rng.uniform(0.0, 0.3, 200)
    y = STEEL.sigma_y(p_n)
    sig_n = random_trial(rng, 200, model, y, rng.uniform(0.7, 1.0, 200))
    sig_tr = sig_n + random_trial(rng, 200, model, y, 0.8)
    f = update(law, model, STEEL_EL, STEEL)
    sig, p, _ = f(sig_n, sig_tr, p_n)
    assert np.mean(p > p_n) > 0.3
    for angle in (0.3, 2.0, -1.1):
        sig_q, p_q, _ = f(rotate(sig_n, angle), rotate(sig_tr, angle), p_n)
        assert np.allclose(sig_q, rotate(sig, angle), rtol=1e-10, atol=1e-9 * y.max())
        assert np.allclose(p_q, p, rtol=1e-10, atol=1e-15)


def test_plane_stress_return_equals_3d_return_with_zero_zz_stress():
    """The plane-stress return (Simo-Taylor, piecewise-linear table) against the 3D radial return with eps_zz
    iterated until sigma_zz = 0: both are the same closest-point projection, so they agree to round-off."""
    de = np.tile([1.0, 0.4, 0.0, 0.6], (8, 1)) * 0.02      # large non-proportional-in-stress steps
    _, sig_ps, p_ps = drive("j2", "plane_stress", STEEL_EL, STEEL, de, [])
    _, sig_3d, p_3d = drive("j2", "axisymmetric", STEEL_EL, STEEL, de, [2])
    assert np.allclose(sig_ps, sig_3d, rtol=1e-9, atol=1e-9 * np.abs(sig_3d).max())
    assert np.allclose(p_ps, p_3d, rtol=1e-9)
    assert p_ps[-1] > 0.2                                 # several table points crossed


# ----------------------------------------------------------------------------------------- Chen
def chen_rate_law(el, hd, de_total, substeps):
    """Chen's rate law s_dot = 2G [e_dot - beta (s:e_dot) s / (s:s)], beta = 1 - E_t(p) / (3G), with an
    elastic volumetric part and sigma_eq p_dot = beta (s:e_dot), integrated by forward Euler in many
    substeps along prescribed strain increments (all four components, plane strain or axisymmetry;
    a monotone path: once on the surface, plastic while s:e_dot > 0). Independent of the return maps."""
    C, G = el.stiffness("plane_strain"), el.mu
    sig, p, plastic, out = np.zeros(4), 0.0, False, []
    for de in np.asarray(de_total, dtype=float):
        d = de / substeps
        for _ in range(substeps):
            s = deviator(sig)
            seq = np.sqrt(1.5 * np.sum(WEIGHT * s * s))
            plastic = plastic or seq >= hd.sigma_y(0.0)
            a = np.sum(WEIGHT * s * d)
            dsig = d @ C.T
            if plastic and a > 0.0:
                h = hd.slope(p)
                beta = 1.0 - el.E * h / (el.E + h) / (3.0 * G)
                dsig -= 2.0 * G * beta * a * s / np.sum(WEIGHT * s * s)
                p += beta * a / seq
            sig = sig + dsig
        out.append((sig.copy(), p))
    return np.array([o[0] for o in out]), np.array([o[1] for o in out])


@pytest.mark.parametrize("model", ["plane_strain", "axisymmetric"])
def test_chen_integrates_its_rate_law(model):
    """The implicit Chen update against its rate law integrated in 4000 substeps per increment (converged
    to 1e-5), on a path that turns (stretch, then shear on top). First order: the largest stress error,
    relative to the stress, measured 1.7e-2 with 20 increments and 1.8e-3 with 200; p within 6e-3 and
    1e-3 of its final value. The soft table (slopes H near G) and nu = 0.3 put Chen's loading surface
    well below the table: J2 on the table misses the rate law by 5.7 %, so the test tells the two apart."""
    el = Elastic(1000.0, 0.3)
    path = np.concatenate([np.tile([0.1, -0.05, 0.0, 0.0], (10, 1)), np.tile([0.0, 0.0, 0.0, 0.1], (10, 1))]) / 10
    ref, p_ref = chen_rate_law(el, SOFT, path, 4000)
    scale = np.linalg.norm(ref, axis=1)
    errs = []
    for refine, p_tol in ((1, 1e-2), (10, 2e-3)):
        de = np.repeat(path, refine, axis=0) / refine
        _, s, p = drive("chen", model, el, SOFT, de, [])
        s, p = s[refine - 1::refine], p[refine - 1::refine]
        errs.append(np.max(np.linalg.norm(s - ref, axis=1) / scale))
        assert np.abs(p - p_ref).max() < p_tol * p_ref[-1]
    assert errs[0] < 0.03 and errs[1] < 0.15 * errs[0]
    _, s_j2, _ = drive("j2", model, el, SOFT, path, [])
    assert np.max(np.linalg.norm(s_j2 - ref, axis=1) / scale) > 0.03
    assert p_ref[-1] > 0.1


def test_chen_loading_surface_slopes():
    """Y' = 3G E_t / (3G - E_t) segment by segment (E_t = E H / (E + H)); the table itself when E = 3G."""
    el = Elastic(1000.0, 0.3)
    Y = chen_loading_surface(el, SOFT)
    p0, s0, h = SOFT.segments
    E_t = 1000.0 * h / (1000.0 + h)
    assert np.allclose(Y.segments[2], 3 * el.mu * E_t / (3 * el.mu - E_t), rtol=1e-14)
    assert Y.strain == SOFT.strain and Y.stress[0] == SOFT.stress[0]
    assert np.all(np.diff(Y.stress) < np.diff(SOFT.stress))         # below the table for nu < 0.5
    near = chen_loading_surface(Elastic(1000.0, 0.4999999), SOFT)
    assert np.allclose(near.stress, SOFT.stress, rtol=1e-6)


@pytest.mark.parametrize("model", MODELS)
def test_chen_tangent_matches_finite_differences(model):
    rng = np.random.default_rng(5)
    n = 400
    p_n = rng.uniform(0.0, 0.6, n)
    chen = Chen(STEEL_EL.E, STEEL_EL.nu, STEEL)
    y = chen.surface.sigma_y(p_n)
    sig_tr = random_trial(rng, n, model, y, rng.uniform(0.5, 1.6, n))
    out = chen.update(sig_tr, sig_tr, p_n, model)
    assert np.sum(out.p > p_n) > 100 and np.sum(out.p == p_n) > 40
    assert np.allclose(von_mises(out.sig[out.p > p_n]), chen.surface.sigma_y(out.p[out.p > p_n]), rtol=1e-10)
    D_fd = fd_tangent(lambda x: chen.update(x, x, p_n, model).sig, sig_tr, 1e-3, model == "plane_stress")
    assert rel_err(out.tangent(model), D_fd).max() < 1e-6


@pytest.mark.parametrize("path", ["uniaxial", "biaxial_ps", "biaxial_3d"])
def test_chen_equals_j2_for_incompressible_elasticity(path):
    """Theory 4.4: with E = 3G (nu -> 0.5) Chen's beta equals the J2 value 3G/(3G + H), so the two laws
    agree at the same increments. Soft, strongly hardening material (H up to 2.6 G), 20 increments to
    eps_xx = 0.2: measured largest difference 4e-5 of |sigma| and 5e-5 in p, the remainder of nu = 0.4999
    (it does not change with 500 increments)."""
    el = Elastic(1000.0, 0.4999)
    m = 20
    model, free, direction = {"uniaxial": ("plane_stress", [1], [1.0, 0.0, 0.0, 0.0]),
                              "biaxial_ps": ("plane_stress", [], [1.0, 0.5, 0.0, 0.2]),
                              "biaxial_3d": ("axisymmetric", [2], [1.0, 0.5, 0.0, 0.2])}[path]
    de = np.tile(direction, (m, 1)) * 0.2 / m
    _, s_j2, p_j2 = drive("j2", model, el, SOFT, de, free)
    _, s_ch, p_ch = drive("chen", model, el, SOFT, de, free)
    scale = np.linalg.norm(s_j2, axis=1)
    assert np.all(np.linalg.norm(s_ch - s_j2, axis=1) < 1e-4 * scale)
    assert np.allclose(p_ch, p_j2, rtol=1e-4, atol=1e-8)
    assert p_j2[-1] > 0.1


@pytest.mark.parametrize("model", ["plane_stress", "axisymmetric"])
@pytest.mark.parametrize("law", ["j2", "chen"])
def test_elastic_unloading_after_plastic_loading(model, law):
    load = np.zeros((40, 4))
    load[:, 0] = 0.03 / 40
    eps, sig, p = drive(law, model, STEEL_EL, STEEL, load, FREE[model])
    assert p[-1] > 0.02
    unload = -0.25 * load[:5]                 # 0.6 of the elastic range, no reverse yielding
    eps_u, sig_u, p_u = drive(law, model, STEEL_EL, STEEL, unload, FREE[model], sig0=sig[-1], p0=p[-1])
    slope = np.diff(np.concatenate([[sig[-1, 0]], sig_u[:, 0]])) / unload[:, 0]
    assert np.allclose(slope, STEEL_EL.E, rtol=1e-9)
    assert np.all(p_u == p[-1])

"""The stability map's pieces (comove_dolfinx/stability/, docs/stability.md): the cause classifier,
the chatter test, and the Jaumann simple-shear case against its closed forms (Dienes 1979)."""
import numpy as np
import pytest

from comove_dolfinx import stability as st


@pytest.mark.parametrize("message, diagnosis, chatter, cause", [
    ("stopped at load factor 0.5: an increment of the smallest size (0.0016, after 6 cut-backs in a row) "
     "failed: no convergence in 25 iterations", None, False, st.NO_CONVERGENCE),
    ("stopped at load factor 0.5: ... failed: no convergence in 25 iterations", None, True, st.CHATTER),
    ("stopped at load factor 0.1: ... failed: diverged (|R| = 1.2e+20)", None, False, st.DIVERGED),
    ("stopped at load factor 0: ... failed: det F = -21.7 <= 0 at a quadrature point", None, False, st.INVERTED),
    ("stopped at load factor 0.2: ... failed: det F = -0.01 <= 0 at a node: an element folds (increment "
     "too large, or the body folds)", None, False, st.INVERTED),
    ("stopped at load factor 0: ... failed: the stress update returned NaN (increment too large?)",
     None, False, st.NAN),
    ("... failed: the stress update returned NaN (increment too large?)", st.SR_RANGE, False, st.SR_RANGE),
    ("... failed: the stress update returned NaN (increment too large?)", st.INVERTED, False, st.INVERTED),
    ("... failed: the constitutive update failed: plane-stress return mapping did not converge",
     None, False, st.RETURN_MAP),
    ("... failed: linear solve: the linear solver failed (PETSc KSP reason -11)", None, False, st.LINEAR),
    ("... failed: the Newton correction is not finite (singular tangent?)", None, False, st.LINEAR),
    ("something else entirely", None, False, st.OTHER),
])
def test_classify(message, diagnosis, chatter, cause):
    assert st.classify(message, diagnosis, chatter) == cause


def test_cycling():
    a, b, c = (1, 2), (1, 2, 3), (2, 3)
    assert st.is_cycling([a, b, a, b, a, b])
    assert st.is_cycling([c, c, a, b, a, c])
    assert not st.is_cycling([a, a, a, a, a])             # settled
    assert not st.is_cycling([a, b, c, (4,), (5,), (6,)])   # moving on, never back
    assert not st.is_cycling([a, b, a])                   # too few changes


def test_green_naghdi_closed_form():
    """docs/theory.md 3.4 table; small gamma: sigma_12 = G gamma."""
    g = np.array([0.5, 1.0, 2.0, 4.0, 8.0])
    np.testing.assert_allclose(st.green_naghdi_shear(g), [0.48051, 0.86978, 1.38629, 2.31794, 5.04602],
                               atol=1e-5)
    assert st.green_naghdi_shear(1e-4) == pytest.approx(1e-4, rel=1e-6)
    assert st.first_decrease(np.linspace(0, 10, 1001), st.green_naghdi_shear(np.linspace(0, 10, 1001))) is None


def test_first_decrease():
    g = np.linspace(0.0, 4.0, 401)
    assert st.first_decrease(g, np.sin(g)) == pytest.approx(np.pi / 2, abs=0.01)
    assert st.first_decrease(g, g) is None


def _curve(update, gamma, n, **kw):
    res = st.simple_shear(update, gamma, n, **kw)
    return np.array([0.0, *res["load"]]), np.array([0.0, *res["s12"]]), res


def test_hughes_winget_simple_shear_is_jaumann():
    """Up to gamma = 3 the Hughes-Winget update follows sigma_12 = G sin(gamma) within 0.04 at
    dgamma = 0.03 (first order: the error halves with the increment) and turns down after pi/2."""
    g, s, res = _curve("hughes_winget", 3.0, 100)
    assert res.completed
    err = np.max(np.abs(s - np.sin(g)))
    assert err < 0.04
    g2, s2, _ = _curve("hughes_winget", 3.0, 50)
    err2 = np.max(np.abs(s2 - np.sin(g2)))
    assert err2 / err == pytest.approx(2.0, rel=0.15)
    assert st.first_decrease(g, s) == pytest.approx(np.pi / 2, abs=0.1)


def test_green_naghdi_simple_shear_is_monotone():
    """The polar (Green-Naghdi) update: sigma_12 rises monotonically up to gamma = 3 and follows
    Dienes's closed form within 2e-3 at dgamma = 0.05."""
    g, s, res = _curve("polar", 3.0, 60)
    assert res.completed
    assert st.first_decrease(g, s) is None
    assert np.max(np.abs(s - st.green_naghdi_shear(g))) < 2e-3


def test_sr_split_out_of_range_in_shear():
    """One shear increment of 2.5 (sin theta = 1.25 > 1): the S-R update has no split; Newton's
    iterates stay beyond the range and the failure is put down to the S-R split. With cut-backs the
    same run completes."""
    rec = st.Recorder()                   # Newton's monitor
    res = st.simple_shear("sr", 2.5, 1, max_cutbacks=0, monitor=rec)
    assert not res.completed
    assert rec.max_omega2 > 1.0           # at the last iterate Newton tried (its line search halves)
    assert st.classify(res.message, rec.nan_diagnosis) == st.SR_RANGE
    res = st.simple_shear("sr", 2.5, 1, max_cutbacks=2)
    assert res.completed and sum(i.cutbacks for i in res.increments) == 1


@pytest.mark.parametrize("scene", ["elastica", "beam", "plate", "ring"])
def test_grid_uses_the_scenes_parameters(scene):
    """Every cell of a scene's grid is a valid --set combination of that scene."""
    from comove_dolfinx.presets import get_scene
    for panel in st.panels(scene):
        for _, rsets in panel.rows:
            for _, csets in panel.columns:
                get_scene(scene, rsets + csets)

"""The stability map's pieces (comove_dolfinx/stability/, docs/stability.md): the cause classifier,
the chatter test, and the Jaumann simple-shear case against its closed forms (Dienes 1979)."""
import numpy as np
import pytest

from comove_dolfinx import stability as st


def _square(update="sr", material=None, newton=None, **step):
    """A unit square of four P1 triangles in plane strain, clamped at the bottom, its top moved
    down by 1.5 (more than its height) in one increment without cut-backs: a run that fails, with
    the message the increment loop really writes."""
    import comove_dolfinx as cm
    md = cm.rectangle(1.0, 1.0, 1.0, order=1)
    body = cm.Body(md, "plane_strain", material or cm.Elastic(1.0, 0.3), update=update, degree=1)
    items = [cm.Fixed("bottom"), cm.Displacement("top", (0.0, -1.5))]
    res = cm.Job(body, items, [cm.Step(1, max_cutbacks=0, **step)], newton=newton).run()
    assert not res.completed and res.message.startswith("stopped at load factor 0")
    return res


def test_classify_the_solvers_own_messages(monkeypatch):
    """Each cause from a failure provoked on a small problem, so that a reworded message in the
    solver, which the classifier would no longer recognise (and put down as OTHER), fails here."""
    import comove_dolfinx as cm
    from comove_dolfinx.mechanics.state import QuadratureState

    # Newton stopped by its iteration limit, then by its divergence test; the same limit with the
    # contact sets cycling is chatter
    res = _square("svk", newton=cm.NewtonSettings(max_it=1, line_search="none"))
    assert st.classify(res.message) == st.NO_CONVERGENCE
    assert st.classify(res.message, chatter=True) == st.CHATTER
    res = _square("svk", newton=cm.NewtonSettings(divergence=1e-6, line_search="none"))
    assert st.classify(res.message) == st.DIVERGED
    # the element turned inside out: det F < 0 at a quadrature point (St Venant-Kirchhoff's stress
    # stays finite there); neo-Hooke's log J is NaN first, which the monitor puts down to det F
    res = _square("svk", newton=cm.NewtonSettings(line_search="none"), predictor="linear")
    assert st.classify(res.message) == st.INVERTED
    rec = st.Recorder()
    res = _square("neo_hooke", newton=cm.NewtonSettings(line_search="none", monitor=rec),
                  predictor="linear")
    assert st.classify(res.message) == st.NAN
    assert rec.nan_diagnosis == st.INVERTED and st.classify(res.message, rec.nan_diagnosis) == st.INVERTED
    # an iterative linear solver held to one iteration: PETSc's reason is negative
    opts = {"ksp_type": "gmres", "pc_type": "none", "ksp_max_it": 1, "ksp_rtol": 1e-12}
    res = _square("svk", newton=cm.NewtonSettings(petsc_options=opts))
    assert st.classify(res.message) == st.LINEAR

    # any error of a material's update (here the quadrature state's, whatever it says)
    def broken(self, *args, **kwargs):
        raise RuntimeError("a material's own words")
    monkeypatch.setattr(QuadratureState, "evaluate", broken)
    res = _square("sr")
    assert st.classify(res.message) == st.RETURN_MAP


def test_classify_the_diagnosis_and_the_rest():
    """The monitor's diagnosis of a NaN decides its cause; a message of no known failure is OTHER."""
    nan = "stopped at load factor 0: ... failed: the stress update returned NaN (increment too large?)"
    assert st.classify(nan, st.SR_RANGE) == st.SR_RANGE and st.classify(nan, None) == st.NAN
    assert st.classify("something else entirely") == st.OTHER


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

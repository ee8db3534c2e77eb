"""Elastic-plastic bodies through the production Model: objectivity of a plastic state under rigid
rotation (exact), and the limit pressure of a thick-walled cylinder (Hill's closed form)."""
import math

import numpy as np
import pytest
import ufl
from mpi4py import MPI

from comove_dolfinx import geometry
from comove_dolfinx.loads import Fixed, Pressure
from comove_dolfinx.mechanics import return_maps, return_maps_ufl
from comove_dolfinx.mechanics.body import Body
from comove_dolfinx.mechanics.kinematics import to_vec
from comove_dolfinx.mechanics.materials import Hardening, as_material
from comove_dolfinx.mechanics.model import Model
from comove_dolfinx.solver import IncrementalSolver, StepSettings


def _rot(a):
    return np.array([[math.cos(a), -math.sin(a)], [math.sin(a), math.cos(a)]])


@pytest.mark.parametrize("update", ["sr", "hughes_winget"])
@pytest.mark.parametrize("law", ["j2", "chen"])
def test_rigid_rotation_keeps_plastic_state(tmp_path, law, update):
    """A block stretched 2 % in plane strain (yield strain 0.1 %), then turned by 90 degrees in three
    rigid increments: the stress turns with it exactly and the plastic strain does not grow."""
    md = geometry.rectangle(1.0, 1.0, 0.5, order=2, comm=MPI.COMM_SELF, cache_dir=str(tmp_path))
    hard = Hardening((0.0, 0.05), (1.0, 1.5))
    m = Model(Body(md, "plane_strain", as_material(1000.0, 0.3, law, hard), update=update))
    m.finalize()
    F = np.diag([1.02, 0.99])
    states = []
    for a in (0.0, 30.0, 60.0, 90.0):
        A = _rot(math.radians(a)) @ F - np.eye(2)
        m.u.interpolate(lambda x: A @ x[:2])
        m.evaluate_stress()
        states.append((m.cauchy_stress().copy(), m.p.x.array.copy()))
        m.commit()
    (s0, p0), (s1, p1) = states[0], states[-1]
    assert p0.min() > 0.01                                   # plastic before the rotation
    Q = np.eye(3)
    Q[:2, :2] = _rot(math.pi / 2)
    for a, b in zip(s0, s1):
        T = np.array([[a[0], a[3], 0], [a[3], a[1], 0], [0, 0, a[2]]])
        R = Q @ T @ Q.T
        assert b == pytest.approx([R[0, 0], R[1, 1], R[2, 2], R[0, 1]], abs=1e-12 * abs(a).max())
    assert p1 == pytest.approx(p0, abs=1e-14)


@pytest.mark.mpi
@pytest.mark.parametrize("update", ["sr", "hughes_winget"])
def test_thick_cylinder_limit_pressure(mpi_tmp, update):
    """Elastic-perfectly plastic tube a = 1, b = 2 under internal pressure, plane strain: the largest
    pressure it carries is (2/sqrt(3)) sigma_0 ln(b/a) (Hill, The Mathematical Theory of Plasticity,
    1950, ch. V). E/sigma_0 = 1000 keeps the geometry change at collapse to a few 1e-3."""
    a, b, s0 = 1.0, 2.0, 1.0
    p_lim = 2.0 / math.sqrt(3.0) * s0 * math.log(b / a)
    md = geometry.annulus_sector(a, b, 0.25, order=2, comm=MPI.COMM_WORLD, cache_dir=str(mpi_tmp))
    items = [Fixed("xsym", component=0), Fixed("ysym", component=1), Pressure("inner", 1.05 * p_lim)]
    m = Model(Body(md, "plane_strain", as_material(1000.0, 0.3, "j2", Hardening.perfect(s0)), update=update),
              items)
    m.finalize()
    res = IncrementalSolver(m, StepSettings(n_increments=10, max_cutbacks=6)).run()
    assert not res.completed                                 # 5 % above the limit: no equilibrium
    carried = res.increments[-1].load * 1.05 * p_lim
    assert 0.985 * p_lim < carried <= 1.002 * p_lim
    assert m.p_n.x.array.min() > 0.0                         # the whole wall has yielded


def _tangent_from_state(m) -> np.ndarray:
    """D = d sigma / d sigma_tr at the points, (points, 4, 4), as the Jacobian applies it: from the
    stored stress and plastic strains (Plastic.tangent_times applied to the unit 4-vectors)."""
    st = m.state
    table = return_maps_ufl.Table.of(m.plastic.surface)
    cols = [m.plastic.tangent_times(st.sigma, st.p, st.p_n, ufl.as_vector([float(k == j) for k in range(4)]),
                                    m.kin.model, m.constants, table) for j in range(4)]
    expr = m.rule.expression(ufl.as_vector([cols[j][i] for i in range(4) for j in range(4)]))
    return m.rule.evaluate(expr).reshape(-1, 4, 4)


@pytest.mark.parametrize("kind, law", [("plane_strain", "j2"), ("plane_strain", "chen"),
                                       ("axisymmetric", "j2"), ("axisymmetric", "j2_saturation")])
def test_compiled_return_map_equals_numpy(tmp_path, kind, law):
    """The return map compiled into the stress evaluation and the NumPy one give the same stress and
    plastic strain at every point, on a history that has points on several segments of the table,
    points unloading and points still elastic; and the Jacobian's D, applied from that stored state,
    is NumPy's D of the return from the trial stress (return_maps.j2_return: theta, c and n from
    the trial's q and the root's segment)."""
    md = geometry.rectangle(1.0, 1.0, 0.25, order=2, x0=0.5 if kind == "axisymmetric" else 0.0,
                            comm=MPI.COMM_SELF, cache_dir=str(tmp_path))
    hard = Hardening((0.0, 0.01, 0.03, 0.08), (1.0, 1.3, 1.5, 1.6))
    if law == "j2_saturation":        # the necking bar's law, scaled: Newton's iteration in the return
        law, hard = "j2", Hardening.saturation(1.0, 0.29, 0.59, 16.93)
    models = []
    for compiled in (True, False):
        m = Model(Body(md, kind, as_material(1000.0, 0.3, law, hard)))
        m.finalize(compiled_return=compiled)
        models.append(m)
    states = []
    for m in models:
        out = []
        # stretched non-uniformly, then partly back: a spread of plastic strains, some unloading
        for b in (0.2, 0.1, 0.3):                     # no strain where x < x0 + 0.4
            r = lambda x: np.maximum(x[0] - md.mesh.geometry.x[:, 0].min() - 0.4, 0.0)  # noqa: E731
            m.u.interpolate(lambda x: np.vstack([b * r(x) ** 3, -b * r(x) ** 2 * x[1]]))
            m.evaluate_stress()
            D = _tangent_from_state(m)
            # the trial stress of the increment (the converged state not yet moved on)
            up = m.update.build(m.u, m.u_n, m.sigma_n)
            sig_tr = m.rule.evaluate(m.rule.expression(to_vec(up.sigma)))
            out.append((m.cauchy_stress().copy(), m.p.x.array.copy(), m.p_n.x.array.copy(), D, sig_tr))
            m.commit()
        states.append(out)
    mixed = []
    for (s1, p1, pn1, D1, sig_tr), (s2, p2, _, D2, _) in zip(*states):
        scale = np.abs(s2).max()
        assert s1 == pytest.approx(s2, abs=1e-12 * scale)
        assert p1 == pytest.approx(p2, abs=1e-14)
        _, p_np, D_np, _ = return_maps.j2_return(sig_tr, pn1, models[1].plastic.elastic,
                                                 models[1].plastic.surface, kind)
        assert p_np == pytest.approx(p2, abs=1e-14)
        assert D1 == pytest.approx(D_np, abs=1e-9)
        assert D2 == pytest.approx(D_np, abs=1e-9)
        yielding = p2 > pn1
        unloading = (pn1 > 0) & ~yielding        # plastic before, elastic in this increment
        mixed.append((yielding.any(), (~yielding).any(), unloading.any()))
        assert np.abs(D_np[yielding] - np.eye(4)).max() > 0.1   # the yielding points' D is not elastic
    assert mixed[0][:2] == (True, True) and mixed[1] == (True, True, True)
    p_end = states[1][-1][1]
    if hard.smooth:                   # well into the saturation term's curvature
        assert hard.delta * p_end.max() > 1.0
    else:
        assert np.unique(np.searchsorted(hard.strain, p_end[p_end > 0])).size >= 3   # several segments

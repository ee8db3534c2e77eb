"""Elastic-plastic bodies through the production Model: objectivity of a plastic state under rigid
rotation (exact), and the limit pressure of a thick-walled cylinder (Hill's closed form)."""
import math

import numpy as np
import pytest
from mpi4py import MPI

from comove_dolfinx import geometry
from comove_dolfinx.loads import Fixed, Pressure
from comove_dolfinx.mechanics.body import Body
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
    res = IncrementalSolver(m, StepSettings(n_steps=10, max_cutbacks=6)).run()
    assert not res.completed                                 # 5 % above the limit: no equilibrium
    carried = res.increments[-1].load * 1.05 * p_lim
    assert 0.985 * p_lim < carried <= 1.002 * p_lim
    assert m.p_n.x.array.min() > 0.0                         # the whole wall has yielded

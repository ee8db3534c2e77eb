"""Plane-stress J2 plasticity at finite strain against closed forms (and against plane strain).

* A strip stretched 5 % in plane stress along the ring's hardening table: the state is uniform, so
  sigma_xx = sigma_y(p) with p = ln(lambda) - sigma_xx / E, the lateral and thickness log-strains are
  -nu sigma / E - p / 2 (plastic incompressibility), and the end force per unit reference thickness is
  sigma_xx lambda_y lambda_z h. The update integrates the strain as the sum of the S-R increments
  lambda_k+1 / lambda_k - 1, which differs from ln(lambda) by at most sum (dlambda/lambda)^2 / 2 =
  1.3e-4 with 10 increments: that bounds the tolerances below.
* Pure bending of an elastic-perfectly plastic strip to many times its yield curvature: the moment
  tends to the fully plastic moment sigma_0 t^2 / 4 in plane stress and (2 / sqrt 3) sigma_0 t^2 / 4 in
  plane strain (with plastic incompressibility and eps_zz = 0 the fibres carry sigma_zz = sigma_xx / 2,
  and yield at sigma_xx = (2 / sqrt 3) sigma_0); with an elastic core of 1/40 of the half depth the
  moment is 1 - (1/40)^2 / 3 of it.
"""
import math

import numpy as np
import pytest
from mpi4py import MPI

from comove_dolfinx import geometry
from comove_dolfinx.loads import Displacement, Fixed
from comove_dolfinx.mechanics.body import Body
from comove_dolfinx.mechanics.materials import J2, Elastic, Hardening
from comove_dolfinx.mechanics.model import Model
from comove_dolfinx.presets.scenes import RING_HARDENING, parse_table
from comove_dolfinx.solver import IncrementalSolver, NewtonSettings, StepSettings

E, NU = 1.89e6, 0.3


@pytest.mark.mpi
def test_strip_tension_follows_the_table_with_its_thickness(mpi_tmp):
    L, h, stretch = 2.0, 0.5, 1.05
    table = parse_table(RING_HARDENING)
    md = geometry.rectangle(L, h, 0.25, order=2, comm=MPI.COMM_WORLD, cache_dir=str(mpi_tmp))
    items = [Fixed("left", component=0), Fixed("bottom", component=1),
             Displacement("right", (stretch - 1.0) * L, component=0)]
    m = Model(Body(md, "plane_stress", J2(E, NU, table)), items)
    m.finalize()
    res = IncrementalSolver(m, StepSettings(n_increments=10)).run()
    assert res.completed, res.message
    # closed form: sigma = sigma_y(ln(lambda) - sigma / E), solved by fixed point (E is large)
    sigma = table.sigma_y(0.0)
    for _ in range(50):
        sigma = float(table.sigma_y(math.log(stretch) - sigma / E))
    p = math.log(stretch) - sigma / E
    lateral = -NU * sigma / E - p / 2
    sig = m.cauchy_stress()
    np.testing.assert_allclose(sig[:, 0], sigma, rtol=1e-3)               # 15000 x 1.3e-4 / 3600
    assert np.abs(sig[:, 1:]).max() < 1e-6 * sigma
    np.testing.assert_allclose(m.p.x.array, p, rtol=5e-3)                 # 1.3e-4 / 0.048
    np.testing.assert_allclose(np.log(m.F22_n.x.array), lateral, rtol=5e-3)
    # lateral in-plane contraction: the top edge moves by h (exp(lateral) - 1)
    uy = m.u.x.array.reshape(-1, 2)[:, 1].min()
    uy = m.comm.allreduce(uy, op=MPI.MIN)
    assert uy == pytest.approx(h * (math.exp(lateral) - 1.0), rel=5e-3)
    force = m.reaction("right")[0]
    assert force == pytest.approx(sigma * math.exp(2 * lateral) * h, rel=2e-3)


def _bending_moment(kind, cache_dir):
    """Moment (per unit thickness) at the rotated end of a strip t = 0.1, L = 0.25 (symmetry at
    x = 0), elastic-perfectly plastic with E / sigma_0 = 10^4, bent to 40 yield curvatures. The end
    turns about its centre, which stays put, so the mid-fibre's chord is held: its stretch
    theta^2 / 6 moves the neutral axis by kappa L^2 / (3 t) = 1.7 % of the half depth (0.03 % of M).
    Fully yielded sections make the tangent nearly singular along the hinge mechanism, so increments
    start from the path's tangent and corrections are scaled by the energy line search."""
    t, L, s0 = 0.1, 0.25, 1.0
    el = Elastic(1e4, NU)
    Ep = el.E / (1 - NU ** 2) if kind == "plane_strain" else el.E
    k = 2 / math.sqrt(3) if kind == "plane_strain" else 1.0
    kappa = 40.0 * k * s0 / Ep / (t / 2)                    # elastic core 1/40 of the half depth
    theta = kappa * L
    md = geometry.rectangle(L, t, t / 8, order=2, comm=MPI.COMM_WORLD, cache_dir=cache_dir)
    fixed = Fixed("left", component=0)         # symmetry; free in y, so no shear force
    c = np.array([L, t / 2])

    def rotation(x, s):
        a = s * theta
        dx, dy = x[0] - c[0], x[1] - c[1]
        return np.vstack([(math.cos(a) - 1) * dx - math.sin(a) * dy,
                          math.sin(a) * dx + (math.cos(a) - 1) * dy])

    m = Model(Body(md, kind, J2(el.E, el.nu, Hardening.perfect(s0))),
              [fixed, Displacement("right", field=rotation)])
    m.finalize()
    res = IncrementalSolver(m, StepSettings(n_increments=8, predictor="tangent"),
                            NewtonSettings(line_search="energy")).run()
    assert res.completed, res.message
    X, f = m.reaction_forces("right")
    Q = np.array([[math.cos(theta), -math.sin(theta)], [math.sin(theta), math.cos(theta)]])
    x = c + (X - c) @ Q.T                   # the end's nodes now: rigidly rotated about c
    local = np.sum((x[:, 0] - c[0]) * f[:, 1] - (x[:, 1] - c[1]) * f[:, 0])
    return abs(m.comm.allreduce(local, op=MPI.SUM)), k * s0 * t ** 2 / 4


@pytest.mark.mpi
def test_pure_bending_reaches_the_fully_plastic_moment(mpi_tmp):
    M_ps, Mp_ps = _bending_moment("plane_stress", str(mpi_tmp))
    M_pe, Mp_pe = _bending_moment("plane_strain", str(mpi_tmp))
    core = 1 - (1 / 40) ** 2 / 3
    assert M_ps == pytest.approx(core * Mp_ps, rel=1e-2)
    assert M_pe == pytest.approx(core * Mp_pe, rel=1e-2)
    assert M_pe / M_ps == pytest.approx(2 / math.sqrt(3), rel=1e-2)

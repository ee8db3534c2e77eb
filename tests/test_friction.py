"""Frictional Hertz contact at the defaults: a half-cylinder pressed onto a rigid flat, then the flat
slides under it (docs/theory.md sections 6.3 and 7.1).

The lower half of an elastic cylinder (R = 1, E = 1000, nu = 0.3, plane strain, P2, elements of 0.04
at the contact) has its flat cut face held; the flat rises by 0.02 in 5 increments, then slides
sideways by 0.05 in 10, with mu = 0.3. Against the frictionless run of the same steps:

* the frictional run completes at the defaults (gamma0 = 100), penalty and Nitsche, with the lagged
  law and with the coulomb law;
* while pressing, friction costs at most 1.5 times the frictionless Newton iterations; while
  sliding, no more per increment than a frictionless pressing increment (a frictionless slide costs
  next to nothing: its surface is already in equilibrium, so the ratio to it says nothing);
* once the whole contact slides, the friction force is mu times the normal force (Coulomb's law at
  its threshold), to 1e-3 (the lagged law: mu times the last increment's normal force, which no
  longer changes), and the normal force is the frictionless one to 1 % (the shear hardly changes it);
* on two ranks the history is the serial one (the same Newton iterations in every increment).
"""
import numpy as np
import pytest
from mpi4py import MPI

import comove_dolfinx as cm

E, NU, MU = 1000.0, 0.3, 0.3
DEPTH, DRAG = 0.02, 0.05
N_PRESS, N_SLIDE = 5, 10


@pytest.fixture(scope="module")
def cache(tmp_path_factory):
    return str(MPI.COMM_WORLD.bcast(str(tmp_path_factory.mktemp("meshes")), root=0))


def _slide(cache, method, friction="lagged", mu=MU, comm=MPI.COMM_WORLD):
    """The run's history: normal force P, friction force Q, Newton iterations, and the reference
    lengths of the contact that stick and slip, per increment (read before the increment commits:
    afterwards its slip is the next increment's starting point, zero)."""
    mesh = cm.quarter_disc(1.0, 0.25, 0.04, 0.3, order=2, half=True, comm=comm, cache_dir=cache)
    body = cm.Body(mesh, "plane_strain", cm.Elastic(E, NU))
    flat = cm.Plane((0.0, 0.0), (0.0, 1.0),
                    motion=lambda f: (DRAG * max(f - 1.0, 0.0), DEPTH * min(f, 1.0)))
    c = cm.Contact("contact", flat, method=method, mu=mu, friction=friction)
    steps = [cm.Step(N_PRESS, ramp={c: 1.0}), cm.Step(N_SLIDE, ramp={c: 2.0})]
    probes = [cm.ContactForce(c, "Q", component=0), cm.ContactForce(c, "P", component=1),
              cm.Value("stick", lambda m: c.stick_slip()[0]), cm.Value("slip", lambda m: c.stick_slip()[1])]
    res = cm.Job(body, [cm.Fixed("top"), c], steps, probes=probes).run()
    assert res.completed, res.message
    assert len(res.rows) == N_PRESS + N_SLIDE                    # no cut-back was needed
    return res["P"], res["Q"], np.array(res.newton_its), (res["stick"], res["slip"])


@pytest.fixture(scope="module")
def frictionless(cache):
    return {m: _slide(cache, m, mu=0.0) for m in ("penalty", "nitsche")}


@pytest.mark.parametrize("method", ["penalty", "nitsche"])
@pytest.mark.parametrize("friction", ["lagged", "coulomb"])
def test_hertz_slide_at_the_defaults(cache, frictionless, method, friction):
    P, Q, its, (stick, slip) = _slide(cache, method, friction)
    P0, Q0, its0, _ = frictionless[method]
    assert np.all(Q0 == 0.0)
    # pressing: friction holds the surface back, the iterations stay those of the frictionless run
    assert its[:N_PRESS].mean() <= 1.5 * its0[:N_PRESS].mean(), (its, its0)
    # steady sliding: the whole contact slips, and Q = mu P
    assert stick[-1] == 0.0 and slip[-1] > 0.0
    assert Q[-1] / (MU * P[-1]) == pytest.approx(1.0, abs=1e-3)
    assert P[-1] == pytest.approx(P0[-1], rel=1e-2)
    # the sliding increments: the stick-to-slip transition takes a few, steady sliding next to none
    assert its[N_PRESS:].mean() <= its0[:N_PRESS].mean(), its


@pytest.mark.mpi
@pytest.mark.parametrize("method, friction", [("penalty", "lagged"), ("nitsche", "coulomb")])
def test_hertz_slide_on_two_ranks_is_the_serial_one(cache, method, friction):
    """The same problem distributed over the ranks and, on every rank, on its own (COMM_SELF)."""
    P, Q, its, _ = _slide(cache, method, friction)
    Ps, Qs, its_s, _ = _slide(cache, method, friction, comm=MPI.COMM_SELF)
    np.testing.assert_array_equal(its, its_s)
    np.testing.assert_allclose(P, Ps, rtol=1e-7)
    np.testing.assert_allclose(Q, Qs, rtol=1e-7, atol=1e-9 * np.abs(Qs).max())

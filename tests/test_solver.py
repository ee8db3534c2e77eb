"""Increment control and Newton globalisation: the predictors (extrapolation, the path's tangent), the
energy line search, the force-scaled convergence test."""
import numpy as np
import pytest
from dolfinx import fem
from mpi4py import MPI

from comove_dolfinx import compat
from comove_dolfinx.mechanics.model import Model
from comove_dolfinx.presets import get_scene
from comove_dolfinx.solver import (
    IncrementalSolver,
    Newton,
    NewtonSettings,
    StepSettings,
)
from comove_dolfinx.solver.predictors import extrapolate, path_rate

# lam = 2 of the inextensible elastica (docs/theory.md section 8.1): v/L
ELASTICA_2 = 0.49346


def _elastica(overrides):
    """The elastica scene's model (not finalised) and its tip probe, attached."""
    scene = get_scene("elastica", overrides)
    body, items, probes = scene.build(scene.mesh_data(MPI.COMM_WORLD))
    model = Model(body, items)
    tip = probes[0]
    tip.attach(model)
    return scene, model, tip


def test_extrapolation_reproduces_polynomial_paths():
    """Lagrange extrapolation through n + 1 states is exact for paths of degree n (unequal steps)."""
    a, b, c = np.array([1.0, -2.0]), np.array([0.5, 3.0]), np.array([-4.0, 0.25])
    linear = lambda t: a + b * t                      # noqa: E731
    quadratic = lambda t: a + b * t + c * t ** 2      # noqa: E731
    ts = [0.1, 0.25, 0.3]
    assert np.allclose(extrapolate([(t, linear(t)) for t in ts[1:]], 0.42), linear(0.42))
    assert np.allclose(extrapolate([(t, quadratic(t)) for t in ts], 0.42), quadratic(0.42))
    # and a quadratic path is not reproduced by the linear predictor
    assert not np.allclose(extrapolate([(t, quadratic(t)) for t in ts[1:]], 0.42), quadratic(0.42))


@pytest.mark.mpi
@pytest.mark.parametrize("predictor", [0, 1, "tangent"])
def test_energy_line_search_reaches_the_elastica(predictor):
    """The globalisation changes the path of the iterations, not the solution: with Crisfield's line
    search (and the linear or the tangent predictor) the elastica still lands on the closed form at
    lam = 2."""
    scene, model, tip = _elastica(["lam=2", "n_increments=10"])
    model.finalize()
    res = IncrementalSolver(model, StepSettings(n_increments=10, predictor=predictor),
                            NewtonSettings(line_search="energy")).run()
    assert res.completed, res.message
    v = -tip(model)["tip_uy"] / scene.L
    assert v == pytest.approx(ELASTICA_2, rel=5e-3)


def test_a_smaller_first_increment_doubles_back_onto_the_nominal_levels():
    """first = 1/4 of the nominal increment: the loop starts there, doubles after each easy increment
    only on the grid of the doubled size, and so lands on the nominal load levels; the elastica
    still reaches its closed form at lam = 2. A first increment that is not 1/2^k is refused."""
    scene, model, tip = _elastica(["lam=2", "n_increments=4"])
    model.finalize()
    res = IncrementalSolver(model, StepSettings(n_increments=4, first=0.25, predictor=1)).run()
    assert res.completed, res.message
    assert [inc.load for inc in res.increments] == pytest.approx([1 / 16, 1 / 8, 1 / 4, 1 / 2, 3 / 4, 1.0])
    assert -tip(model)["tip_uy"] / scene.L == pytest.approx(ELASTICA_2, rel=5e-3)
    for bad in (0.3, 0.5 ** 7, 0.0, 2.0):
        with pytest.raises(ValueError, match="first"):
            IncrementalSolver(model, StepSettings(n_increments=4, first=bad))


def test_unknown_line_search_is_refused():
    _, model, _ = _elastica(["n_increments=1"])
    model.finalize()
    with pytest.raises(ValueError, match="'bogus'"):
        Newton(model, NewtonSettings(line_search="bogus"))
    assert Newton(model, NewtonSettings(line_search="none")).line_search is None   # as the message offers
    with pytest.raises(ValueError, match="'bogus'"):
        Newton(model, NewtonSettings(scale="bogus"))
    with pytest.raises(ValueError, match="'bogus'"):
        IncrementalSolver(model, StepSettings(predictor="bogus")).run()


@pytest.mark.mpi
def test_tangent_predictor_is_the_derivative_of_the_path():
    """The tangent predictor's rate v = -K^-1 dR/dt at a converged state of the elastica (lam = 1) is
    the derivative of the path: the chords (u(t + h) - u(t)) / h of converged solutions approach it
    at first order in h (error halves with h; measured 4.5e-2 and 2.2e-2 of |v| for h = 0.1, 0.05, the
    same on two ranks)."""
    _, model, _ = _elastica(["lam=2", "n_increments=5"])
    model.finalize()
    solver = IncrementalSolver(model, StepSettings(n_increments=5, t_end=0.5), NewtonSettings())
    assert solver.run().completed
    rate = fem.Function(model.V)
    assert solver.newton.load_rate(0.5, rate, 1e-6)
    u1 = model.u_n.x.array.copy()
    err = {}
    for h in (0.1, 0.05):
        model.restore()
        model.set_load(0.5 + h)
        ok, _, reason = solver.newton.solve()
        assert ok, reason
        chord = fem.Function(model.V)
        chord.x.array[:] = (model.u.x.array - u1) / h - rate.x.array
        err[h] = compat.petsc_vec(chord).norm() / compat.petsc_vec(rate).norm()
    assert err[0.1] < 0.1
    assert err[0.05] / err[0.1] == pytest.approx(0.5, abs=0.1)


def test_path_rate_is_the_slope_of_the_interpolant():
    """The reference rate of the tangent's check is the slope at the newest state of the polynomial
    through the converged states: exact for linear paths through two states and for quadratic paths
    through three (unequal steps), and the chord's error on a quadratic path is (t2 - t1) |c2|."""
    a, b, c = np.array([1.0, -2.0]), np.array([0.5, 3.0]), np.array([-4.0, 0.25])
    path = lambda t: a + b * t + c * t ** 2           # noqa: E731
    slope = lambda t: b + 2 * c * t                   # noqa: E731
    ts = [0.1, 0.25, 0.3]
    assert np.allclose(path_rate([(t, path(t)) for t in ts]), slope(0.3))
    assert np.allclose(path_rate([(t, a + b * t) for t in ts[1:]]), b)
    chord = path_rate([(t, path(t)) for t in ts[1:]])
    assert np.allclose(slope(0.3) - chord, c * (0.3 - 0.25))


def test_tangent_predictor_falls_back_to_the_chord():
    """A tangent that strays from the rate of the last converged states by more than chord_tol (a
    spurious part along a near-mechanism) is not used: against the chord of two states the check
    accepts 5 % and refuses 20 % with chord_tol = 0.1. With three states on a path that curves (as
    the elastica's does), the exact tangent differs from the chord by more than that, and is
    accepted; the same tangent with a spurious part of 20 % of the chord at one node is refused."""
    _, model, _ = _elastica(["n_increments=1"])
    model.finalize()
    solver = IncrementalSolver(model, StepSettings(predictor="tangent", chord_tol=0.1))
    rng = np.random.default_rng(1)
    u0, u1 = np.zeros_like(model.u.x.array), rng.standard_normal(model.u.x.array.size)
    past = [(0.0, u0), (0.5, u1)]
    chord = 2.0 * u1
    rate = fem.Function(model.V)
    for factor, ok in ((1.05, True), (1.2, False), (0.8, False)):
        rate.x.array[:] = factor * chord
        assert solver._agrees_with_path(rate, past) is ok
    b, c = u1, 2.0 * rng.standard_normal(u1.size)                   # u(t) = b t + c t^2
    ts = (0.2, 0.4, 0.6)
    past = [(t, b * t + c * t * t) for t in ts]
    chord = (past[2][1] - past[1][1]) / 0.2
    rate.x.array[:] = b + 2 * c * ts[2]
    assert np.linalg.norm(rate.x.array - chord) > 0.1 * np.linalg.norm(chord)   # the chord's test fails
    assert solver._agrees_with_path(rate, past)
    rate.x.array[:2] += 0.2 * np.linalg.norm(chord)                  # one node, both components
    assert not solver._agrees_with_path(rate, past)


@pytest.mark.mpi
def test_force_scaled_convergence_balances_the_reaction():
    """With rtol relative to ||F_int|| (scale = "force") the elastica still lands on the closed form,
    and F_int, the force scale, is what the body carries: its vertical components sum to zero (a
    constant is a rigid motion) and, at the clamp, to the reaction that balances the dead tip load P
    (equilibrium of the whole cantilever, to within rtol)."""
    scene, model, tip = _elastica(["lam=2", "n_increments=10"])
    model.finalize()
    solver = IncrementalSolver(model, StepSettings(n_increments=10), NewtonSettings(scale="force",
                                                                              rtol=1e-6))
    res = solver.run()
    assert res.completed, res.message
    assert -tip(model)["tip_uy"] / scene.L == pytest.approx(ELASTICA_2, rel=5e-3)
    newton = solver.newton
    f_norm = newton.force_scale()
    assert newton.residual() <= 1e-6 * f_norm
    V = model.V
    clamp = fem.locate_dofs_topological(V.sub(1), 1, model.context().facets("left"))   # unrolled (y) dofs
    f = newton._f.array                                                         # owned entries
    owned = clamp[clamp < f.size]
    comm = MPI.COMM_WORLD
    reaction = comm.allreduce(float(f[owned].sum()), op=MPI.SUM)
    total = comm.allreduce(float(f[1::2].sum()), op=MPI.SUM)
    P = scene.lam * scene.E * scene.h ** 3 / 12 / scene.L ** 2
    assert abs(total) < 1e-9 * f_norm
    assert reaction == pytest.approx(P, rel=1e-5)


def test_force_scale_comes_with_the_residual():
    """With scale = "force" the residual is assembled as F_int plus the items' terms: the scale
    each accepted iterate was tested against is its own ||F_int||, assembled afresh after the
    run's every increment (to round-off), and the split residual still lands on the elastica's
    closed form (the stol test is off, so every increment passes the residual test)."""
    scene, model, tip = _elastica(["lam=2", "n_increments=10"])
    model.finalize()
    rtol = 1e-5

    class Watch:
        rnorm, accepted = None, 0

        def iteration(self, newton, it, rnorm):
            self.rnorm = rnorm

        def solved(self, newton, ok, its, reason):
            if ok:
                used = newton.residual_scale
                fresh = newton.force_scale()
                assert used == pytest.approx(fresh, rel=1e-12)
                assert self.rnorm <= rtol * fresh, (self.rnorm, fresh)
                self.accepted += 1

    watch = Watch()
    settings = NewtonSettings(scale="force", rtol=rtol, atol=0.0, stol=0.0, monitor=watch)
    solver = IncrementalSolver(model, StepSettings(n_increments=10), settings)
    res = solver.run()
    assert res.completed, res.message
    assert watch.accepted == len(res.increments) == 10
    assert -tip(model)["tip_uy"] / scene.L == pytest.approx(ELASTICA_2, rel=5e-3)


@pytest.mark.mpi
def test_load_terms_carry_the_residuals_dependence_on_the_load(mpi_tmp):
    """The tangent predictor's dR/dt comes from the load terms alone (F_int depends on u, not on the
    load factor): at a converged elastic-plastic state of a strip loaded by every kind of term that
    moves with t - a prescribed displacement (its lifting and constraint rows), a follower pressure
    (a facet form) and a point load (a nodal force) - the difference of Newton.load_terms between two
    load factors equals that of the whole residual to round-off, on one rank and on two."""
    from comove_dolfinx import geometry
    from comove_dolfinx.loads import Displacement, Fixed, PointLoad, Pressure
    from comove_dolfinx.mechanics.body import Body
    from comove_dolfinx.mechanics.materials import J2, Hardening

    L, H = 1.0, 0.2
    md = geometry.rectangle(L, H, H / 4, order=2, comm=MPI.COMM_WORLD, cache_dir=str(mpi_tmp))
    model = Model(Body(md, "plane_strain", J2(1e4, 0.3, Hardening.perfect(1.0))),
                  [Fixed("left", component=0), Fixed("bottom", component=1),
                   Displacement("right", value=3e-4, component=0), Pressure("top", 0.02),
                   PointLoad((L, H), (0.0, -0.002))])
    model.finalize()
    solver = IncrementalSolver(model, StepSettings(n_increments=2), NewtonSettings())
    assert solver.run().completed
    assert model.comm.allreduce(float(model.p.x.array.max(initial=0.0)), op=MPI.MAX) > 0.0
    newton, t, h = solver.newton, model.load, 0.25

    def difference(assemble):
        out = []
        for s in (t + h, t):
            model.set_load(s)
            assemble()
            out.append(newton.b.copy())
        out[0].axpy(-1.0, out[1])
        return out[0]
    whole = difference(newton.residual)
    terms = difference(lambda: newton.load_terms(newton.b))
    f_int = newton.force_scale()
    terms.axpy(-1.0, whole)
    assert whole.norm() > 1e-3 * f_int                   # the load terms do move
    assert terms.norm() <= 1e-12 * f_int

"""The saturation hardening law, the necking bar's mesh and the necking verification case.

* Hardening.saturation: its input checks; the return map's root and slope; monotonic uniaxial stress
  lands on sigma_y(p) with eps = sigma/E + p for any step size (the path is proportional, so the
  backward-Euler return is exact), in every model; the consistent tangent against finite
  differences.
* A straight bar pulled homogeneously through the production model: force and radius equal the
  S-R updates' exact discrete uniaxial solutions (verify.necking.homogeneous with n_increments), which
  tends to the logarithmic-strain closed form as the increments shrink.
* The builder's tags, areas, lengths and grading; the committed CalculiX deck is the one the module
  writes; the sampled *PLASTIC table keeps its interpolation bound.
* The case itself (run(tmp_path, small=True): the default mesh, which is already small).
"""
import math

import numpy as np
import pytest
from mpi4py import MPI

import comove_dolfinx as cm
from comove_dolfinx.mechanics.material_data import MODELS, Elastic, Hardening, MaterialError, von_mises
from comove_dolfinx.mechanics.return_maps import j2_return
from comove_dolfinx.verify import necking
from test_materials import FREE, drive, fd_tangent, random_trial, rel_err

LAW = Hardening.saturation(necking.SIGMA0, necking.H, necking.DSIGMA, necking.DELTA)
EL = Elastic(necking.E, necking.NU)


@pytest.mark.parametrize("args, msg", [
    ((float("nan"), 0.1, 0.2, 3.0), r"sigma0 = nan must be a finite number"),
    ((0.0, 0.1, 0.2, 3.0), r"sigma0 = 0.0 must be > 0"),
    ((1.0, -0.1, 0.2, 3.0), r"H = -0.1 must be >= 0 \(Hardening.saturation: no softening\)"),
    ((1.0, 0.1, -0.2, 3.0), r"dsigma = -0.2 must be >= 0"),
    ((1.0, 0.1, 0.2, float("inf")), r"delta = inf must be a finite number"),
    ((1.0, 0.1, True, 3.0), r"dsigma = True must be a finite number")])
def test_saturation_rejects_bad_input(args, msg):
    with pytest.raises(MaterialError, match=msg):
        Hardening.saturation(*args)


def test_saturation_term_checks_and_chen():
    with pytest.raises(MaterialError, match=r"dsigma = -1.0 must be >= 0: a negative saturation term softens"):
        Hardening((0.0,), (1.0,), dsigma=-1.0, delta=2.0)
    with pytest.raises(MaterialError, match=r"delta = nan must be a finite number >= 0"):
        Hardening((0.0,), (1.0,), dsigma=1.0, delta=float("nan"))
    with pytest.raises(MaterialError, match=r"delta = True must be a finite number >= 0"):
        Hardening((0.0,), (1.0,), dsigma=1.0, delta=True)
    with pytest.raises(MaterialError, match=r"Chen's law takes a piecewise-linear hardening table"):
        cm.Chen(1000.0, 0.3, LAW)
    # the curve and its slope
    p = np.array([0.0, 0.05, 0.3, 2.0])
    assert LAW.sigma_y(p) == pytest.approx(necking.yield_stress(p), rel=1e-15)
    assert LAW.slope(p) == pytest.approx(0.12924 + 0.265 * 16.93 * np.exp(-16.93 * p), rel=1e-14)
    assert LAW.smooth and not Hardening.linear(1.0, 2.0).smooth


def test_saturation_return_is_the_root():
    """dp solves q - 3 mu dp - sigma_y(p_n + dp) = 0 to round-off, and the slope returned is
    sigma_y'(p_n + dp), from the saturated range (delta p up to 17) to the first yield."""
    rng = np.random.default_rng(4)
    p_n = np.r_[rng.uniform(0.0, 1.0, 500), np.zeros(10)]
    three_mu = 3.0 * EL.mu
    seq = LAW.sigma_y(p_n) + np.r_[rng.uniform(0.0, 50.0, 500), np.geomspace(1e-12, 1e-3, 10)]
    dp, slope = LAW.solve_dp(seq, p_n, three_mu)
    assert np.all(dp > 0.0)
    assert np.abs(seq - three_mu * dp - LAW.sigma_y(p_n + dp)).max() < 1e-13 * seq.max()
    assert slope == pytest.approx(LAW.slope(p_n + dp), rel=1e-14)


@pytest.mark.parametrize("model", MODELS)
@pytest.mark.parametrize("steps", [6, 300])
def test_uniaxial_stress_follows_the_saturation_law(model, steps):
    """Monotonic uniaxial stress to eps = 0.6 (delta p = 10: the saturation term is spent): the stress
    is sigma_y(p) and eps = sigma/E + p at every step, in big steps as in small ones."""
    de = np.zeros((steps, 4))
    de[:, 0] = 0.6 / steps
    eps, sig, p = drive("j2", model, EL, LAW, de, FREE[model])
    y = p > 0.0                     # the first steps may still be elastic
    assert np.abs(sig[y, 0] - LAW.sigma_y(p[y])).max() < 1e-12 * sig[:, 0].max()
    assert np.all(sig[~y, 0] <= necking.SIGMA0) and y.sum() >= steps - 1
    assert eps[:, 0] == pytest.approx(sig[:, 0] / EL.E + p, rel=1e-12, abs=1e-15)
    assert np.abs(sig[:, 1:]).max() < 1e-10 * sig[:, 0].max()
    assert necking.DELTA * p[-1] > 9.0


@pytest.mark.parametrize("model", MODELS)
def test_saturation_tangent_matches_finite_differences(model):
    rng = np.random.default_rng(5)
    n = 300
    p_n = np.r_[np.zeros(50), rng.uniform(0.0, 0.4, n - 50)]
    sig_tr = random_trial(rng, n, model, LAW.sigma_y(p_n), 1.0 + rng.uniform(1e-3, 1.0, n))
    sig, p, D, _ = j2_return(sig_tr, p_n, EL, LAW, model)
    assert np.allclose(von_mises(sig), LAW.sigma_y(p), rtol=1e-12)
    f = lambda x: j2_return(x, p_n, EL, LAW, model)[0]     # noqa: E731
    assert rel_err(D, fd_tangent(f, sig_tr, 1e-5, model == "plane_stress")).max() < 1e-6


@pytest.mark.mpi
@pytest.mark.parametrize("update", ["sr_log", "sr"])
def test_homogeneous_bar_follows_the_law(mpi_tmp, update):
    """A straight bar (no imperfection: necking_bar with reduction 0) pulled 2 mm on its half length in
    10 increments, before the load's maximum (2.85 mm for the imperfect bar): force and radius are the
    S-R update's discrete uniaxial solution to 1e-7 (Newton's tolerance; that solution tends to the
    logarithmic closed form at first order, next test)."""
    n, pull = 10, 2.0
    mesh = cm.necking_bar(reduction=0.0, n_r=2, n_z=3, grading=1.0, comm=MPI.COMM_WORLD, cache_dir=str(mpi_tmp))
    body = cm.Body(mesh, "axisymmetric", cm.J2(necking.E, necking.NU, LAW), update=update)
    items = [cm.Fixed("axis", component=0), cm.Fixed("neck", component=1), cm.Displacement("end", pull, component=1)]
    probes = [cm.Reaction("end", "end"), cm.NodeDisplacement("corner", (necking.R, 0.0), component=0, column="ur")]
    res = cm.Job(body, items, [cm.Step(n)], probes=probes, newton=cm.NewtonSettings(rtol=1e-10)).run()
    assert res.completed
    u = pull * res["load"]
    force, radius = res["end_fy"], necking.R + res["ur"]
    f_disc, r_disc = necking.homogeneous(u, n_increments=n, update=update)
    assert force == pytest.approx(f_disc, rel=1e-7)
    assert radius == pytest.approx(r_disc, rel=1e-9)
    # well into the saturation term's curvature: the true stress at the end is 1.43 sigma0 (delta p = 1.2)
    assert force[-1] / (math.pi * radius[-1] ** 2) > 1.4 * necking.SIGMA0


@pytest.mark.parametrize("update, order", [("sr", 1), ("sr_log", 2)])
def test_discrete_homogeneous_solution_tends_to_the_closed_form(update, order):
    """The S-R discrete solution converges to the logarithmic closed form at first order, the one
    with logarithmic increments at second order."""
    u = np.array([2.0])
    errs = [abs(necking.homogeneous(u, n_increments=n, update=update)[0][0] / necking.homogeneous(u)[0][0] - 1)
            for n in (10, 20, 40)]
    assert errs[0] / errs[1] == pytest.approx(2.0 ** order, rel=0.05)
    assert errs[1] / errs[2] == pytest.approx(2.0 ** order, rel=0.05)


def test_necking_bar_mesh(tmp_path):
    """Tags, the section's area (the trapezoid), the boundaries' lengths, the grading 3:1 of the cells
    along the axis, the vertices on necking_bar_grid; bad input refused."""
    import ufl
    from dolfinx import fem
    R, L, red = 6.413, 53.334, 0.018
    md = cm.necking_bar(comm=MPI.COMM_WORLD, cache_dir=str(tmp_path))
    assert md.tags == {"axis": 1, "neck": 2, "end": 3, "surface": 4}
    ds = ufl.Measure("ds", domain=md.mesh, subdomain_data=md.facet_tags)
    one = fem.Constant(md.mesh, 1.0)
    total = lambda form: md.mesh.comm.allreduce(fem.assemble_scalar(fem.form(form)), op=MPI.SUM)  # noqa: E731
    assert total(one * ufl.dx(domain=md.mesh)) == pytest.approx(0.5 * L * R * (1 - red / 2), rel=1e-12)
    lengths = {"axis": 0.5 * L, "neck": R * (1 - red), "end": R, "surface": math.hypot(0.5 * L, R * red)}
    for name, length in lengths.items():
        assert total(one * ds(md.ds_id(name))) == pytest.approx(length, rel=1e-12)
    x = md.mesh.geometry.x
    z, r = cm.necking_bar_grid()
    axis = np.sort(x[np.abs(x[:, 0]) < 1e-12, 1])[::2]          # vertices (P2: every other node)
    assert axis == pytest.approx(z, abs=1e-7) and np.diff(z)[-1] / np.diff(z)[0] == pytest.approx(3.0)
    cells = md.mesh.comm.allreduce(md.mesh.topology.index_map(2).size_local, op=MPI.SUM)
    assert cells == 2 * 5 * 40
    for kwargs, msg in [(dict(reduction=1.0), "reduction must be a number in"), (dict(n_z=0), "n_z must be"),
                        (dict(grading=0.5), "grading must be >= 1"), (dict(R=-1.0), "R must be a finite")]:
        with pytest.raises(ValueError, match=msg):
            cm.necking_bar(cache_dir=str(tmp_path), **kwargs)


def test_calculix_deck_and_table():
    """The committed deck is what calculix_deck writes (its CSV comes from it), and its *PLASTIC
    table is within the stated 1e-5 GPa of the law (the bound h^2/8 max|sigma_y''| of linear
    interpolation)."""
    assert (necking.DATA / "necking_calculix.inp").read_text() == necking.calculix_deck()
    p, s = necking.plastic_table(1e-5)
    fine = np.linspace(0.0, p[-1], 200001)
    assert np.abs(np.interp(fine, p, s) - necking.yield_stress(fine)).max() <= 1e-5
    assert np.abs(np.interp(fine, p, s) - necking.yield_stress(fine)).max() > 0.5e-5   # the bound is near


@pytest.mark.mpi
def test_case_at_the_defaults(mpi_tmp):
    """The case as `comove verify necking` runs it: 5 x 40 cells, 140 increments at the library's
    defaults against CalculiX in 140 increments on the same grid, within 0.5 % (measured 0.17 % in
    the force and 0.31 % in the neck radius up to 6 mm), and no cut-back."""
    checks = necking.run(mpi_tmp, small=True)
    assert checks and all(c.ok for c in checks), "\n".join(
        f"{c.quantity}: {c.result} vs {c.reference} ({c.error:.3g} > {c.tolerance})" for c in checks if not c.ok)
    MPI.COMM_WORLD.barrier()
    assert (mpi_tmp / "necking.png").is_file()

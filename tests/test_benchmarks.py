"""The cost benchmarks (comove_dolfinx.benchmarks, docs/performance.md): the elastic floor solves the system
it assembles, a one-increment floor study of the ring writes its table and chart with its parts
inside the run, scene parameters reach the runs, the line-search probe and the parts study leave the
run as it was; the deprecated comove_dolfinx.cost still forwards to them."""
import subprocess
import sys

import numpy as np
import pytest

from comove_dolfinx import benchmarks
from comove_dolfinx.io.csv_tables import read_table


def test_the_floor_solves_the_elastic_system_it_assembles():
    """The floor's iteration is a real linear-elastic solve on the run's mesh, space and supports:
    its right-hand side is the stiffness times a random field w (with Newton's lifting of the
    supported rows), so the factorisation and solve must give w back, to round-off, and the
    stiffness is regular on the supported ring (no rigid-body mode left). A matrix and residual of
    different forms, a wrong lifting or a solve that did not happen would not."""
    run = benchmarks.short_run("ring", 0.22, 1)
    floor = benchmarks.ElasticFloor(run["model"])
    for _ in range(2):                             # a new field each time, the analysis reused
        times = floor.sample()
        w, x = floor.w.x.array, floor.x.array
        assert np.linalg.norm(x - w) < 1e-9 * np.linalg.norm(w)
        assert all(t >= 0.0 for t in times)
    floor.destroy()


def test_floor_study_writes_its_table_with_the_parts_inside_the_run(tmp_path):
    """The Timer's parts are measured by their own clock calls inside the run, the run's CPU around
    it: they must fit in it. Every Newton iteration evaluates the residual at least once."""
    rows = benchmarks.floor(tmp_path, sizes=(0.22,), repeats=1, increments=1)
    (row,) = read_table(tmp_path / "floor.csv")
    assert (tmp_path / "floor.png").stat().st_size > 0
    assert int(row["dofs"]) == rows[0]["dofs"] > 1000 and int(row["iterations"]) >= 1
    assert float(row["residuals_per_it"]) >= 1.0
    timed = sum(float(row[f"{k}_s_per_it"]) for k in ("solve", "jacobian", "assembly", "stress_update",
                                                       "force_scale", "predictor"))
    assert 0.0 < timed <= float(row["iteration_cpu_s"]) * 1.05
    assert float(row["floor_cpu_s"]) > 0.0 and np.isfinite(float(row["ratio"]))


def test_scene_parameters_reach_the_runs_and_bad_ones_are_refused(capsys):
    """`--set` changes the ring's runs: with the tangent predictor (the scene's) the Timer books
    the predictor's residuals and back-substitution, with the linear extrapolation nothing; a value
    the scene does not know is a one-line usage error, before any run."""
    def predictor_time(predictor):
        run = benchmarks.short_run("ring", 0.22, 3, overrides=[f"predictor={predictor}"])
        assert run["increments"] >= 3
        return run["timer"].get("predictor", 0.0)
    assert predictor_time("tangent") > 0.0 and predictor_time("linear") == 0.0
    with pytest.raises(SystemExit):
        benchmarks.main(["floor", "--set", "predictor=bogus", "--sizes", "0.22"])
    err = capsys.readouterr().err.strip().splitlines()
    assert "predictor = 'bogus'" in err[-1] and "tangent" in err[-1]


def test_slope_probe_sees_the_exact_tangent_and_leaves_the_run_as_it_was(tmp_path):
    """Along Newton's own corrections of the ring (first contact and yield), the residual's secant
    slope (s(a) - s(0)) / (a |s(0)|), s(a) = du . R(u + a du), tends to the tangent's, 1, as the step
    shrinks: a Jacobian that missed or mis-scaled a part along du would leave it away from 1. Before
    the residual stiffens well beyond the tangent along du, points that yield at the iterate have
    unloaded (docs/performance.md). The probe evaluates the residual along du and goes back: the
    run is the same to the last bit."""
    probe = benchmarks.SlopeProbe(count=3, after=0.0, overshoot=0.0)
    run = benchmarks.short_run("ring", 0.22, 6, monitor=probe)
    plain = benchmarks.short_run("ring", 0.22, 6)
    assert run["iterations"] == plain["iterations"]
    assert np.array_equal(run["model"].u.x.array, plain["model"].u.x.array)
    assert len(probe.cases) == 3
    stiffening = 0
    for case in probe.cases:
        slope = {r[0]: r[1] for r in case["rows"]}
        assert case["s0"] < 0.0 and slope[1.0] > 1.0          # each of them overshoots
        assert abs(slope[1e-5] - 1.0) < 1e-3
        assert abs(slope[1e-4] - 1.0) < 1e-2
        # the crown yields from the first increment; no point changes at the smallest step
        assert case["yielding"] > 0 and case["rows"][0][3:] == (0, 0)
        # the secant first reaches 1.5 times the tangent's slope once points have unloaded
        stiff = [k for k, r in enumerate(case["rows"]) if r[1] >= 1.5]
        if stiff:
            stiffening += 1
            assert any(r[3] > 0 for r in case["rows"][:stiff[0] + 1]), case["rows"]
    assert stiffening > 0          # the check above ran (two of the three cases reach 1.5)
    # the command writes the cases' rows (one per step) and the chart
    benchmarks.main(["slopes", "--sizes", "0.22", "--increments", "24", "--out", str(tmp_path)])
    rows = read_table(tmp_path / "slopes.csv")
    assert len(rows) % len(benchmarks.SLOPE_STEPS) == 0 and rows
    assert (tmp_path / "slopes.png").stat().st_size > 0


def test_parts_study_times_each_part_three_ways_and_leaves_the_state(tmp_path):
    """`benchmarks parts` writes one row per part with its three timings (the figures themselves are
    benchmarks, not asserted); the stress it evaluates again for the timing (which Newton would
    skip at the same iterate) is the state's to the last bit, so the timing changes nothing the run
    would see."""
    run = benchmarks.short_run("ring", 0.22, 3)
    m, newton = run["model"], run["newton"]
    rnorm = newton.residual()          # the committed state's iterate, evaluated once
    sigma = m.state.sigma.x.array.copy()
    m.state.sigma.x.array[:] = 0.0
    m.evaluate_stress()                # the same iterate: nothing done, the zeros stay
    assert not m.state.sigma.x.array.any() and np.abs(sigma).max() > 0.0
    m.evaluate_stress(again=True)
    assert np.array_equal(m.state.sigma.x.array, sigma) and newton.residual() == rnorm
    benchmarks.main(["parts", "--sizes", "0.22", "--increments", "2", "--repeats", "2", "--out", str(tmp_path)])
    rows = read_table(tmp_path / "parts.csv")
    assert [r["part"] for r in rows] == [
        "residual (stress evaluated again)", "stress evaluation", "residual without the stress",
        "Jacobian", "floor: elastic matrix", "floor: elastic residual", "NumPy: sum of 16 values",
        "PETSc: a vector's norm"]
    for r in rows:
        t = [float(r[k]) for k in ("alone_us", "after_factorisation_us", "after_idle_us")]
        assert all(np.isfinite(v) and v > 0.0 for v in t), r
    assert (tmp_path / "parts.png").stat().st_size > 0


def test_the_deprecated_cost_module_forwards_with_a_warning():
    """``comove_dolfinx.cost`` (the benchmarks' former home) gives the benchmarks' names and runs
    their command, each with a DeprecationWarning that names the new place; a name the benchmarks
    lack stays an AttributeError."""
    from comove_dolfinx import cost
    with pytest.warns(DeprecationWarning, match="comove_dolfinx.benchmarks.SlopeProbe"):
        assert cost.SlopeProbe is benchmarks.SlopeProbe
    with pytest.raises(AttributeError):
        cost.no_such_name
    p = subprocess.run([sys.executable, "-m", "comove_dolfinx.cost", "floor", "--set", "predictor=bogus"],
                       capture_output=True, text=True)
    err = p.stderr.strip().splitlines()
    assert p.returncode == 2
    assert any("DeprecationWarning" in line and "python -m comove_dolfinx.benchmarks" in line for line in err)
    assert err[-1].startswith("python -m comove_dolfinx.cost: error: ") and "predictor = 'bogus'" in err[-1]


def test_solid_study_runs_the_bent_block_with_each_solver(tmp_path):
    """The 3D study on a coarse block: a row per linear solver in solid.csv, Krylov iterations for
    GAMG only, the run completed by both, and GAMG at its default tolerance within 20 % of MUMPS's
    Newton iterations (the linear error does not change Newton's path)."""
    from comove_dolfinx.benchmarks.solid3d import solid
    solid(tmp_path, sizes=(0.5,), names=("gamg", "mumps"), repeats=1)
    rows = {r["solver"]: r for r in read_table(tmp_path / "solid.csv")}
    assert set(rows) == {"gamg", "mumps"}
    assert float(rows["gamg"]["krylov_per_solve"]) > 1.0 and float(rows["mumps"]["krylov_per_solve"]) == 0.0
    assert all(float(r["completed_to"]) == 1.0 for r in rows.values())
    assert float(rows["gamg"]["newton_its"]) <= 1.2 * float(rows["mumps"]["newton_its"])


def test_output_study_times_the_writers_inside_the_job(tmp_path, capsys):
    """The output benchmark runs the elastica as `comove run` does, in a process of its own: the
    writers' CPU seconds are timed inside the job's (0 < output < job), a scene does nothing after
    its job, and the run wrote what the output paid for (history, run.json, the VTK series). An
    unknown case is a one-line usage error before any run."""
    from comove_dolfinx.benchmarks.output_share import output
    (row,) = output(tmp_path, repeats=1, names=["scene:elastica"])
    assert 0.0 < row["output_cpu_s"] < row["job_cpu_s"] and row["after_cpu_s"] == 0.0
    assert row["share"] == pytest.approx(row["output_cpu_s"] / row["job_cpu_s"])
    run = tmp_path / "scene_elastica"
    assert (run / "history.csv").exists() and (run / "run.json").exists() and (run / "results.pvd").exists()
    assert read_table(tmp_path / "output.csv")[0]["case"] == "scene:elastica"
    with pytest.raises(SystemExit):
        benchmarks.main(["output", "--scenes", "bogus"])
    assert "unknown case(s) bogus" in capsys.readouterr().err.strip().splitlines()[-1]

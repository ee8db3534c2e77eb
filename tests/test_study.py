"""The study's arithmetic (Richardson, Pareto front, the claim table, q read off a history) on sequences
with known answers; material constants that do not enter the generated code; the timing's clocks
nested in the process's."""
import math

import numpy as np
import pytest
from mpi4py import MPI

import comove_dolfinx as cm
from comove_dolfinx.study import report
from comove_dolfinx.study.plan import PLANS, ScenePlan
from comove_dolfinx.study.runner import quantity


def test_richardson_recovers_the_limit_and_order():
    for p in (1.0, 2.0, 3.0):
        q = [2.0 + 0.3 * h ** p for h in (0.4, 0.2, 0.1)]
        ext, err, order = report.richardson(q)
        assert ext == pytest.approx(2.0, abs=1e-12) and order == pytest.approx(p, rel=1e-10)
        assert err == pytest.approx(0.3 * 0.1 ** p, rel=1e-9)
    # differences that grow or change sign: no extrapolation, the last change is the error
    assert report.richardson([1.0, 1.1, 1.0]) == (1.0, pytest.approx(0.1), pytest.approx(math.nan, nan_ok=True))
    assert report.richardson([1.0, 1.01, 1.1])[:2] == (1.1, pytest.approx(0.09))


def test_pareto_front_keeps_the_undominated_runs():
    """Only completed runs: one that stopped after its q was read (id 6, cheap because short) would
    otherwise dominate the front."""
    rows = [{"cpu_s": c, "error_percent": e, "id": i, "status": st}
            for i, (c, e, st) in enumerate([(1.0, 5.0, "completed"), (2.0, 1.0, "completed"),
                                            (1.5, 6.0, "completed"), (3.0, 1.0, "completed"),
                                            (4.0, 0.1, "completed"), (0.5, math.nan, "completed"),
                                            (0.9, 0.5, "stopped")])]
    assert [r["id"] for r in report.pareto(rows)] == [0, 1, 4]


def test_quantity_is_interpolated_at_the_load_level_or_read_at_the_end(tmp_path):
    """q read off a history file as the study reads it (led by the unloaded state)."""
    from comove_dolfinx.io.csv_tables import read_history, write_table
    write_table(tmp_path / "h.csv", [{"load": 0.5, "force": 10.0}, {"load": 1.5, "force": 30.0}])
    hist = read_history(tmp_path / "h.csv", origin=True)
    ring = ScenePlan("x", "force", 1.0, "P")
    assert quantity(ring, hist) == pytest.approx(20.0)
    assert quantity(ScenePlan("x", "force", 0.25, "P"), hist) == pytest.approx(5.0)   # from the origin
    assert math.isnan(quantity(ScenePlan("x", "force", 2.0, "P"), hist))
    assert quantity(ScenePlan("x", "force", None, "P", sign=-1.0), hist) == -30.0
    write_table(tmp_path / "empty.csv", [], ["load", "force"])
    assert math.isnan(quantity(ring, read_history(tmp_path / "empty.csv", origin=True)))


def test_claim_table_finds_the_fewest_increments():
    """q(n) = 1 + 0.9/n: within 1 % from n = 100, 0.1 % from n = 1000 against the reference 1; the same against
    the update's own limit, which Richardson recovers exactly from the three finest runs."""
    plan = ScenePlan("s", "q", None, "q", updates=("sr",))
    rows = [{"family": "update sr", "x": float(n), "q": 1.0 + 0.9 / n, "status": "completed",
             "cpu_s": 0.01 * n} for n in (10, 100, 400, 1000, 2000, 4000)]
    report.add_errors(rows, 1.0)
    (c,) = report.claim_rows(plan, rows)
    assert c["own_limit"] == pytest.approx(1.0, rel=1e-12)
    assert (c["n_reference_1%"], c["n_reference_0.1%"]) == (100, 1000)
    assert (c["n_own_1%"], c["n_own_0.1%"]) == (100, 1000)
    assert c["cpu_reference_1%"] == pytest.approx(1.0)


def test_every_scene_plan_has_its_reference_runs():
    for plan in PLANS.values():
        refs = plan.reference_cases()
        assert len(refs) == 6 and all(c.tag for c in refs.values())
        tags = [c.tag for c in plan.cases()]
        assert len(tags) == len(set(tags))                 # no two runs share a folder


def _block(E, mu, tmp_path):
    md = cm.rectangle(1.0, 0.25, 0.125, order=1, comm=MPI.COMM_SELF, cache_dir=str(tmp_path))
    body = cm.Body(md, "plane_strain", cm.Elastic(E=E, nu=0.3), degree=1)
    floor = cm.Contact("bottom", cm.Plane((0.0, -0.5), (0.0, 1.0)), mu=mu)
    tip = cm.NodeDisplacement("tip", (1.0, 0.25))
    job = cm.Job(body, [cm.Fixed("left"), cm.Traction("right", (0.0, -1e-4)), floor], [cm.Step(1)], [tip])
    return job, job.run()


def test_material_constants_do_not_enter_the_compiled_code(tmp_path):
    """Two models that differ in E and in the friction coefficient have the same form signature (so
    they share the compiled code and the JIT cache), and still give the answers of their own
    constants: far from the obstacle, at a load that strains the block by 1e-5, the tip moves half
    as much for twice the modulus (to the geometric nonlinearity, ~1e-5)."""
    job1, r1 = _block(1000.0, 0.1, tmp_path)
    job2, r2 = _block(2000.0, 0.3, tmp_path)
    assert r1.completed and r2.completed
    assert job1.model.residual_ufl.signature() == job2.model.residual_ufl.signature()
    ratio = r1["tip_uy"][-1] / r2["tip_uy"][-1]
    assert r1["tip_uy"][-1] < 0 and ratio == pytest.approx(2.0, rel=1e-4)


def test_timing_fits_in_the_process(tmp_path):
    """Three clocks nest: the parts the run times (each span its own clock calls) fit in the run's
    wall time, and what came before the run plus the run fit in the process's life as the kernel
    counts it (/proc)."""
    _, res = _block(1000.0, 0.0, tmp_path)
    parts = res.timing
    before = parts["before the run (start-up, imports, mesh)"]
    assert 0.0 < before < res.process["wall_s"]
    timed = [v for k, v in parts.items() if not k.startswith("before") and k != "other"]
    assert timed and min(timed) >= 0.0 and sum(timed) <= res.wall_s
    assert before + res.wall_s <= res.process["wall_s"] + 0.02      # /proc's clock ticks: 10 ms
    assert res.process["cpu_s"] > 0.0
    assert "process: wall" in res.timing_report
    assert np.isfinite(res.process["compiler_cpu_s"])


@pytest.mark.parametrize("args, msg", [
    (["nope"], "study 'nope': choose one of elastica, beam, plate, ring or all"),
    (["ring", "--repeat", "0"], "--repeat 0 --jobs 2: give whole numbers >= 1"),
    (["ring", "--out", ""], "--out '': give the output folder")])
def test_study_refuses_bad_arguments_in_one_line(args, msg, tmp_path):
    import launch
    out = [] if "--out" in args else ["--out", str(tmp_path / "s")]
    p = launch.run(["-m", "comove_dolfinx.cli", "study", *args, *out])
    assert p.returncode == 2 and p.stderr.strip() == f"comove: {msg}"
    assert not (tmp_path / "s").exists()


def test_study_refuses_to_start_under_mpirun(tmp_path, monkeypatch, capsys):
    """Under a launcher every rank would start the whole study into the same folder."""
    from comove_dolfinx import cli
    monkeypatch.setenv("OMPI_COMM_WORLD_SIZE", "2")
    assert cli.main(["study", "ring", "--out", str(tmp_path / "s")]) == 2
    assert capsys.readouterr().err.startswith("comove: study: it starts its runs as processes of its own")
    assert not (tmp_path / "s").exists()


_GRID = '''
import json, pathlib, sys
from comove_dolfinx.study import PLANS, executors, runner
from comove_dolfinx.study.plan import Case

if __name__ == "__main__":           # (the pool's workers import this file under another name)
    kind, why = executors.choose("auto")
    assert why is None, why
    cases = [Case("update sr", n, ("update=sr", f"n_increments={n}")) for n in (1, 2)]
    cases.append(Case("update polar", 2, ("update=polar", "n_increments=2")))
    with executors.make(kind, 2) as pool:
        rows = runner.run_all(PLANS["elastica"], cases, pathlib.Path(sys.argv[1]), 1, pool=pool)
    print(json.dumps({"executor": kind, "rows": rows}))
'''

#: what a run's row holds besides its clocks
_TIMINGS = ("cpu_s", "cpu_spread_s", "compile_cpu_s")


def test_the_mpi_pool_runs_a_grid_as_the_local_executor_does(tmp_path):
    """A grid of three elastica runs through mpi4py.futures' pool on two processes (one hands out the
    runs, one runs them, each a `comove run` of its own) and through the local executor: the
    executor is detected from the launch, and the rows are the same but for the CPU times."""
    import json

    import launch
    script = tmp_path / "grid.py"
    script.write_text(_GRID)
    got = {}
    for name, args, n in (("mpi", ["-m", "mpi4py.futures", script], 2), ("local", [script], 1)):
        p = launch.run([*args, tmp_path / name], n=n, timeout=600)
        assert p.returncode == 0, p.stderr[-2000:]
        got[name] = json.loads(p.stdout.strip().splitlines()[-1])
    assert got["mpi"]["executor"] == "mpi" and got["local"]["executor"] == "local"
    rows = {k: [{c: v for c, v in r.items() if c not in _TIMINGS} for r in g["rows"]] for k, g in got.items()}
    assert json.dumps(rows["mpi"], sort_keys=True) == json.dumps(rows["local"], sort_keys=True)  # (NaN as NaN)
    assert [r["status"] for r in rows["local"]] == ["completed"] * 3
    assert all(r["cpu_s"] > 0 for g in got.values() for r in g["rows"])


@pytest.mark.parametrize("executor, msg", [
    ("mpi", "--executor mpi: start the study as mpiexec -n N python -m mpi4py.futures -m "
            "comove_dolfinx.study ... (N >= 2: one process hands out the runs, N - 1 run them)"),
    ("dask", "--executor 'dask': choose auto, local, mpi")])
def test_study_refuses_an_executor_it_cannot_have(executor, msg, tmp_path, capsys):
    from comove_dolfinx import cli
    assert cli.main(["study", "ring", "--executor", executor, "--out", str(tmp_path / "s")]) == 2
    assert capsys.readouterr().err.strip() == f"comove: {msg}"
    assert not (tmp_path / "s").exists()

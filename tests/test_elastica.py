"""The elastica verification scene against the inextensible elastica (docs/theory.md section 8.1), every update."""
import csv
import re

import launch
import pytest

from comove_dolfinx.cli import run_scene
from comove_dolfinx.mechanics.updates import UPDATES
from comove_dolfinx.presets import get_scene

# lam: (v/L, (L - x_tip)/L) of the inextensible elastica, docs/theory.md section 8.1
ELASTICA = {1.0: (0.30172, 0.05643), 2.0: (0.49346, 0.16064), 5.0: (0.71379, 0.38763)}


def read_history(path):
    with open(path) as fh:
        return [{k: float(v) for k, v in row.items()} for row in csv.DictReader(fh)]


@pytest.mark.parametrize("update", [name for name, cls in UPDATES.items() if cls.geometric])
def test_elastica_tip(update, mpi_tmp):
    """Every finite-strain update (linear kinematics cannot rotate the beam): a continuum cantilever
    with L/h = 40 follows the elastica to well within 0.5 % (shear and
    extension of the continuum, neglected by the elastica, are O((h/L)^2) ~ 1e-3 here). The rate-form
    updates add a first-order increment error (measured at lam = 1: 0.5 % in v with 10 increments,
    0.05 % with 40), so they run with 20; the shortening L - x ~ v^2 doubles relative errors."""
    scene = get_scene("elastica", [f"update={update}", "n_increments=20"])
    res = run_scene(scene, mpi_tmp / update, progress=False)
    assert res.completed
    rows = {round(r["load"], 9): r for r in read_history(mpi_tmp / update / "history.csv")}
    for lam, (v, xs) in ELASTICA.items():
        r = rows[lam]
        assert -r["tip_uy"] / scene.L == pytest.approx(v, rel=5e-3), lam
        assert -r["tip_ux"] / scene.L == pytest.approx(xs, rel=1e-2), lam


def _cli(args, n=1, cwd=None):
    return launch.run(["-m", "comove_dolfinx.cli", *args], n=n, cwd=cwd)


def test_one_and_two_ranks_give_the_same_history(tmp_path):
    args = ["run", "elastica", "--no-progress", "--set", "n_increments=4", "--set", "lam=3"]
    hist = []
    for n in (1, 2):
        out = tmp_path / f"np{n}"
        p = _cli([*args, "--out", str(out)], n=n)
        assert p.returncode == 0, p.stderr
        hist.append(read_history(out / "history.csv"))
    assert len(hist[0]) == len(hist[1]) == 4
    for a, b in zip(*hist):
        for key in ("load", "tip_ux", "tip_uy", "newton_its"):
            assert b[key] == pytest.approx(a[key], rel=1e-9, abs=1e-12), key


def test_progress_bar_only_on_a_terminal(tmp_path):
    """Run as from a script or into a log (stdout and stderr are pipes here): the console's increment
    lines and no progress bar (tqdm's bar would come out as one line per refresh, '...%|###...')."""
    p = _cli(["run", "elastica", "--set", "n_increments=2", "--set", "lam=1", "--out", str(tmp_path / "run")])
    assert p.returncode == 0, p.stderr
    assert "%|" not in p.stderr + p.stdout
    assert "increment   2  load 1" in p.stdout


def _elastica_tip(E, lam=5.0):
    """(v/L, (L - x_tip)/L, Newton iterations) of the elastica scene on a coarse mesh at lam."""
    from mpi4py import MPI
    scene = get_scene("elastica", [f"E={E!r}", f"lam={lam}", "n_increments=5", "size=0.25"])
    res = scene.job(scene.mesh_data(MPI.COMM_WORLD)).run()
    assert res.completed, res.message
    return -res["tip_uy"][-1] / scene.L, -res["tip_ux"][-1] / scene.L, res.newton_its


@pytest.mark.parametrize("E", [1e-100, 1e-8, 1e100])
def test_the_elastica_at_any_scale_of_E(E):
    """The tip load is lam E I / L^2, so the displacement does not depend on E: at E = 1e-8 (loads
    of 1e-13, below Newton's absolute tolerance, which once accepted the unloaded state) and at
    1e+-100 the tip lies where the elastica puts it (within the coarse mesh's 1 %) and where it lies
    at E = 1000 (to 1e-6). (The iterations may differ by one: where the forces are below atol /
    rtol the absolute tolerance is rtol times the force level instead of atol.)"""
    v, xs, its = _elastica_tip(E)
    v0, xs0, _ = _elastica_tip(1000.0)
    assert v == pytest.approx(ELASTICA[5.0][0], rel=1e-2) and xs == pytest.approx(ELASTICA[5.0][1], rel=2e-2)
    assert v == pytest.approx(v0, rel=1e-6) and xs == pytest.approx(xs0, rel=1e-6)
    assert min(its) >= 1


def test_a_young_s_modulus_beyond_double_precision_is_refused():
    """E = 1e300: the scene refuses it in one line before anything is built; a job of the API
    with forces whose squares overflow (E = 1e200) or underflow (1e-300) stops at its first
    residual with the reason, without cutting back (no smaller increment helps)."""
    import comove_dolfinx as cm
    from comove_dolfinx.presets import SceneError
    for E in ("1e300", "1e-300"):
        with pytest.raises(SceneError, match=re.escape(f"E = {float(E):g}: give a Young's modulus from 1e-100 to 1e+100")):
            get_scene("elastica", [f"E={E}"])
    for E in (1e200, 1e-300):
        mesh = cm.rectangle(2.0, 0.5, 0.5, order=1)
        body = cm.Body(mesh, "plane_strain", cm.Elastic(E, 0.3), degree=1)
        job = cm.Job(body, [cm.Fixed("left"), cm.Traction("right", (0.0, -1e-3 * E))], [cm.Step(2)])
        res = job.run()
        assert not res.completed and len(res) == 0 and res.cutbacks == 0
        assert "beyond the range of double precision" in res.message and res.failures == {"diverged": 1}, res.message

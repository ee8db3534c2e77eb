"""The elastica verification scene against the inextensible elastica (docs/theory.md section 8.1), every update."""
import csv

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

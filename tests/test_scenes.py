"""The contact scenes end to end: the same history on one and two ranks, the warning for an obstacle
that is never reached, and the elastica's accuracy with few large increments."""

import pytest
from test_elastica import ELASTICA, _cli, read_history

from comove_dolfinx.cli import run_scene
from comove_dolfinx.presets import get_scene


def test_beam_one_and_two_ranks_give_the_same_history(tmp_path):
    """Coarse beam pressed onto the plane with friction: contact, friction history and the contact
    force are partition-independent."""
    args = ["run", "beam", "--no-progress", "--set", "size=0.25", "--set", "q_max=0.1",
            "--set", "n_increments=4"]
    hist = []
    for n in (1, 2):
        out = tmp_path / f"np{n}"
        p = _cli([*args, "--out", str(out)], n=n)
        assert p.returncode == 0, p.stdout + p.stderr
        hist.append(read_history(out / "history.csv"))
    assert len(hist[0]) == len(hist[1])
    assert hist[0][-1]["contact_force"] > 0                  # the run does reach the plane
    for a, b in zip(*hist):
        for key in ("load", "tip_ux", "tip_uy", "contact_length", "contact_force"):
            assert b[key] == pytest.approx(a[key], rel=1e-7, abs=1e-10), key


def test_obstacle_never_reached_warns(tmp_path):
    p = _cli(["run", "beam", "--no-progress", "--set", "size=0.25", "--set", "gap=50",
              "--set", "q_max=0.001", "--set", "n_increments=1", "--out", str(tmp_path)])
    assert p.returncode == 0, p.stderr
    assert "never touched" in p.stdout


def test_negative_gap_is_refused(tmp_path):
    p = _cli(["run", "beam", "--set", "gap=-0.1", "--out", str(tmp_path)])
    assert p.returncode == 2 and "gap" in p.stderr and "Traceback" not in p.stderr


@pytest.mark.mpi
def test_elastica_one_percent_in_five_increments(mpi_tmp):
    """The S-R update within 1 % of the elastica at lam = 5 in at most 10 equal
    increments, here 5, with no cut-back."""
    scene = get_scene("elastica", ["n_increments=5", "max_cutbacks=0"])
    res = run_scene(scene, mpi_tmp, progress=False)
    assert res.completed
    row = read_history(mpi_tmp / "history.csv")[-1]
    assert -row["tip_uy"] / scene.L == pytest.approx(ELASTICA[5.0][0], rel=1e-2)

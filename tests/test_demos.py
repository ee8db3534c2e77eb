"""The demo scripts run as a user runs them (a process of their own, serial and on two ranks), leave
their pictures and XDMF file, pass their own checks (exit status 0) and end where the physics puts
them: the beam's tip and the plate's centre rest on the obstacle (displacement = gap, to the
penalty's penetration), the crushed ring carries more than the rigid-perfectly-plastic ring
(DeRunz-Hodge), two ranks give the serial history, and the released ring keeps its plastic strain,
springs back and, pressed again without friction, carries its load again."""
import csv
import math
import pathlib
import re

import launch
import pytest

DEMOS = pathlib.Path(__file__).resolve().parent.parent / "demos"


def read_history(path):
    with open(path, newline="") as fh:
        return [{k: float(v) for k, v in row.items()} for row in csv.DictReader(fh)]


def _demo(name, out, args=(), n=1, pictures=None):
    p = launch.run([DEMOS / f"demo_{name}.py", "--out", out, *args], n=n)
    assert p.returncode == 0, p.stdout + p.stderr
    for f in ["results.pvd", "results_00000.vtu", "history.csv", *(pictures or [f"{name}_shapes.png",
                                                                         f"{name}_curves.png"])]:
        assert (out / f).is_file(), f
    return p.stdout, read_history(out / "history.csv")


@pytest.mark.parametrize("name, column, gap", [("beam", "tip_uy", 3.0), ("plate", "center_uz", 1.5)])
def test_elastic_demos_end_on_the_obstacle(tmp_path, name, column, gap):
    out, hist = _demo(name, tmp_path, ["--size", "0.25"])
    assert "OK" in out
    assert -hist[-1][column] == pytest.approx(gap, abs=1e-3)
    assert hist[-1]["contact_force"] > 0


def test_ring_demo_above_rigid_plastic_and_same_on_two_ranks(tmp_path):
    """A hardening ring carries more than the rigid-perfectly-plastic ring of DeRunz and Hodge once it
    has collapsed: P >= P0 / sqrt(1 - (delta / D)^2), P0 = 4 M_p / R with the plane-strain fully
    plastic moment M_p = (2 / sqrt 3) sigma_0 t^2 / 4 of the initial yield stress (docs/theory.md 8.6)."""
    out, serial = _demo("ring", tmp_path / "np1")
    t, R_out, s0 = 0.866, 5.715, 2800.0
    R = R_out - t / 2
    P0 = 4 * (2 / math.sqrt(3)) * s0 * t ** 2 / 4 / R
    collapsed = [row for row in serial if row["load"] >= 1.0]
    assert len(collapsed) > 20
    for row in collapsed:
        assert row["force"] > P0 / math.sqrt(1 - (row["load"] / (2 * R)) ** 2), row
    # the zone leaves the crown: its inner edge moves off x = 0
    assert serial[-1]["zone_min"] > 1.0 and serial[0]["zone_min"] == pytest.approx(0.0, abs=1e-12)
    # the lift-off printed (the crown's geometric gap opening for good, interpolated) falls between
    # the last increment whose contact pressure still reaches the crown and the first that does not
    split = float(re.search(r"crown lifts off at delta = ([0-9.]+)", out).group(1))
    first_off = next(k for k, row in enumerate(serial) if row["zone_min"] > 1e-9)
    assert serial[first_off - 1]["load"] - 1e-3 <= split < serial[first_off]["load"], out
    _, parallel = _demo("ring", tmp_path / "np2", n=2)
    assert len(parallel) == len(serial)
    for a, b in zip(serial, parallel):
        assert b["force"] == pytest.approx(a["force"], rel=1e-6)


def test_springback_demo(tmp_path):
    """Released, the ring springs back by a small fraction of the approach, keeps its plastic strain
    and no force; pressed again without friction it carries its load again (an elastic path is
    reversible: within 0.5 %)."""
    out, h = _demo("springback", tmp_path, ["--mu", "0"], pictures=["springback.png"])
    assert "OK" in out
    top = max(range(len(h)), key=lambda k: h[k]["force"] if h[k]["time"] <= 1.0 else -1)
    free = [row for row in h if abs(row["time"] - 3.0) < 1e-9][0]
    springback = free["height"] - h[top]["height"]
    assert 0.0 < springback < 0.05 * 6.6
    assert free["max_plastic_strain"] == pytest.approx(h[top]["max_plastic_strain"], rel=1e-2)
    assert abs(free["force"]) < 1e-6 * h[top]["force"]
    assert h[-1]["force"] == pytest.approx(h[top]["force"], rel=5e-3)

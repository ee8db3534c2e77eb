"""The tube demo (demos/demo_tube.py) runs as a user runs it (a process of its own), writes its
history, VTK files and chart, passes its own check (exit status 0), and its history holds what that
check claims, recomputed here from the recorded columns:

* the energy balance: the indenter's work, the trapezoidal integral of the force over the travel,
  equals the elastic energy plus the plastic and friction dissipation of the final state (1 %);
* the force rises with the travel at every increment (a hardening tube under a deepening dent);
* the top of the tube under the indenter follows it: the dent's depth at the end is the travel, to
  the penalty's penetration.
"""
import csv
import pathlib

import launch
import pytest

DEMOS = pathlib.Path(__file__).resolve().parent.parent / "demos"


def read_history(path):
    with open(path, newline="") as fh:
        return [{k: float(v) for k, v in row.items()} for row in csv.DictReader(fh)]


def test_tube_demo_energy_balance_and_rising_force(tmp_path):
    """A steel tube (r_out = 30 mm, wall 6 mm, J2 with hardening) dented 2 mm by a rigid transverse
    cylinder (R = 10 mm, friction 0.1), a quarter in P2 tetrahedra."""
    p = launch.run([DEMOS / "demo_tube.py", "--out", tmp_path])
    assert p.returncode == 0, p.stdout + p.stderr
    assert "OK" in p.stdout, p.stdout
    for f in ["history.csv", "results.pvd", "results_00000.vtu", "tube.png"]:
        assert (tmp_path / f).is_file(), f
    h = read_history(tmp_path / "history.csv")
    travel, force = [0.0] + [r["travel"] for r in h], [0.0] + [r["force"] for r in h]
    work = sum(0.5 * (force[k] + force[k + 1]) * (travel[k + 1] - travel[k]) for k in range(len(h)))
    end = h[-1]
    assert end["travel"] == pytest.approx(2.0, rel=1e-12)
    assert end["max_plastic_strain"] > 0.01                 # a plastic dent
    assert end["plastic_dissipation"] > 0 and end["friction_dissipation"] >= 0
    stored = end["elastic_energy"] + end["plastic_dissipation"] + end["friction_dissipation"]
    assert stored == pytest.approx(work, rel=0.01)
    assert all(b > a for a, b in zip(force, force[1:])), force
    assert end["dent"] == pytest.approx(end["travel"], abs=0.005)

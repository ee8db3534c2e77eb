"""The ironing and seal demos run as a user runs them (a process of their own), write their history,
XDMF file and chart, pass their own checks (exit status 0), and their histories hold what those
checks claim, recomputed here from the recorded forces with the demos' own tolerances:

* ironing: at the end of the indentation the contact half-width and peak pressure are Hertz's for
  the computed force (5 %), and in full slip the tangential force is mu times the normal force (3 %);
* seal: at small squeeze (approach <= 2.5 % of the diameter) the force is that of the closed form
  for a cylinder between two plates (2 %), and the contact half-width is Hertz's for that force
  within a quarter of the crown's element size wherever the zone spans two elements.
"""
import csv
import math
import pathlib

import launch
import pytest

DEMOS = pathlib.Path(__file__).resolve().parent.parent / "demos"


def read_history(path):
    with open(path, newline="") as fh:
        return [{k: float(v) for k, v in row.items()} for row in csv.DictReader(fh)]


def _demo(name, out):
    p = launch.run([DEMOS / f"demo_{name}.py", "--out", out])
    assert p.returncode == 0, p.stdout + p.stderr
    assert "OK" in p.stdout, p.stdout
    for f in ["history.csv", "results.pvd", "results_00000.vtu", f"{name}.png"]:
        assert (out / f).is_file(), f
    return read_history(out / "history.csv")


def test_ironing_demo_hertz_then_coulomb(tmp_path):
    """A rigid cylinder (R = 2) pressed 0.2 mm into a 4 x 1 block (E = 1000, nu = 0.3, plane strain),
    then dragged 8 mm with mu = 0.2 (demos/demo_ironing.py)."""
    h = _demo("ironing", tmp_path)
    E, nu, R, H, mu, drag = 1000.0, 0.3, 2.0, 1.0, 0.2, 0.8
    Es = E / (1 - nu ** 2)
    end = [r for r in h if abs(r["time"] - 1.0) < 1e-9]
    assert len(end) == 1                                   # the indentation step ended at time 1
    end = end[0]
    P = -end["contact_fy"]
    a = math.sqrt(4 * P * R / (math.pi * Es))              # Hertz: rigid cylinder on a half-space
    assert 0.1 < a / H < 0.25 and a / R < 0.1              # a contact small against block and cylinder
    assert end["half_width"] == pytest.approx(a, rel=0.05)
    assert end["p_max"] == pytest.approx(2 * P / (math.pi * a), rel=0.05)
    sliding = [r for r in h if r["time"] > 1.0 and r["slip_share"] >= 0.99]
    assert len(sliding) >= 8                               # full slip developed and lasted
    for r in sliding:
        assert r["contact_fx"] > 0                         # friction drags the block along (+x)
        assert r["contact_fx"] == pytest.approx(mu * -r["contact_fy"], rel=0.03)
    # the first increment of the drag is still partly stuck: full slip is not there from the start
    first_drag = next(r for r in h if r["time"] > 1.0)
    assert first_drag["slip_share"] < 0.99
    assert first_drag["contact_fx"] < 0.9 * mu * -first_drag["contact_fy"]
    assert h[-1]["travel"] == pytest.approx(drag, rel=1e-9)  # the drag ran to its end


def _cylinder_between_plates(delta, R, Es):
    """Force per unit length P for the approach delta of two rigid plates squeezing a cylinder:
    delta = (2 P / (pi Es)) (2 ln(4 R / a) - 1), a = sqrt(4 P R / (pi Es)); bisection in log P
    (delta grows with P while a < 4 R / e)."""
    def approach(P):
        a = math.sqrt(4 * P * R / (math.pi * Es))
        return 2 * P / (math.pi * Es) * (2 * math.log(4 * R / a) - 1)
    lo, hi = 1e-12, 1e3
    for _ in range(200):
        mid = math.sqrt(lo * hi)
        lo, hi = (mid, hi) if approach(mid) < delta else (lo, mid)
    return math.sqrt(lo * hi)


def test_seal_demo_closed_form_force_and_width(tmp_path):
    """An O-ring section (R = 1, E = 10, nu = 0.45, neo-Hooke) squeezed by 25 % of its diameter
    between frictionless rigid plates, a quarter meshed from demos/seal.geo (demos/demo_seal.py)."""
    h = _demo("seal", tmp_path)
    assert (tmp_path / "seal.msh").is_file()               # the demo meshed seal.geo itself
    R, E, nu = 1.0, 10.0, 0.45
    Es = E / (1 - nu ** 2)
    small = [r for r in h if r["approach"] / (2 * R) <= 0.025]
    assert len(small) >= 3
    for r in small:
        P = -2.0 * r["plate_fy"]                           # the whole plate: twice the quarter's
        assert P == pytest.approx(_cylinder_between_plates(r["approach"], R, Es), rel=0.02), r
    h_crown = 0.015                                        # size_top in demos/seal.geo
    spans = 0
    for r in small:
        a = math.sqrt(4 * (-2.0 * r["plate_fy"]) * R / (math.pi * Es))   # Hertz's half-width
        if a >= 2 * h_crown:
            spans += 1
            assert abs(r["half_width"] - a) <= 0.25 * h_crown, r
    assert spans >= 3
    for r in h:
        assert r["plate_fy"] < 0                           # the plate pushes down
    assert h[-1]["approach"] == pytest.approx(0.25 * 2 * R, rel=1e-9)   # squeezed to 25 %

"""Hertz line contact: an elastic cylinder pressed onto a rigid flat (plane strain).

The cylinder (R = 1, E = 1000, nu = 0.3) is modelled by the quarter x >= 0 of its lower half
(``cm.quarter_disc``: the arc touches y = 0 at the origin; xsym held in x), its flat top pushed
down by d = 0.0095 in two increments onto the frictionless rigid plane y = 0 (Nitsche, gamma0 = 10).
For the force P per unit length of the whole cylinder (twice the quarter's, ContactForce), Hertz's
line contact has the half-width a = sqrt(4 P R / (pi E*)), E* = E / (1 - nu^2), the peak pressure
p0 = 2 P / (pi a) and the pressure p0 sqrt(1 - x^2 / a^2) [Johnson 1985, ch. 4 and 5]; here
a / R = 0.074.

Measures: a is the current length of the contact set of the quarter (ContactLength: the boundary
where the pressure at the facet quadrature points is positive, 4 Gauss points per facet); p0 the
largest nodal contact pressure (``contact.update_fields()``, the lumped projection of the pressure
per current area); the profile's deviation is the root mean square over the nodes inside x < a of
p - p0_Hertz sqrt(1 - x^2/a^2), relative to p0_Hertz, with x the current coordinate (the reference
one for the small-strain update, whose theory does not tell the two apart: the surface moves
sideways by about 1 % of a within the contact).

The series refines the contact zone (element size h_c within 0.15 of the origin, 0.1 far away);
the checks are those of its finest mesh: a and p0 within 1 %, the profile within 2 %. With
``small`` the series stops at h_c = 0.005 (about 15 elements across a), where a, p0 and the profile
are held to 2 % (measured: at most 0.6 %, 0.5 % and 1.3 %). The rows run with the finite-strain S-R
update (``sr_log``, the default) and again with the small-strain update.
"""
from __future__ import annotations

import pathlib

import numpy as np
from mpi4py import MPI

from . import Check
from .common import profile, run_job, save_figure

NAME = "hertz_line"
TITLE = "Hertz line contact"
SOURCE = "Johnson 1985, ch. 4 and 5"

R, E, NU, DEPTH = 1.0, 1000.0, 0.3, 0.0095
ES = E / (1 - NU ** 2)
SERIES = (0.02, 0.01, 0.005, 0.0025)           # element size in the contact zone
SMALL_SERIES = (0.02, 0.01, 0.005)


def hertz(P: float) -> tuple[float, float]:
    """(a, p0) of Hertz's line contact under P per unit length."""
    a = np.sqrt(4 * P * R / (np.pi * ES))
    return float(a), float(2 * P / (np.pi * a))


def _press(hc: float, update: str, out: pathlib.Path, comm) -> dict:
    """One run on the mesh of contact size hc: P, a, p0, the profile, Newton its, CPU s."""
    import comove_dolfinx as cm
    mesh = cm.quarter_disc(R, 0.1, hc, 0.15, comm=comm, cache_dir=out / "meshes")
    body = cm.Body(mesh, "plane_strain", cm.Elastic(E, NU), update=update)
    contact = cm.Contact("contact", cm.Plane((0.0, 0.0), (0.0, 1.0)), method="nitsche", gamma0=10.0)
    keep = {}

    class Profile(cm.Writer):
        def write(self, run, row, increment):
            keep["x"], keep["p"] = profile(contact, run.model, current=update != "small_strain")

    job = cm.Job(body, [cm.Fixed("xsym", component=0), cm.Displacement("top", -DEPTH, component=1), contact],
                 [cm.Step(2)], probes=[cm.ContactForce(contact, "P", component=1, scale=2.0),
                                       cm.ContactLength(contact, "a")], writers=[Profile()])
    res, its, cpu = run_job(job, comm)
    P = res.last["P"]
    a_h, p0_h = hertz(P)
    x, p = keep["x"], keep["p"]
    inside = x < a_h
    dev = float(np.sqrt(np.mean((p[inside] - p0_h * np.sqrt(1 - (x[inside] / a_h) ** 2)) ** 2)) / p0_h)
    return dict(hc=hc, update=update, dofs=res.dofs, P=P, a_hertz=a_h, a=res.last["a"], p0_hertz=p0_h,
                p0=float(p.max()), profile_rms=dev, newton_its=its, cpu_s=cpu, x=x, p=p)


def run(out: pathlib.Path, small: bool = False) -> list[Check]:
    comm = MPI.COMM_WORLD
    out = pathlib.Path(out)
    series = SMALL_SERIES if small else SERIES
    tol, tol_profile = (0.02, 0.02) if small else (0.01, 0.02)
    rows, checks = [], []
    for update, label in (("sr_log", "finite strain (sr_log)"), ("small_strain", "small strain")):
        runs = [_press(hc, update, out, comm) for hc in series]
        rows += runs
        f = runs[-1]
        n_across = f["a_hertz"] / f["hc"]
        where = f"{label}, h = a/{n_across:.0f}"
        its, cpu = sum(r["newton_its"] for r in runs), sum(r["cpu_s"] for r in runs)
        checks += [Check(TITLE, SOURCE, f"{where}: half-width a", f["a_hertz"], f["a"], tol, its, cpu),
                   Check(TITLE, SOURCE, f"{where}: peak pressure p0", f["p0_hertz"], f["p0"], tol, its, cpu),
                   Check(TITLE, SOURCE, f"{where}: profile, rms deviation / p0", 0.0, f["profile_rms"],
                         tol_profile, its, cpu)]
    _series_table(out, rows, comm)
    _plot(out, rows, comm)
    return checks


def _series_table(out, rows, comm):
    """out/hertz_line_series.csv and .md: the convergence series."""
    if comm.rank != 0:
        return
    from ..io.csv_tables import write_table
    keys = ("update", "hc", "dofs", "P", "a_hertz", "a", "p0_hertz", "p0", "profile_rms", "newton_its", "cpu_s")
    table = [{k: r[k] for k in keys} | {"a_error": r["a"] / r["a_hertz"] - 1, "p0_error": r["p0"] / r["p0_hertz"] - 1}
             for r in rows]
    write_table(out / f"{NAME}_series.csv", table)
    lines = ["| update | h in the contact zone | a / h | dofs | P | a (Hertz) | a | error | p0 (Hertz) | p0 | error "
             "| profile rms / p0 | Newton its | CPU s |", "|" + "---|" * 14]
    for r in table:
        lines.append(f"| {r['update']} | {r['hc']:g} | {r['a_hertz'] / r['hc']:.1f} | {r['dofs']} | {r['P']:.5g} | "
                     f"{r['a_hertz']:.5f} | {r['a']:.5f} | {100 * r['a_error']:+.2f} % | {r['p0_hertz']:.4g} | "
                     f"{r['p0']:.4g} | {100 * r['p0_error']:+.2f} % | {100 * r['profile_rms']:.2f} % | "
                     f"{r['newton_its']} | {r['cpu_s']:.1f} |")
    (out / f"{NAME}_series.md").write_text("\n".join(lines) + "\n")


def _plot(out, rows, comm):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, (a0, a1) = plt.subplots(1, 2, figsize=(11, 4.2))
    sr = [r for r in rows if r["update"] == "sr_log"]
    for r, mark in zip(sr, "v^so"):
        a0.plot(r["x"] / r["a_hertz"], r["p"] / r["p0_hertz"], mark, ms=3.5, mfc="none",
                label=f"h = {r['hc']:g} (a/h = {r['a_hertz'] / r['hc']:.0f})")
    s = np.linspace(0, 1, 200)
    a0.plot(s, np.sqrt(1 - s ** 2), "k-", lw=1, label="Hertz p0 sqrt(1 - x^2/a^2)")
    a0.set_xlim(0, 1.6)
    a0.set_xlabel("current x / a (Hertz, at the computed force)")
    a0.set_ylabel("contact pressure / p0 (Hertz)")
    a0.set_title(f"pressure profile, R = {R:g}, E = {E:g}, nu = {NU:g}, d = {DEPTH:g}", fontsize=9)
    a0.legend(fontsize=8)
    for update, ls in (("sr_log", "-"), ("small_strain", "--")):
        rr = [r for r in rows if r["update"] == update]
        if not rr:
            continue
        h = np.array([r["hc"] for r in rr])
        a1.plot(h, [100 * (r["a"] / r["a_hertz"] - 1) for r in rr], "o" + ls, label=f"a, {update}")
        a1.plot(h, [100 * (r["p0"] / r["p0_hertz"] - 1) for r in rr], "s" + ls, label=f"p0, {update}")
        a1.plot(h, [100 * r["profile_rms"] for r in rr], "^" + ls, label=f"profile rms / p0, {update}")
    for y in (-1, 1):
        a1.axhline(y, color="k", ls=":", lw=0.8)
    a1.set_xscale("log")
    hs = sorted({r["hc"] for r in rows})
    a1.set_xticks(hs, [f"{h:g}" for h in hs])
    a1.minorticks_off()
    a1.set_xlabel("element size in the contact zone")
    a1.set_ylabel("error against Hertz (%)")
    a1.set_title("convergence series (dotted: the 1 % tolerance of a and p0)", fontsize=9)
    a1.legend(fontsize=8)
    fig.tight_layout()
    save_figure(fig, out, NAME, comm)

"""Spherical indentation of an elastic-perfectly plastic block (axisymmetric): Hertz, then Tabor.

A rigid sphere of radius R = 1 (``cm.Circle`` in the r-z plane, its centre on the axis) is pressed
into a cylindrical block of radius and height 2 (axisymmetric, J2 perfectly plastic: E = 1000,
nu = 0.3, yield stress Y = 1, a metal's E / Y; finite strain, S-R update), whose base is held and
whose axis is held in r. The contact is frictionless (Nitsche, gamma0 = 10). The mesh is graded
about the first point of contact, the element size 0.1 times the distance to it (down to a tenth of
the first contact radius), so that every contact radius of the run is resolved by about the same
number of elements.

Two stages [Johnson 1985, ch. 4 and 6]:

* Elastic: first yield under a sphere comes at p0 = 1.60 Y (nu = 0.3), i.e. at the depth
  d_y = R (1.60 pi Y / (2 E*))^2 = 5.2e-6 R, E* = E / (1 - nu^2). At d = d_y / 2 (two increments)
  the force is Hertz's P = (4/3) E* sqrt(R) d^(3/2) (d the sphere's travel; the block is 1000
  contact radii deep, so its own compliance is negligible): checked within 2 %, with no plastic
  strain anywhere.
* Fully plastic: the sphere then goes down to d = 0.006 R in increments growing geometrically. As
  E* a / (R Y) passes about 40 the plastic zone reaches the surface around the contact, and the mean
  pressure p_m = P / (pi a^2) levels off at the hardness, 2.8 to 3 times the yield stress [Tabor
  1951]. The increments from E* a / (R Y) = 60 to the last (about 126) lie well beyond: the mean
  pressure of their least-squares fit P = p_m pi a^2 (the contact radius of a single increment is
  resolved to a few per cent of itself, so single increments scatter by +-3 %) is checked against
  2.9 Y within 3.5 %, i.e. inside Tabor's band. This is a plausibility band from experiments and slip
  line estimates [Tabor 1951; Johnson 1985, ch. 6], not a closed form.

Measures: P from ContactForce (total over the circumference), a from ContactLength (the current
radius of the contact disc), d the sphere's travel. With ``small`` the grading is 0.2 times the
distance (coarser, 5 elements across each radius) and the elastic check is held to 4 %; the plastic
band is the same.
"""
from __future__ import annotations

import math
import pathlib

import numpy as np
from mpi4py import MPI

from . import Check
from .common import run_job, save_figure

NAME = "indentation"
TITLE = "Spherical indentation"
SOURCE = "Johnson 1985, ch. 4 and 6; Tabor 1951"

R, E, NU, Y = 1.0, 1000.0, 0.3, 1.0
W = H = 2.0
ES = E / (1 - NU ** 2)
D_YIELD = R * (1.60 * math.pi * Y / (2 * ES)) ** 2
D_ELASTIC, D_MAX = 0.5 * D_YIELD, 0.006 * R
TABOR, TABOR_TOL = 2.9, 0.035          # 2.8 to 3.0
PLATEAU = 60.0                         # E* a / (R Y) beyond which the mean pressure is fitted


def hertz_force(d: float) -> float:
    """Hertz's force of a rigid sphere pressed d into an elastic half-space."""
    return 4.0 / 3.0 * ES * math.sqrt(R) * d ** 1.5


def _mesh(cache_dir: pathlib.Path, grading: float, comm):
    """The block [0, W] x [0, H] (r, z), triangles of size grading x the distance to (0, H), at least
    a tenth of the elastic stage's contact radius; facet groups axis, bottom, right, top."""
    from ..geometry.gmsh_session import gmsh
    from ..geometry.meshes import BODY_TAG, add_group, build_cached

    def construct() -> None:
        geo = gmsh.model.geo
        p = [geo.addPoint(x, y, 0) for x, y in [(0, 0), (W, 0), (W, H), (0, H)]]
        bottom, right, top, axis = (geo.addLine(p[i], p[(i + 1) % 4]) for i in range(4))
        surface = geo.addPlaneSurface([geo.addCurveLoop([bottom, right, top, axis])])
        geo.synchronize()
        hmin = 0.1 * math.sqrt(R * D_ELASTIC)
        field = gmsh.model.mesh.field
        f = field.add("MathEval")
        field.setString(f, "F", f"min(max({hmin}, {grading} * sqrt(x^2 + (y - {H})^2)), 0.25)")
        field.setAsBackgroundMesh(f)
        for option in ("MeshSizeExtendFromBoundary", "MeshSizeFromPoints", "MeshSizeFromCurvature"):
            gmsh.option.setNumber(f"Mesh.{option}", 0)
        add_group(2, [surface], BODY_TAG, "body")
        for tag, (name, curve) in enumerate([("axis", axis), ("bottom", bottom), ("right", right),
                                             ("top", top)], start=1):
            add_group(1, [curve], tag, name)

    params = dict(W=W, H=H, R=R, grading=float(grading), order=2)
    return build_cached("indentation_block", params, construct, comm, cache_dir)


def run(out: pathlib.Path, small: bool = False) -> list[Check]:
    import comove_dolfinx as cm
    comm = MPI.COMM_WORLD
    out = pathlib.Path(out)
    grading = 0.2 if small else 0.1
    tol_hertz = 0.04 if small else 0.02
    mesh = _mesh(out / "meshes", grading, comm)
    body = cm.Body(mesh, "axisymmetric", cm.J2(E, NU, cm.Hardening.perfect(Y)))
    sphere = cm.Circle((0.0, H + R), R, motion=(0.0, -D_MAX))
    contact = cm.Contact("top", sphere, method="nitsche", gamma0=10.0)
    f1 = D_ELASTIC / D_MAX
    steps = [cm.Step(2, ramp={contact: f1}, name="elastic"),
             cm.Step(24 if small else 40, ramp={contact: lambda s: f1 * (1 / f1) ** s}, name="plastic")]
    probes = [cm.ContactForce(contact, "P", component=1, scale=-1.0), cm.ContactLength(contact, "a"),
              cm.MaxPlasticStrain(), cm.Value("d", lambda model: -sphere.displacement(contact.factor)[1])]
    job = cm.Job(body, [cm.Fixed("bottom"), cm.Fixed("axis", component=0), contact], steps, probes)
    res, its, cpu = run_job(job, comm)
    d, P, a, ep = res["d"], res["P"], res["a"], res["max_plastic_strain"]
    elastic = int(np.argmin(np.abs(d - D_ELASTIC)))
    pm = P / (np.pi * a ** 2)
    # fully plastic: p_m from the least-squares fit P = p_m pi a^2 over the increments beyond
    # E* a / (R Y) = PLATEAU (a single increment's a is resolved to a few per cent of itself)
    full = ES * a / (R * Y) >= PLATEAU
    pm_fit = float(np.sum(P[full] * a[full] ** 2) / (np.pi * np.sum(a[full] ** 4)))
    checks = [
        Check(TITLE, SOURCE, f"elastic, d = d_y/2 = {D_ELASTIC:.3g}: force against (4/3) E* sqrt(R) d^1.5",
              hertz_force(d[elastic]), P[elastic], tol_hertz, its, cpu),
        Check(TITLE, SOURCE, "elastic, d = d_y/2: largest plastic strain (absolute)", 0.0, ep[elastic], 1e-12,
              its, cpu),
        Check(TITLE, SOURCE, f"fully plastic, E* a/(R Y) = {PLATEAU:g} to {ES * a[-1] / (R * Y):.0f} "
              f"({int(full.sum())} increments): mean pressure / Y (Tabor's band 2.8-3.0)", TABOR, pm_fit / Y,
              TABOR_TOL, its, cpu),
    ]
    if comm.rank == 0:
        from ..io.csv_tables import write_table
        write_table(out / f"{NAME}_history.csv",
                    [{"d": di, "P": Pi, "a": ai, "p_m/Y": pmi / Y, "E*a/(RY)": ES * ai / (R * Y),
                      "max_plastic_strain": e, "newton_its": n}
                     for di, Pi, ai, pmi, e, n in zip(d, P, a, pm, ep, res["newton_its"])])
    _plot(out, d, P, a, pm_fit, comm)
    return checks


def _plot(out, d, P, a, pm_fit, comm):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, (a0, a1) = plt.subplots(1, 2, figsize=(11, 4.2))
    dd = np.geomspace(d.min(), d.max(), 100)
    a0.loglog(d / R, P, "o", ms=4, mfc="none", label="computed (J2, perfectly plastic)")
    a0.loglog(dd / R, [hertz_force(x) for x in dd], "k-", lw=1, label="Hertz, elastic")
    a0.axvline(D_YIELD / R, color="0.5", ls=":", lw=1, label="first yield (p0 = 1.60 Y)")
    a0.set_xlabel("indentation depth d / R")
    a0.set_ylabel("force P")
    a0.set_title(f"rigid sphere R = {R:g} into a block: E = {E:g}, nu = {NU:g}, Y = {Y:g}", fontsize=9)
    a0.legend(fontsize=8)
    x = ES * a / (R * Y)
    a1.semilogx(x, P / (np.pi * a ** 2) / Y, "o", ms=4, mfc="none", label="computed P / (pi a^2 Y)")
    a1.semilogx([PLATEAU, x.max()], [pm_fit / Y] * 2, "C3-", lw=2, label=f"fit beyond {PLATEAU:g}: {pm_fit / Y:.3f}")
    xs = np.geomspace(x.min(), math.pi * 1.60 / 2, 50)       # up to first yield
    a1.semilogx(xs, 4 / (3 * math.pi) * xs, "k-", lw=1, label="Hertz: p_m = (2/3) p0, to first yield")
    a1.axhspan(2.8, 3.0, color="0.88", label="Tabor 1951: 2.8-3.0")
    a1.set_xlabel("E* a / (R Y)")
    a1.set_ylabel("mean contact pressure / Y")
    a1.set_ylim(0, 3.5)
    a1.set_title("mean pressure over the yield stress", fontsize=9)
    a1.legend(fontsize=8, loc="lower right")
    fig.tight_layout()
    save_figure(fig, out, NAME, comm)

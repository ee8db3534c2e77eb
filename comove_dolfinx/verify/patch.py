"""The contact patch test: an elastic block pressed by a uniform pressure onto a rigid flat.

A block L x H (plane strain, E = 1000, nu = 0.3, units arbitrary but consistent) lies on the
frictionless rigid plane y = 0 and carries a follower pressure p = 20 on its top face; its left face
is held in x only. The exact solution is homogeneous (a uniform compression, finite strain
included): the contact pressure is p at every point of the bottom face and the contact force p times
the face's current width. A method passes the patch test when it reproduces this state to
round-off on a mesh that has nothing regular about it [Taylor and Papadopoulos 1991].

* Nitsche's method is consistent: the homogeneous state satisfies its equations whatever the
  weight gamma = gamma0 E / h of each facet, so it is run on a fully unstructured mesh (triangles
  of every size and shape along the contact face).
* The penalty method's pressure is gamma times the penetration. The homogeneous state has a uniform
  penetration p / gamma, so it is reproduced only where gamma is the same on every facet, i.e. where
  the cells along the contact face share one diameter h: it is run on a mesh whose cells on the
  face are congruent (one structured row), unstructured above. On the fully unstructured mesh the
  penalty's pressure follows h (shown in the picture, not checked); its total force is still exact.

Measures: the nodal contact pressure along the bottom face (``contact.update_fields()``, a lumped
projection of the quadrature points' pressure per current area, which reproduces a uniform pressure
exactly), its largest and smallest value against p (1e-8 relative); the same at the facet quadrature
points, where the contact law is evaluated (``contact.profile()``); and the contact force (ContactForce, from the residual) against p times the current
width of the top face (1e-8).
"""
from __future__ import annotations

import pathlib

import numpy as np
from mpi4py import MPI

from . import Check
from .common import profile, run_job, save_figure, triangles

NAME = "patch"
TITLE = "Contact patch test"
SOURCE = "Taylor & Papadopoulos 1991"

L, H, E, NU, P = 2.0, 1.0, 1000.0, 0.3, 20.0
TOL = 1e-8


def _mesh(cache_dir: pathlib.Path, strip: bool, size: float, comm):
    """The block meshed by gmsh: unstructured triangles whose size varies from corner to corner;
    with ``strip``, one structured row of congruent triangles along the bottom. Facet groups left,
    right, bottom, top."""
    from ..geometry.gmsh_session import gmsh
    from ..geometry.meshes import BODY_TAG, add_group, build_cached

    def construct() -> None:
        geo = gmsh.model.geo
        t = size if strip else 0.0
        sizes = [0.45 * size, 1.6 * size, 0.7 * size, 1.3 * size]    # irregular on purpose
        if strip:
            sizes[:2] = [size, size]
        corners = [(0, 0), (L, 0), (L, H), (0, H)]
        p = [geo.addPoint(x, y, 0, s) for (x, y), s in zip(corners, sizes)]
        bottom = geo.addLine(p[0], p[1])
        top, left_up = geo.addLine(p[2], p[3]), None
        surfaces = []
        if strip:
            q = [geo.addPoint(L, t, 0, size), geo.addPoint(0, t, 0, size)]
            right_low, mid, left_low = geo.addLine(p[1], q[0]), geo.addLine(q[0], q[1]), geo.addLine(q[1], p[0])
            right_up, left_up = geo.addLine(q[0], p[2]), geo.addLine(p[3], q[1])
            low = geo.addPlaneSurface([geo.addCurveLoop([bottom, right_low, mid, left_low])])
            n = int(round(L / size))
            for c, k in ((bottom, n), (mid, n), (right_low, 1), (left_low, 1)):
                geo.mesh.setTransfiniteCurve(c, k + 1)
            geo.mesh.setTransfiniteSurface(low, "AlternateLeft")
            up = geo.addPlaneSurface([geo.addCurveLoop([-mid, right_up, top, left_up])])
            surfaces = [low, up]
            rights, lefts = [right_low, right_up], [left_low, left_up]
        else:
            right, left = geo.addLine(p[1], p[2]), geo.addLine(p[3], p[0])
            surfaces = [geo.addPlaneSurface([geo.addCurveLoop([bottom, right, top, left])])]
            rights, lefts = [right], [left]
        geo.synchronize()
        add_group(2, surfaces, BODY_TAG, "body")
        for tag, (name, curves) in enumerate([("left", lefts), ("right", rights), ("bottom", [bottom]),
                                              ("top", [top])], start=1):
            add_group(1, curves, tag, name)
        gmsh.option.setNumber("Mesh.Algorithm", 5)

    params = dict(L=L, H=H, size=float(size), strip=bool(strip), order=2)
    return build_cached("patch_block", params, construct, comm, cache_dir)


def _press(mesh, method: str, comm):
    """One run: (x, p along the bottom, contact force, top's current width, Newton its, CPU s)."""
    import comove_dolfinx as cm
    body = cm.Body(mesh, "plane_strain", cm.Elastic(E, NU))
    contact = cm.Contact("bottom", cm.Plane((0.0, 0.0), (0.0, 1.0)), method=method,
                         gamma0=100.0 if method == "penalty" else 10.0)
    keep = {}

    class Keep(cm.Writer):
        def write(self, run, row, increment):
            keep["x"], keep["p"] = profile(contact, run.model)
            # the pressure at the facet quadrature points, where the contact law is evaluated
            keep["pq"] = contact.profile().p
            X = run.model.V.tabulate_dof_coordinates()[:, 0]
            x = X + run.model.u.x.array.reshape(-1, 2)[:, 0]
            keep["width"] = (run.model.comm.allreduce(float(x.max()), op=MPI.MAX)
                             - run.model.comm.allreduce(float(x.min()), op=MPI.MIN))

    job = cm.Job(body, [cm.Fixed("left", component=0), cm.Pressure("top", P), contact], [cm.Step(2)],
                 probes=[cm.ContactForce(contact, "force", component=None)], writers=[Keep()],
                 newton=cm.NewtonSettings(rtol=1e-12, atol=1e-11))
    res, its, cpu = run_job(job, comm)
    F = np.array([res.last["force_fx"], res.last["force_fy"]])
    return keep["x"], keep["p"], keep["pq"], F, keep["width"], its, cpu


def run(out: pathlib.Path, small: bool = False) -> list[Check]:
    comm = MPI.COMM_WORLD
    out = pathlib.Path(out)
    size = 0.25 if small else 0.1
    meshes = {strip: _mesh(out / "meshes", strip, size, comm)
              for strip in (False, True)}
    runs = [("nitsche", False, True), ("penalty", True, True), ("penalty", False, False)]
    checks, curves = [], []
    bench = "Contact patch test"
    for method, strip, uniform in runs:
        x, p, pq, F, width, its, cpu = _press(meshes[strip], method, comm)
        where = "congruent cells on the face" if strip else "unstructured mesh"
        curves.append((f"{method}, {where}", x, p))
        if uniform:
            checks += [Check(bench, SOURCE, f"{method}, {where}: largest contact pressure", P,
                             float(p.max()), TOL, its, cpu),
                       Check(bench, SOURCE, f"{method}, {where}: smallest contact pressure", P,
                             float(p.min()), TOL, its, cpu)]
            for key, fn in (("largest", np.max), ("smallest", np.min)):
                name = f"{method}, {where}: {key} pressure at the quadrature points"
                checks.append(Check(bench, SOURCE, name, P, float(fn(pq)), TOL, its, cpu))
        checks.append(Check(bench, SOURCE, f"{method}, {where}: contact force / current width", P,
                            float(F[1] / width), TOL, its, cpu))
    _plot(out, curves, meshes)
    return checks


def _plot(out, curves, meshes):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    comm = MPI.COMM_WORLD
    fig, (a0, a1) = plt.subplots(1, 2, figsize=(11, 4.2), gridspec_kw={"width_ratios": [1.1, 1]})
    for md, colour in ((meshes[False], "C0"), (meshes[True], "C1")):
        tri = np.concatenate(comm.allgather(triangles(md.mesh)))
        shift = 0.0 if colour == "C0" else L + 0.2
        for t in tri:
            a0.fill(t[:, 0] + shift, t[:, 1], fill=False, ec=colour, lw=0.4)
    a0.set_aspect("equal")
    a0.set_title("meshes: unstructured (left), congruent cells on the face (right)", fontsize=9)
    a0.axis("off")
    for (label, x, p), mark in zip(curves, "os^"):
        a1.semilogy(x, np.maximum(np.abs(p - P) / P, 1e-17), mark + "-", ms=3, lw=0.8, label=label)
    a1.axhline(TOL, color="k", ls=":", lw=0.8, label="tolerance 1e-8")
    a1.set_ylim(1e-17, 1e-1)
    a1.set_xlabel("current x of the bottom face")
    a1.set_ylabel("|p - p_applied| / p_applied  (nodes, floor 1e-17)")
    a1.set_title(f"contact pressure along the flat, p = {P:g}, E = {E:g}", fontsize=9)
    a1.legend(fontsize=8)
    fig.tight_layout()
    save_figure(fig, out, NAME, comm)

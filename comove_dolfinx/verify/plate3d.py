"""3D bodies against the 2D models: the plate scene as a quarter of the disc in tetrahedra.

The plate scene (docs/scenes.md: a thick circular plate R = 10, t = 2, E = 1000, nu = 0.3, under a
follower pressure up to 10 on its top face, the lower part of its rim, z < z_support = 0.25, held in
z, pressed onto a rigid base 1.5 below, mu = 0.1, penalty contact) is run twice: axisymmetric, as the
scene runs it, and as a 3D body, the quarter x, y >= 0 of the disc (``cm.plate_quarter``) in P2
tetrahedra, its symmetry faces held in their normal directions (u_x = 0 on x = 0, u_y = 0 on y = 0,
so the axis is held in both), the rim support held in z, pressed onto the 3D plane z = -1.5 with the
scene's friction, penalty stiffness, increments and Newton settings. Compared at the increments
both runs take (a run that cuts back takes more):

* the centre's deflection (the node at r = 0 on the bottom face), before contact (the increments
  where the axisymmetric base force is 0; in contact it is the gap, -1.5, within the penalty's
  penetration);
* the force on the base (the quarter's vertical contact force x 4; the axisymmetric one is the total
  over the circumference) and the contact radius, where the axisymmetric radius exceeds R / 8 (at
  the first touch, p = 2, both are a small fraction of their final values and hang on the instant
  of touching). The 3D radius is measured along both symmetry edges of the bottom face, on y = 0
  and on x = 0 (``ContactRadius``: the pressure sampled along the edge as along a 2D boundary and
  the edge of the contact set extrapolated as the axisymmetric ``ContactLength`` extrapolates it,
  a straight line in p^2), so that both models measure the same thing; sqrt(4 A / pi) from the
  quarter's contact area A (``ContactArea``) is reported beside them (it lags the edge: the area is
  that of the set where the computed penetration is positive).

The plate's contact is conforming: the bottom leaves the base tangentially, the gap opens slowly
beyond the edge and the pressure stays high up to the last points in contact, so the edge sits
where the discrete solution's last point in contact lies, and it moves by a fraction of the
element at the edge from one mesh to another. The axisymmetric model itself shows how far: at
size 0.25 its radius differs from the reference's (0.0625) by 2.77 % at most, at 0.125 by 1.13 %
(over the same increments): the radius converges like the element size at the edge. So does the
3D quarter's: with 0.25 on the bottom it differs by 2.09 % along both edges (2.66 % from the area),
with 0.1 by 0.90 % (1.21 % from the area), checked within 1 %. The picture's middle panel draws
the three 3D radii.

The axisymmetric reference is the scene at a quarter of its own size (0.0625, 41730 dofs): at its
default size 0.25 its base force is 0.9 % below (3 % at p = 2.5), so the scene's own mesh is no
1 % reference. The 3D mesh: size 0.5 (four elements through the thickness), 0.125 on the rim
support, whose edge (the end of the support at z_support) is a singular point that governs the
plate's stiffness (without it the 3D plate is 0.6 % stiffer before contact and its base force 2.7 %
low), and 0.1 on the bottom face to r = 4.5, where the contact edge moves (170208 dofs). Measured
(largest differences): deflection 0.13 %, force 0.54 %, the contact radius along the two edges
0.90 %, each checked within 1 %.

With ``small`` the scene runs to half its pressure (p = 5 in 10 increments of the scene's size) on
size 1 (0.25 on the rim support, 0.5 on the bottom to r = 3; 26592 dofs) against the axisymmetric
plate at size 0.125; measured 0.25 % (deflection) and 0.91 % (force), checked within 1 % and 1.5 %
(the coarse mesh's force is 2.7 % off without the rim's refinement: the bound is that of the
refined mesh, not of the coarse one), and the contact radius along both edges 4.0 % (4.2 % from
the area), checked within 4.5 %: what the axisymmetric model itself gives at the quarter's bottom
size, 0.5, against the same reference over the same increments (4.45 %).
"""
from __future__ import annotations

import math
import pathlib

import numpy as np
from mpi4py import MPI

from . import Check
from .common import run_job, save_figure

NAME = "plate3d"
TITLE = "The plate as a 3D quarter"
SOURCE = "the axisymmetric plate scene"

#: the 3D mesh (cm.plate_quarter): size 0.5, 0.125 on the rim support, 0.1 on the bottom to r = 4.5
MESH = {"size": 0.5, "size_rim": 0.125, "size_contact": 0.1, "contact_radius": 4.5}
SIZE_2D = 0.0625            # the axisymmetric reference: the scene at a quarter of its size
A_FROM = 0.125              # radius and force compared where the contact radius exceeds A_FROM R
TOL = {"w": 0.01, "F": 0.01, "a": 0.01}
SMALL_MESH = {"size": 1.0, "size_rim": 0.25, "size_contact": 0.5, "contact_radius": 3.0}
SMALL_LOAD = ("p_max=5.0", "n_increments=10")   # the first half of the scene's increments
SMALL_SIZE_2D = 0.125
SMALL_TOL = {"w": 0.01, "F": 0.015, "a": 0.045}


def quarter_job(scene, mesh: dict, comm=MPI.COMM_WORLD):
    """The plate ``scene`` (a presets.Plate) as the quarter x, y >= 0 of the disc in P2 tetrahedra
    (``mesh``: the sizes of ``cm.plate_quarter``); a Job whose history has the load ``p``, the
    centre's deflection, the contact radius and the force on the base."""
    import comove_dolfinx as cm
    md = cm.plate_quarter(scene.R, scene.t, scene.z_support, comm=comm, **mesh)
    body = cm.Body(md, "solid", scene.elastic(), update=scene.update, degree=scene.degree)
    base = cm.Plane((0.0, 0.0, -scene.gap), (0.0, 0.0, 1.0))
    contact = scene.contact_item("bottom", base)
    items = [cm.Fixed("xsym", 0), cm.Fixed("ysym", 1), cm.Fixed("rim_support", 2),
             cm.Pressure("top", scene.p_max), contact]
    probes = [cm.NodeDisplacement("center", (0.0, 0.0, 0.0), component=2, column="center_uz"),
              cm.ContactArea(contact, "quarter_area"),
              cm.ContactRadius(contact, "radius_x", direction=(1.0, 0.0, 0.0)),
              cm.ContactRadius(contact, "radius_y", direction=(0.0, 1.0, 0.0)),
              cm.ContactForce(contact, "contact_force", component=2, scale=4.0)]
    return cm.Job(body, items, scene.steps(), probes, writers=[], newton=scene.newton_settings(),
                  load=lambda f: f * scene.p_max)


def compare(mesh: dict, comm=MPI.COMM_WORLD, size_2d: float = SIZE_2D, overrides: tuple = ()) -> dict:
    """Both runs: each one's load, centre deflection, contact radius and base force, and the
    relative differences at the common increments; dofs, iterations and CPU seconds."""
    from ..presets import get_scene
    scene = get_scene("plate", [f"size={size_2d}", *overrides])
    res2, its2, cpu2 = run_job(scene.job(scene.mesh_data(comm), []), comm)
    res3, its3, cpu3 = run_job(quarter_job(scene, mesh, comm), comm)
    a3 = np.sqrt(4.0 * np.asarray(res3["quarter_area"]) / math.pi)
    two = {"p": res2["load"], "w": res2["center_uz"], "a": res2["contact_radius"], "F": res2["contact_force"]}
    three = {"p": res3["load"], "w": res3["center_uz"], "a_area": a3, "F": res3["contact_force"],
             "a_x": res3["radius_x"], "a_y": res3["radius_y"]}
    common = [(i, int(np.argmin(np.abs(three["p"] - p)))) for i, p in enumerate(two["p"])
              if np.min(np.abs(three["p"] - p)) < 1e-9 * scene.p_max]
    return {"2d": two, "3d": three, "common": common, "R": scene.R, "dofs": (res2.dofs, res3.dofs),
            "its": (its2, its3), "cpu": (cpu2, cpu3)}


def _worst(c: dict, key: str, rows: list) -> float:
    """The largest relative difference of quantity ``key`` over the common increments ``rows``."""
    ref = "a" if key.startswith("a_") else key
    return max(abs(c["3d"][key][j] / c["2d"][ref][i] - 1.0) for i, j in rows)


def run(out: pathlib.Path, small: bool = False) -> list[Check]:
    comm = MPI.COMM_WORLD
    out = pathlib.Path(out)
    mesh, size_2d, overrides, tol = ((SMALL_MESH, SMALL_SIZE_2D, SMALL_LOAD, SMALL_TOL) if small
                                     else (MESH, SIZE_2D, (), TOL))
    c = compare(dict(mesh, cache_dir=out / "meshes"), comm, size_2d, overrides)
    radius = c["R"]
    touching = [(i, j) for i, j in c["common"] if c["2d"]["a"][i] > A_FROM * radius]
    before = [(i, j) for i, j in c["common"] if c["2d"]["F"][i] == 0.0]
    dofs, its, cpu = f"({c['dofs'][1]} dofs against {c['dofs'][0]})", sum(c["its"]), sum(c["cpu"])
    where = f"{len(touching)} increments with a > {A_FROM * radius:g}"
    rows = [("w", f"centre deflection before contact, {len(before)} increments", before),
            ("F", f"force on the base, {where}", touching),
            ("a_x", f"contact radius along the bottom's edge on y = 0, {where}", touching),
            ("a_y", f"contact radius along the bottom's edge on x = 0, {where}", touching)]
    checks = [Check(TITLE, SOURCE, f"{label} {dofs}: largest relative difference", 0.0,
                    _worst(c, key, sel), tol[key[0]], its, cpu) for key, label, sel in rows]
    _plot(out, c, comm)
    if comm.rank == 0:
        print(f"plate3d: contact radius against the axisymmetric one {dofs}, largest relative differences "
              f"over {len(touching)} increments: along y = 0 {_worst(c, 'a_x', touching):.4f}, along x = 0 "
              f"{_worst(c, 'a_y', touching):.4f}, sqrt(4 A / pi) from the contact area "
              f"{_worst(c, 'a_area', touching):.4f} (reported)", flush=True)
    return checks


def _plot(out, c: dict, comm) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(1, 3, figsize=(10.5, 3.6))
    labels = {"w": "centre deflection u_z [cm]", "a": "contact radius a [cm]", "F": "force on the base [kgf]"}
    marks = {"a_x": ("o", "along y = 0"), "a_y": ("x", "along x = 0"), "a_area": ("s", "sqrt(4 A / pi)")}
    for ax, key in zip(axes, ("w", "a", "F")):
        ax.plot(c["2d"]["p"], c["2d"][key], "-", lw=1.2, label=f"axisymmetric ({c['dofs'][0]} dofs)")
        for k3 in (("a_x", "a_y", "a_area") if key == "a" else (key,)):
            m, what = marks.get(k3, ("o", ""))
            ax.plot(c["3d"]["p"], c["3d"][k3], m, ms=3.5, mfc="none",
                    label=f"3D quarter ({c['dofs'][1]} dofs)" if key != "a" else f"3D, {what}")
        ax.set_xlabel("pressure p [kgf/cm^2]")
        ax.set_ylabel(labels[key])
    axes[0].legend(fontsize=8, loc="upper right")
    axes[1].legend(fontsize=7, loc="upper left")
    fig.suptitle("the plate scene, axisymmetric and as a quarter of the disc in P2 tetrahedra", fontsize=9)
    fig.tight_layout()
    save_figure(fig, out, NAME, comm)

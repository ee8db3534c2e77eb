"""3D bodies against the 2D models: the ring scene as a slice of tetrahedra.

The ring scene (docs/scenes.md: a steel ring crushed between rigid plates, J2 with its hardening
table, mu = 0.1, penalty contact) is run twice: as the scene runs it, in 2D, and as a 3D body, a
slice of the quarter ring of thickness t (``cm.tube_sector`` with ``angle = pi/2``: the faces xsym,
ysym, zsym and end), P2 tetrahedra, pressed by a 3D plane with the same motion, friction and
stiffness, in the same increments and Newton settings. Its force per unit thickness, P = 2 x the
quarter's vertical contact force / t, is compared with the 2D force at the increments both runs
take (a run that cuts back takes more), beyond the first contact (delta > 0.3, where the force is
large against its round-off):

* u_z = 0 on both faces: plane strain, against the plane-strain ring; t = size. The two meshes
  differ (the 2D one is structured, the 3D one not), so the difference falls as both are refined:
  checked within 1 % at size 0.11 (the default mesh is 0.22).
* both faces free and t = 0.05, under a quarter of the element size: plane stress, against the
  plane-stress ring (``plane = "plane_stress"``), checked within 1 %.

With ``small`` both slices are at size 0.22 and crushed to two thirds of the scene's approach
(delta = 4.4, in 24 increments of the scene's size), the plane-strain one checked within 1.5 %: the
coarse one-layer slice may fold an element near the end of the full crush, depending on the mesh
Gmsh makes (it did with Gmsh 4.13, at delta = 5.7).
"""
from __future__ import annotations

import math
import pathlib

import numpy as np
from mpi4py import MPI

from . import Check
from .common import run_job, save_figure

NAME = "slices"
TITLE = "The ring as a 3D slice"
SOURCE = "the 2D ring scene (plane strain, plane stress)"

DELTA_FROM = 0.3            # compared beyond the first contact
SMALL_CRUSH = (4.4, 24)     # small: two thirds of the crush, in increments of the scene's size


def slice_job(scene, t: float, free: bool, comm=MPI.COMM_WORLD):
    """The ring ``scene`` (a presets.Ring) as a 3D slice of thickness ``t``: faces held in z, or
    ``free``; a Job whose history has the approach ``delta`` and the force per unit thickness."""
    import comove_dolfinx as cm
    R, wall = scene.R_out, scene.wall
    mesh = cm.tube_sector(R - wall, R, t, scene.size, angle=math.pi / 2, comm=comm)
    body = cm.Body(mesh, "solid", cm.J2(scene.E, scene.nu, scene.table()), update=scene.update)
    plate = cm.Plane((0.0, R, 0.0), (0.0, -1.0, 0.0), motion=(0.0, -0.5 * scene.delta_max, 0.0))
    contact = cm.Contact("outer", plate, gamma0=scene.gamma0, mu=scene.mu)
    items = [cm.Fixed("xsym", 0), cm.Fixed("ysym", 1), cm.Fixed("zsym", 2), contact]
    if not free:
        items.append(cm.Fixed("end", 2))
    steps = [cm.Step(scene.n_increments, predictor=scene.predictor, first=scene.first)]
    probes = [cm.ContactForce(contact, "force", component=1, scale=-2.0 / t)]
    return cm.Job(body, items, steps, probes, writers=[], newton=scene.newton_settings(),
                  load=lambda f: f * scene.delta_max)


def compare(size: float, t: float, free: bool, comm=MPI.COMM_WORLD, crush: tuple = ()) -> dict:
    """Both runs at mesh ``size``: the approaches and forces of each, the relative differences at
    the common increments beyond DELTA_FROM, the dofs, iterations and CPU seconds. ``crush``: the
    scene's delta_max and n_increments if not its own."""
    from ..presets import get_scene
    overrides = [f"size={size}", f"plane={'plane_stress' if free else 'plane_strain'}"]
    if crush:
        overrides += [f"delta_max={crush[0]}", f"n_increments={crush[1]}"]
    scene = get_scene("ring", overrides)
    res2, its2, cpu2 = run_job(scene.job(scene.mesh_data(comm), []), comm)
    res3, its3, cpu3 = run_job(slice_job(scene, t, free, comm), comm)
    d2, P2, d3, P3 = res2["load"], res2["force"], res3["load"], res3["force"]
    common = [(i, int(np.argmin(np.abs(d3 - d)))) for i, d in enumerate(d2)
              if d > DELTA_FROM and np.min(np.abs(d3 - d)) < 1e-9 * scene.delta_max]
    rel = np.array([P3[j] / P2[i] - 1.0 for i, j in common])
    return {"d2": d2, "P2": P2, "d3": d3, "P3": P3, "rel": rel, "dofs": (res2.dofs, res3.dofs),
            "its": its2 + its3, "cpu": cpu2 + cpu3}


def run(out: pathlib.Path, small: bool = False) -> list[Check]:
    comm = MPI.COMM_WORLD
    out = pathlib.Path(out)
    size = 0.22 if small else 0.11
    crush = SMALL_CRUSH if small else ()
    strain = compare(size, size, False, comm, crush)
    stress = compare(0.22, 0.05, True, comm, crush)
    checks = []
    for label, c, tol in ((f"u_z = 0, t = size = {size}: plane strain", strain, 0.015 if small else 0.01),
                          ("free faces, t = 0.05, size 0.22: plane stress", stress, 0.01)):
        worst = float(np.abs(c["rel"]).max())
        checks.append(Check(TITLE, SOURCE, f"{label} ({c['dofs'][1]} dofs against {c['dofs'][0]}): largest "
                            f"relative difference of the 3D force over {len(c['rel'])} increments, "
                            f"delta > {DELTA_FROM}", 0.0,
                            worst, tol, c["its"], c["cpu"]))
    _plot(out, strain, stress, comm)
    return checks


def _plot(out, strain: dict, stress: dict, comm) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(7.5, 4.4))
    for c, label in ((strain, "plane strain"), (stress, "plane stress")):
        ax.plot(c["d2"], c["P2"], "-", lw=1.2, label=f"2D, {label}")
        ax.plot(c["d3"], c["P3"], "o", ms=3.5, mfc="none", label=f"3D slice, {label}")
    ax.set_xlabel("approach of the plates delta [cm]")
    ax.set_ylabel("force per unit length P [kgf/cm]")
    ax.set_title("the ring scene in 2D and as a slice of tetrahedra", fontsize=9)
    ax.legend(fontsize=8, loc="lower right")
    fig.tight_layout()
    save_figure(fig, out, NAME, comm)

"""3D bodies against the 2D models: the ring scene as a slice of tetrahedra or bricks.

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
  checked within 0.5 % at size 0.11 (the default mesh is 0.22), both runs converged to 1e-6 of
  ``||F_int||`` (``RTOL``; at the scene's 1e-3 the slice's force strays by up to 1.5 % at single
  increments, Newton's tolerance and not the discretisation).
* u_z = 0 on both faces of a slice of Q2 hexahedra, one layer of t = size, whose section is the
  plane-strain ring's grid as Q2 quadrilaterals (:func:`section`): the 3D space holds the 2D
  solution extended along z, which solves the 3D equations too (its out-of-plane shears vanish, and
  sigma_zz does no work on a test function that vanishes on both faces), so the two runs differ
  only by the penalty's stiffness, which scales with the cell's diameter (the brick's against the
  quadrilateral's), and by Newton's tolerance (``RTOL`` here too): the 3D update, return map and
  contact terms are checked against their 2D forms. Checked within 0.5 %.
* both faces free and t = 0.05, under a quarter of the element size: plane stress, against the
  plane-stress ring (``plane = "plane_stress"``), checked within 1 %.

With ``small`` the slices are at size 0.22 and crushed to two thirds of the scene's approach
(delta = 4.4, in 24 increments of the scene's size), the tetrahedral plane-strain one checked
within 1.5 % and the bricks within 0.5 %: the
coarse one-layer slice may fold an element near the end of the full crush, depending on the mesh
Gmsh makes (it did with Gmsh 4.13, at delta = 5.7).
"""
from __future__ import annotations

import dataclasses
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
# Newton's tolerance of the plane-strain comparisons (the scene's own is 1e-3 of ||F_int||, at which
# the slice's force strays by up to 1.5 % at single increments: the comparison would measure that)
RTOL = 1e-6


def slice_job(scene, t: float, free: bool, comm=MPI.COMM_WORLD, bricks: bool = False):
    """The ring ``scene`` (a presets.Ring) as a 3D slice of thickness ``t``: faces held in z, or
    ``free``; a Job whose history has the approach ``delta`` and the force per unit thickness.
    ``bricks``: Q2 hexahedra, the extrusion of :func:`section`'s grid, instead of tetrahedra."""
    import comove_dolfinx as cm
    R, wall = scene.R_out, scene.wall
    mesh = cm.tube_sector(R - wall, R, t, scene.size, angle=math.pi / 2, comm=comm, hexahedra=bricks)
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


def section(scene, comm=MPI.COMM_WORLD):
    """The ring ``scene``'s quarter as Q2 quadrilaterals: the scene's structured grid (annulus_sector)
    with its cells recombined, the section of the slice of bricks."""
    from ..geometry import annulus_sector
    return annulus_sector(scene.R_out - scene.wall, scene.R_out, scene.size, order=scene.geometry_order,
                          comm=comm, quadrilaterals=True)


def _converged_to(scene, rtol: float):
    """``scene`` with Newton's relative tolerance ``rtol`` in place of its own, the rest of its
    settings kept."""
    own = scene.newton_settings
    scene.newton_settings = lambda: dataclasses.replace(own(), rtol=rtol)
    return scene


def compare(size: float, t: float, free: bool, comm=MPI.COMM_WORLD, crush: tuple = (),
            bricks: bool = False, rtol: float | None = None) -> dict:
    """Both runs at mesh ``size``: the approaches and forces of each, the relative differences at
    the common increments beyond DELTA_FROM, the dofs, iterations and CPU seconds. ``crush``: the
    scene's delta_max and n_increments if not its own; ``bricks``: the 2D ring on Q2
    quadrilaterals and the slice in Q2 hexahedra on the same grid; ``rtol``: Newton's tolerance
    of both runs if not the scene's."""
    from ..presets import get_scene
    overrides = [f"size={size}", f"plane={'plane_stress' if free else 'plane_strain'}"]
    if crush:
        overrides += [f"delta_max={crush[0]}", f"n_increments={crush[1]}"]
    scene = get_scene("ring", overrides)
    if rtol is not None:
        scene = _converged_to(scene, rtol)
    md = section(scene, comm) if bricks else scene.mesh_data(comm)
    res2, its2, cpu2 = run_job(scene.job(md, []), comm)
    res3, its3, cpu3 = run_job(slice_job(scene, t, free, comm, bricks), comm)
    d2, P2, d3, P3 = res2["load"], res2["force"], res3["load"], res3["force"]
    common = [(i, int(np.argmin(np.abs(d3 - d)))) for i, d in enumerate(d2)
              if d > DELTA_FROM and np.min(np.abs(d3 - d)) < 1e-9 * scene.delta_max]
    rel = np.array([P3[j] / P2[i] - 1.0 for i, j in common])
    return {"d2": d2, "P2": P2, "d3": d3, "P3": P3, "rel": rel, "d_rel": np.array([d2[i] for i, _ in common]),
            "dofs": (res2.dofs, res3.dofs),
            "its": its2 + its3, "cpu": cpu2 + cpu3}


def run(out: pathlib.Path, small: bool = False) -> list[Check]:
    comm = MPI.COMM_WORLD
    out = pathlib.Path(out)
    size = 0.22 if small else 0.11
    crush = SMALL_CRUSH if small else ()
    strain = compare(size, size, False, comm, crush, rtol=RTOL)
    bricks = compare(size, size, False, comm, crush, bricks=True, rtol=RTOL)
    stress = compare(0.22, 0.05, True, comm, crush)
    checks = []
    for label, c, tol in ((f"u_z = 0, t = size = {size}: plane strain", strain, 0.015 if small else 0.005),
                          (f"u_z = 0, Q2 bricks on the Q2 quadrilaterals' grid, t = size = {size}: plane "
                           "strain", bricks, 0.005),
                          ("free faces, t = 0.05, size 0.22: plane stress", stress, 0.01)):
        worst = float(np.abs(c["rel"]).max())
        checks.append(Check(TITLE, SOURCE, f"{label} ({c['dofs'][1]} dofs against {c['dofs'][0]}): largest "
                            f"relative difference of the 3D force over {len(c['rel'])} increments, "
                            f"delta > {DELTA_FROM}", 0.0,
                            worst, tol, c["its"], c["cpu"]))
    _plot(out, [(strain, "plane strain", "P2 triangles", "P2 tetrahedra"),
                (bricks, "plane strain", "Q2 quadrilaterals", "Q2 bricks"),
                (stress, "plane stress", "P2 triangles", "P2 tetrahedra")], comm)
    return checks


def _plot(out, runs: list, comm) -> None:
    """Left: the force of each 2D run and its slice; right: their relative differences (``runs``:
    (comparison, model, 2D elements, 3D elements))."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, (ax, dx) = plt.subplots(1, 2, figsize=(10.5, 4.2))
    for k, (c, model, cells2, cells3) in enumerate(runs):
        color = f"C{k}"
        ax.plot(c["d2"], c["P2"], "-", color=color, lw=1.2, label=f"2D {model}, {cells2}")
        ax.plot(c["d3"], c["P3"], "o", color=color, ms=3.5, mfc="none", label=f"3D slice, {cells3}")
        dx.plot(c["d_rel"], 100.0 * np.asarray(c["rel"]), "o-", color=color, ms=3, lw=0.8,
                label=f"{model}: {cells3} / {cells2}")
    ax.set_xlabel("approach of the plates delta [cm]")
    ax.set_ylabel("force per unit length P [kgf/cm]")
    ax.legend(fontsize=7, loc="lower right")
    dx.axhline(0.0, color="k", lw=0.6)
    dx.set_xlabel("approach of the plates delta [cm]")
    dx.set_ylabel("3D slice / 2D - 1 [%]")
    dx.legend(fontsize=7)
    fig.suptitle("the ring scene in 2D and as a 3D slice", fontsize=9)
    fig.tight_layout()
    save_figure(fig, out, NAME, comm)

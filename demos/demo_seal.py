# %% [markdown]
# # An O-ring seal squeezed between two rigid plates (plane strain, rubber)
#
# The cross-section of an O-ring, a rubber circle of radius 1 cm, is squeezed between two flat rigid
# plates until they have approached by 25 % of its diameter. The mesh comes from a Gmsh script
# shipped with the demo (demos/seal.geo), meshed here through gmsh's Python API. The demo checks the
# force and the contact width at small squeeze against the closed forms for a cylinder between two
# plates, and exits with status 1 if either check fails.
#
# Run: `python demos/demo_seal.py [--out DIR]` (a few seconds), also under mpirun.

# %%
import argparse
import logging
import pathlib
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from mpi4py import MPI  # noqa: E402

import comove_dolfinx as cm  # noqa: E402
from comove_dolfinx.geometry import gmsh_session  # noqa: E402
from comove_dolfinx.geometry.gmsh_session import gmsh  # noqa: E402

parser = argparse.ArgumentParser(description="an O-ring section squeezed between rigid plates")
parser.add_argument("--out", default="results/demo_seal")
parser.add_argument("--geo", default=str(pathlib.Path(__file__).resolve().with_name("seal.geo")),
                    help="the Gmsh script of the quarter section")
args = parser.parse_args()
out = pathlib.Path(args.out)
comm = MPI.COMM_WORLD
logging.disable(logging.INFO)                 # the form compiler's messages

# %% [markdown]
# ## The mesh
# seal.geo describes the quarter x >= 0, y >= 0 of the section with quadratic triangles, small at
# the crown (0, R) where the plate first touches, and names its edges: "xsym" (x = 0), "ysym"
# (y = 0) and "outer" (the arc). Rank 0 meshes it into the output folder; every rank reads it.

# %%
msh = out / "seal.msh"
if comm.rank == 0:
    out.mkdir(parents=True, exist_ok=True)
    gmsh_session.start()                            # gmsh.initialize, keeping Python's Ctrl-C
    try:
        gmsh.open(args.geo)
        gmsh.model.mesh.generate(2)
        gmsh.model.mesh.setOrder(2)                 # mid-side nodes on the true arc
        gmsh.write(str(msh))
    finally:
        gmsh_session.stop()
comm.barrier()

# %% [markdown]
# ## The problem
# Units: cm and kgf. Rubber: E = 10 kgf/cm^2 and nu = 0.45 (nearer 0.5 the displacement-only P2
# elements would lock), with the neo-Hookean law for the large strains of a squeezed seal. Both
# plates are frictionless, so the quarter needs only its symmetry conditions: u_x = 0 on x = 0,
# u_y = 0 on y = 0 (the lower plate's half of the approach). The upper plate starts at the crown
# and moves down by half the approach. The contact item's factor follows s^2 over the step's
# fraction s, which makes the first increments short: the check at small squeeze gets five of them
# below 2.5 % of the diameter.

# %%
R, E, nu = 1.0, 10.0, 0.45             # section radius [cm], rubber [kgf/cm^2]
squeeze = 0.25                         # final approach of the plates / diameter

mesh = cm.load_msh(msh, comm, required=("xsym", "ysym", "outer"))
body = cm.Body(mesh, "plane_strain", cm.Elastic(E, nu), update="neo_hooke")
plate = cm.Plane((0.0, R), (0.0, -1.0), motion=(0.0, -squeeze * R))    # down by squeeze * D / 2
contact = cm.Contact("outer", plate)                                    # penalty, frictionless
items = [cm.Fixed("xsym", component=0), cm.Fixed("ysym", component=1), contact]
steps = [cm.Step(16, ramp={contact: lambda s: s ** 2})]
probes = [cm.Value("approach", lambda model: -2.0 * plate.displacement(contact.factor)[1]),
          cm.ContactForce(contact, "plate", component=None),     # plate_fx, plate_fy on the quarter
          cm.Reaction("ysym"),                                    # ysym_fx, ysym_fy
          cm.ContactLength(contact, "half_width")]                # the quarter has half the contact
job = cm.Job(body, items, steps, probes,
             writers=[cm.VTK(out, overwrite=True), cm.HistoryCSV(out / "history.csv")])
res = job.run()

# %% [markdown]
# ## Check 1: the force at small squeeze
# A cylinder of radius R between two rigid plates, loaded by P per unit length, touches each plate
# over the Hertz half-width a = sqrt(4 P R / (pi E*)), E* = E / (1 - nu^2), and the plates approach
# by
#
#     delta = (2 P / (pi E*)) (2 ln(4 R / a) - 1)
#
# (the classical result for a cylinder between two plates, e.g. K. L. Johnson, Contact Mechanics,
# 1985, chapter 5). It follows from integrating the strain along the loaded diameter. There a disc
# under two opposed line loads carries the radial field of each load, sigma_y = -2 P / (pi r) at
# the distance r from it, and a uniform tension P / (pi R) in both directions; near a plate,
# Hertz's field takes the place of that load's own, which it approaches for z >> a: at the depth z,
# sigma_y = -p0 a / sqrt(a^2 + z^2) and sigma_x = -(p0 / a) ((a^2 + 2 z^2) / sqrt(a^2 + z^2) - 2 z),
# p0 a = 2 P / pi. With the plane-strain strain E* eps_y = sigma_y - nu / (1 - nu) sigma_x, the two
# sigma_x parts cancel (Hertz's integrates to -P / pi, the tension's to +P / pi), and delta =
# 2 * integral over 0 <= z <= R of -eps_y, with r = 2R - z for the far load, gives the line above.
# It neglects terms of order (a / R)^2, 1.7 % at delta / D = 2.5 % (a / R = 0.13), and the change
# of shape; the check asks the computed force to match within 2 % up to that squeeze. The closed
# form is solved for P at each computed approach (a fixed-point iteration: the logarithm varies
# slowly).
#
# ## Check 2: the contact width at small squeeze
# Each plate touches the section over the Hertz half-width a = sqrt(4 P R / (pi E*)) for the force
# P it carries. The contact item places the zone's edge where the pressure between two of its
# quadrature points reaches zero, within a fraction of an element of the exact edge
# (docs/verification.md, hertz_line), so the computed half-width must match Hertz's for the computed
# force within a quarter of the crown's element size (size_top in seal.geo), wherever the zone spans
# at least two elements and the squeeze is small.

# %%
Es = E / (1 - nu ** 2)


def closed_form_force(delta):
    P = np.pi * Es * delta / 10.0
    for _ in range(60):
        a = np.sqrt(4 * P * R / (np.pi * Es))
        P = np.pi * Es * delta / (2 * (2 * np.log(4 * R / a) - 1))
    return P


ratio = delta = P = a_hertz = width_error = np.zeros(0)
h_crown = 0.015                       # size_top of seal.geo: the element size at the crown
if len(res):
    delta, P = res["approach"], -2.0 * res["plate_fy"]         # the whole plate: twice the quarter's
    ratio = P / closed_form_force(delta)
    a_hertz = np.sqrt(4 * P * R / (np.pi * Es))
    width_error = np.abs(res["half_width"] - a_hertz) / h_crown
small = delta / (2 * R) <= 0.025
force_ok = small.sum() >= 3 and bool(np.all(np.abs(ratio[small] - 1) <= 0.02))
spans = small & (a_hertz >= 2 * h_crown)
width_ok = spans.sum() >= 3 and bool(np.all(width_error[spans] <= 0.25))
ok = res.completed and force_ok and width_ok

# %% [markdown]
# ## The chart
# Left: the force per unit length against the plates' approach, computed and closed form (which
# holds at small squeeze only: beyond it the section's change of shape stiffens it). Right: the
# two checks as relative differences on a log scale, with their tolerances.

# %%
if comm.rank == 0 and len(res):
    pct = 100 * delta / (2 * R)
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(11, 4.2), layout="constrained")
    dd = np.linspace(0, squeeze * 2 * R, 201)[1:]
    a1.plot(np.r_[0, pct], np.r_[0, P], "o", ms=4, label="computed (neo-Hooke, P2)")
    a1.plot(100 * dd / (2 * R), closed_form_force(dd), "-", label="cylinder between plates, closed form")
    a1.axvspan(0, 2.5, color="grey", alpha=0.15, lw=0, label="checked: approach <= 2.5 % of D")
    a1.set(xlabel="approach of the plates / diameter [%]", ylabel="plate force P [kgf per cm of length]",
           title="O-ring section between rigid plates")
    a1.legend(loc="upper left", fontsize=9)
    zoom = a1.inset_axes([0.63, 0.07, 0.34, 0.3])
    zoom.plot(pct[small], P[small], "o", ms=4)
    zoom.plot(100 * dd[dd <= 0.03 * 2 * R] / (2 * R), closed_form_force(dd[dd <= 0.03 * 2 * R]), "-")
    zoom.set_title("approach <= 3 % of D", fontsize=8)
    zoom.tick_params(labelsize=7)
    a2.semilogy(pct, np.abs(ratio - 1), "o-", ms=4, label="force: |P / closed form - 1|")
    a2.plot([0, 2.5], [0.02, 0.02], "--", color="C0", label="its tolerance (2 %, approach <= 2.5 %)")
    a2.semilogy(pct, np.abs(res["half_width"] / a_hertz - 1), "s-", ms=4, color="C2",
                label="half-width: |a / Hertz's a - 1|")
    a2.plot(pct[spans], 0.25 * h_crown / a_hertz[spans], "--", color="C2",
            label="its tolerance (h / 4, where a >= 2 h)")
    a2.set(xlabel="approach of the plates / diameter [%]", ylabel="relative difference",
           title="the checks", ylim=(1e-4, 1.0))
    a2.legend(loc="upper right", fontsize=8)
    fig.savefig(out / "seal.png", dpi=130)
    plt.close(fig)
    if small.any():
        print(f"force at small squeeze (approach <= 2.5 % of D, {small.sum()} increments): P / closed "
              f"form from {ratio[small].min():.4f} to {ratio[small].max():.4f} (tolerance 2 %); at "
              f"{pct[-1]:.1f} %: P = {P[-1]:.4g} kgf/cm, {ratio[-1]:.3f} x the closed form")
    if spans.any():
        print(f"half-width at small squeeze ({spans.sum()} increments with a >= 2 h): at most "
              f"{width_error[spans].max():.2f} h from Hertz's (tolerance h / 4)")
if comm.rank == 0:
    print(f"{res.message}; {'OK' if ok else 'FAILED'}: ParaView {out / 'results.pvd'}")
sys.exit(0 if ok else 1)

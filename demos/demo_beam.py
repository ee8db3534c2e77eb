# %% [markdown]
# # A cantilever pressed onto a rigid foundation (plane stress, large deflection, friction)
#
# A cantilever 10 cm long and 0.5 cm deep (E = 1000 kgf/cm^2, nu = 0.3, plane stress), clamped at
# x = 0, carries a pressure q on its upper face that follows the face as it turns, and bends down
# onto a rigid plane 3 cm below (Coulomb friction 0.1, the pressure lagged by one increment;
# docs/scenes.md, "beam"). The tip travels 3 cm in the first twentieth of the load; after that the
# beam lies down on the foundation from the tip inwards. The demo checks that the tip rests on the
# plane at the end and that the foundation carries a load.
#
# Run: `python demos/demo_beam.py [--out DIR] [--size 0.125]`, also under mpirun.

# %%
import argparse
import logging
import pathlib
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from mpi4py import MPI  # noqa: E402

import comove_dolfinx as cm  # noqa: E402
from comove_dolfinx.io import draw_plane, snapshot_grid  # noqa: E402

parser = argparse.ArgumentParser(description="a cantilever pressed onto a rigid foundation")
parser.add_argument("--out", default="results/demo_beam")
parser.add_argument("--size", type=float, default=0.125, help="mesh size [cm]")
args = parser.parse_args()
out = pathlib.Path(args.out)
comm = MPI.COMM_WORLD
logging.disable(logging.INFO)                 # the form compiler's messages

# %% [markdown]
# ## The problem (cm, kgf)

# %%
L, h, q, gap = 10.0, 0.5, 0.5, 3.0
mesh = cm.rectangle(L, h, args.size, comm=comm)          # tags left, right, bottom, top
body = cm.Body(mesh, "plane_stress", cm.Elastic(1000.0, 0.3))
foundation = cm.Contact("bottom", cm.Plane((0.0, -gap), (0.0, 1.0)), mu=0.1)
items = [cm.Fixed("left"), cm.Pressure("top", q), foundation]
probes = [cm.NodeDisplacement("tip", (L, 0.0)), cm.ContactLength(foundation),
          cm.ContactForce(foundation, "contact_force", component=1)]
snaps = cm.Snapshots([0.05 * q, 0.25 * q, 0.5 * q, q])
# overwrite=True: a second run into the same folder replaces the datasets of the first (the VTK
# writer refuses a folder holding another run's datasets otherwise)
job = cm.Job(body, items, [cm.Step(20)], probes, load=lambda t: q * t,     # load column: q
             writers=[cm.VTK(out, overwrite=True), cm.HistoryCSV(out / "history.csv"), snaps])
if comm.rank == 0:
    out.mkdir(parents=True, exist_ok=True)
res = job.run(progress=True)

# %% [markdown]
# ## The check: the tip rests on the plane (to the penalty's penetration) and the plane carries load

# %%
tip_gap = gap + res["tip_uy"][-1]
ok = res.completed and abs(tip_gap) < 1e-2 and res["contact_force"][-1] > 0

# %% [markdown]
# ## Pictures
# Deformed shapes coloured by the von Mises stress; the tip's displacements, the contact length and
# the foundation's force against q on a logarithmic axis (the first increment carries the tip most
# of the way down; each marker is a converged increment).

# %%
if comm.rank == 0:
    snapshot_grid(snaps.taken, lambda ax, s: draw_plane(ax, -gap, -0.5, L + 0.5), out / "beam_shapes.png",
                  "beam: deformed configurations", load_name="q [kgf/cm$^2$]", columns=2)
    fig, axes = plt.subplots(1, 3, figsize=(13, 3.8), layout="constrained")
    qq = res["load"]
    axes[0].semilogx(qq, -res["tip_uy"], "o-", ms=3, label="$-u_y$")
    axes[0].semilogx(qq, -res["tip_ux"], "s-", ms=3, label="$-u_x$")
    axes[0].axhline(gap, color="grey", ls="--", lw=0.8, label="gap to the plane")
    axes[0].set(xlabel="q [kgf/cm$^2$]", ylabel="tip displacement [cm]", title="tip (x = L, y = 0)")
    axes[0].legend()
    axes[1].semilogx(qq, res["contact_length"], "o-", ms=3)
    axes[1].set(xlabel="q [kgf/cm$^2$]", ylabel="contact length [cm]", title="contact (current length)")
    axes[2].semilogx(qq, res["contact_force"], "o-", ms=3)
    axes[2].semilogx(qq, qq * L, ":", color="k", label="q L (all of the load)")
    axes[2].set(xlabel="q [kgf/cm$^2$]", ylabel="force [kgf per cm of width]", title="force on the plane")
    axes[2].legend()
    fig.savefig(out / "beam_curves.png", dpi=130)
    plt.close(fig)
    print(f"tip gap at q = {q}: {tip_gap:.2e} cm; force on the plane {res['contact_force'][-1]:.4g} "
          f"of q L = {q * L:.4g}; {res.message}; {'OK' if ok else 'FAILED'}")
sys.exit(0 if ok else 1)

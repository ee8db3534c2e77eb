# %% [markdown]
# # A metal ring crushed between rigid plates (plane strain, elastic-plastic)
#
# A steel ring of outer diameter 11.43 cm and wall 0.866 cm is crushed between two rigid plates
# (Coulomb friction 0.1) until they have approached by 6.6 cm (docs/scenes.md, "ring"). It is
# Shang and Chen's elastic-plastic example: four plastic hinges form, the ring collapses into a
# mechanism, and the contact patch under each plate splits in two once the crown lifts off.
# The demo builds the problem with the public API and checks the load against the rigid-plastic
# bound of DeRunz and Hodge (docs/theory.md section 8.6).
#
# Run: `python demos/demo_ring.py [--out DIR] [--size 0.22] [--law j2|chen]`, also under mpirun.

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
from comove_dolfinx.io import draw_plane, snapshot_grid  # noqa: E402
from comove_dolfinx.presets import split_delta  # noqa: E402

parser = argparse.ArgumentParser(description="a ring crushed between rigid plates")
parser.add_argument("--out", default="results/demo_ring")
parser.add_argument("--size", type=float, default=0.22, help="mesh size [cm]")
parser.add_argument("--law", default="j2", choices=("j2", "chen"))
args = parser.parse_args()
out = pathlib.Path(args.out)
comm = MPI.COMM_WORLD
logging.disable(logging.INFO)                 # the form compiler's messages

# %% [markdown]
# ## The problem
# One quarter (x, y >= 0) with symmetry conditions; the upper plate starts touching the crown and
# moves down by delta / 2 (the lower plate's half is the symmetry of y = 0). Units: cm, kgf.
# Mild steel: E = 1.89e6 kgf/cm^2, nu = 0.3, J2 flow with a piecewise-linear hardening table.

# %%
R_out, wall, delta = 5.715, 0.866, 6.6
steel = cm.Hardening([0, 0.01, 0.05, 0.1, 0.2, 0.5], [2800, 3000, 3600, 4000, 4500, 5300])
Law = cm.J2 if args.law == "j2" else cm.Chen
mesh = cm.annulus_sector(R_out - wall, R_out, args.size, comm=comm)   # tags xsym, ysym, inner, outer
body = cm.Body(mesh, "plane_strain", Law(1.89e6, 0.3, steel))
plate = cm.Plane(point=(0.0, R_out), normal=(0.0, -1.0), motion=(0.0, -delta / 2))
contact = cm.Contact("outer", plate, method="penalty", gamma0=1.0, mu=0.1)
items = [cm.Fixed("xsym", component=0), cm.Fixed("ysym", component=1), contact]

# %% [markdown]
# The history records the load on the whole ring (twice the quarter's: both halves of the plate),
# where the contact zone begins and ends on the plate, the crown's height under the plate and the
# largest plastic strain. The crush is a smooth path, so each increment starts from the Euler step
# along its tangent; Newton stops when the out-of-balance force is below 1e-3 of the forces the
# ring carries, with an energy line search for the travelling hinges (docs/theory.md section 7).

# %%
probes = [cm.ContactForce(contact, "force", component=1, scale=-2.0),
          cm.ContactEdges(contact, "zone", axis=0),
          cm.NodeDisplacement("crown", (0.0, R_out), component=1),
          cm.MaxPlasticStrain()]
snaps = cm.Snapshots([0.15 * delta, 0.3 * delta, 0.6 * delta, delta], field="plastic_strain")
job = cm.Job(body, items, [cm.Step(36, predictor="tangent")], probes,
             writers=[cm.VTK(out, overwrite=True), cm.HistoryCSV(out / "history.csv"), snaps],
             newton=cm.NewtonSettings(line_search="energy", energy_eta=0.2, scale="force", rtol=1e-3),
             load=lambda t: delta * t)                   # the history's load: the approach delta
if comm.rank == 0:
    out.mkdir(parents=True, exist_ok=True)
res = job.run(progress=True)

# %% [markdown]
# ## The check
# A ring that hardens must carry more than the rigid-perfectly-plastic ring, whose four hinges give
# P0 = 4 M_p / R with the plane-strain fully plastic moment M_p = (2/sqrt 3) sigma_0 t^2 / 4, and
# P = P0 / sqrt(1 - (delta/D)^2) once collapsed (DeRunz and Hodge 1963; D = 2R the mean diameter).

# %%
d, P = res["load"], res["force"]
R = R_out - wall / 2
P0 = 4 * (2 / np.sqrt(3)) * 2800.0 * wall ** 2 / 4 / R
bound = P0 / np.sqrt(1 - (np.minimum(d, 2 * R * 0.999) / (2 * R)) ** 2)
collapsed = d >= 1.0
ratio = P[collapsed] / bound[collapsed]
crown_gap = (R_out - d / 2) - (R_out + res["crown_uy"])          # plate minus crown height
# the crown lifts off where its gap opens for good (the last opening, interpolated between increments)
in_contact = np.isfinite(res["zone_min"])                         # NaN: no contact on the plate
split = split_delta(d, crown_gap, in_contact)
ok = res.completed and ratio.size > 0 and ratio.min() > 1.0

# %% [markdown]
# ## Pictures
# The deformed quarter at four approaches (mirrored to show the half ring), coloured by the
# equivalent plastic strain; the load against the approach with the elastic thin-ring line (inset)
# and the rigid-plastic curve; where each contact zone on the plate begins and ends.

# %%
if comm.rank == 0:
    snapshot_grid(snaps.taken, lambda ax, s: draw_plane(ax, R_out - s.load / 2, -R_out - 0.5, R_out + 0.5,
                                                         below=False),
                  out / "ring_shapes.png", "ring: deformed half (mirrored quarter)", mirror=True,
                  load_name="delta [cm]", columns=2)
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(11, 4.2), layout="constrained")
    a1.plot(np.r_[0, d], np.r_[0, P], "o-", ms=2.5, label=f"co-moving S-R, {args.law}")
    dd = np.linspace(0, delta, 200)
    a1.plot(dd, P0 / np.sqrt(1 - (dd / (2 * R)) ** 2), "--", label="DeRunz-Hodge, rigid-plastic")
    a1.set(xlabel="plate approach delta [cm]", ylabel="P [kgf per cm of ring length]",
           title="load against approach")
    a1.legend(loc="upper left")
    ins = a1.inset_axes([0.56, 0.1, 0.4, 0.33])              # below the curves, where the axes are empty
    E1 = 1.89e6 / (1 - 0.3 ** 2)
    k = E1 * wall ** 3 / 12 / (0.1488 * R ** 3)             # thin ring, diametral loads
    first = d <= 0.25
    ins.plot(np.r_[0, d[first]], np.r_[0, P[first]], "o-", ms=2.5)
    ins.plot([0, P0 / k], [0, P0], ":", color="k", label="thin ring, elastic")
    ins.set_title("first increments", fontsize=8)
    ins.legend(fontsize=7)
    ins.tick_params(labelsize=7)
    a2.plot(d, res["zone_min"], "-", label="inner edge (x of the zone's start)")
    a2.plot(d, res["zone_max"], "-", label="outer edge")
    if split is not None:
        a2.axvline(split, color="grey", ls="--", lw=0.8, label=f"crown lifts off, delta = {split:.2f}")
    a2.set(xlabel="plate approach delta [cm]", ylabel="x on the plate [cm]",
           title="contact zone on the plate (one of two, mirrored at x = 0)")
    a2.legend()
    fig.savefig(out / "ring_curves.png", dpi=130)
    plt.close(fig)
    print(f"P(delta = {d[-1]:.3g}) = {P[-1]:.1f} kgf/cm; P / DeRunz-Hodge for delta >= 1: "
          f"{ratio.min():.3f} to {ratio.max():.3f}; crown lifts off at delta = "
          f"{'(never)' if split is None else f'{split:.3f}'}")
    print(f"{res.message}; {'OK' if ok else 'FAILED'}: ParaView {out / 'results.pvd'}")
sys.exit(0 if ok else 1)

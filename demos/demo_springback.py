# %% [markdown]
# # Springback: the crushed ring released
#
# The ring of demo_ring.py (steel, OD 11.43 cm, wall 0.866 cm, J2 with hardening, plane strain)
# is crushed between rigid plates to an approach of 6.6 cm and then released: the plate goes back
# where it started. Two steps of one job: the contact item's factor goes 0 -> 1 (the plate moves
# down by delta / 2) and then 1 -> 0 (it moves back up). The ring springs back elastically and
# keeps its plastic hinges.
#
# Then the plate comes down again to the same approach. Checks: after release no force is left on
# the plate; the release is elastic (the largest plastic strain does not change); the springback,
# the height the ring recovers, against the load carried times the compliance of the first
# unloading increment (a linear elastic unloading); and reversibility: pressed again to the same
# approach, the ring must carry the load it carried before: to 0.5 % without friction (an elastic
# path is reversible), to 3 % with it (friction slips one way on release and the other on reloading,
# a hysteresis of a few percent of the load). The linear estimate of the springback (the load times
# the compliance of the first unloading increment) is printed beside it: the contact patch shrinks
# as the plate lets go, so the unloading softens and the true springback is larger.
#
# Run: `python demos/demo_springback.py [--out DIR] [--size 0.22]`, also under mpirun.

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

parser = argparse.ArgumentParser(description="a crushed ring released")
parser.add_argument("--out", default="results/demo_springback")
parser.add_argument("--size", type=float, default=0.22, help="mesh size [cm]")
parser.add_argument("--mu", type=float, default=0.1, help="friction coefficient of the plate")
args = parser.parse_args()
out = pathlib.Path(args.out)
comm = MPI.COMM_WORLD
logging.disable(logging.INFO)                 # the form compiler's messages

# %% [markdown]
# ## The problem: the ring's quarter, a plate that goes down and comes back

# %%
R_out, wall, delta = 5.715, 0.866, 6.6
steel = cm.Hardening([0, 0.01, 0.05, 0.1, 0.2, 0.5], [2800, 3000, 3600, 4000, 4500, 5300])
mesh = cm.annulus_sector(R_out - wall, R_out, args.size, comm=comm)
body = cm.Body(mesh, "plane_strain", cm.J2(1.89e6, 0.3, steel))
plate = cm.Plane((0.0, R_out), (0.0, -1.0), motion=(0.0, -delta / 2))
contact = cm.Contact("outer", plate, gamma0=1.0, mu=args.mu)
items = [cm.Fixed("xsym", component=0), cm.Fixed("ysym", component=1), contact]
back = 0.15 / (delta / 2)            # the plate's first 0.15 cm back up: the ring lets go within it
steps = [cm.Step(36, ramp={contact: 1.0}, predictor="tangent", name="crush"),
         cm.Step(10, ramp={contact: 1.0 - back}, name="release"),
         cm.Step(4, ramp={contact: 0.0}, name="plate back to its start"),
         cm.Step(12, ramp={contact: 1.0}, name="press again")]


def ring_height(model):
    """Twice the highest point of the quarter (current configuration): the ring's outer height."""
    V = model.V
    n = V.dofmap.index_map.size_local
    y = V.tabulate_dof_coordinates()[:n, 1] + model.u.x.array.reshape(-1, 2)[:n, 1]
    return 2 * model.comm.allreduce(float(y.max()) if n else -np.inf, op=MPI.MAX)


probes = [cm.ContactForce(contact, "force", component=1, scale=-2.0),
          cm.Value("height", ring_height), cm.MaxPlasticStrain()]
job = cm.Job(body, items, steps, probes, writers=[cm.VTK(out, overwrite=True),
                                                  cm.HistoryCSV(out / "history.csv")],
             newton=cm.NewtonSettings(line_search="energy", energy_eta=0.2, scale="force", rtol=1e-3),
             load=lambda time: delta * contact.factor)      # the plates' approach
if comm.rank == 0:
    out.mkdir(parents=True, exist_ok=True)
res = job.run(progress=True)

# %% [markdown]
# ## The numbers
# The springback is the height recovered between the end of the crush and the end of the release.
# Its elastic estimate: the load at the end of the crush times the compliance of the first unloading
# increment (d height / d P at the start of the release), valid if the unloading stays elastic and
# nearly linear until the plate lets go.

# %%
t, P, H, p = res["time"], res["force"], res["height"], res["max_plastic_strain"]
top = np.argmin(np.abs(t - 1.0))                    # the end of the crush
free = np.argmin(np.abs(t - 3.0))                   # the plate back at its start
springback = H[free] - H[top]
compliance = (H[top + 1] - H[top]) / (P[top] - P[top + 1])
estimate = P[top] * compliance
reload = P[-1] / P[top]
ok = (res.completed and abs(P[free]) < 1e-6 * P[top] and abs(p[free] - p[top]) <= 0.01 * p[top]
      and springback > estimate > 0 and abs(reload - 1) < (0.03 if args.mu > 0 else 0.005))

# %%
if comm.rank == 0:
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(11, 4), layout="constrained")
    D0 = 2 * R_out
    a1.plot(np.r_[0, D0 - H[:top + 1]], np.r_[0, P[:top + 1]], "o-", ms=2.5, label="crush")
    a1.plot(D0 - H[top:free + 1], P[top:free + 1], "s-", ms=2.5, label="release")
    a1.plot(D0 - H[free:], P[free:], "^-", ms=2.5, label="pressed again")
    a1.set(xlabel="loss of height D0 - H [cm]", ylabel="P [kgf per cm of ring length]",
           title="load against loss of height")
    a1.legend()
    a2.plot(D0 - H[top:free + 1], P[top:free + 1], "s-", ms=3, color="C1", label="release")
    a2.plot(D0 - H[free:], P[free:], "^", ms=4, color="C2", mfc="none", label="pressed again")
    a2.plot([D0 - H[top], D0 - H[top] - estimate], [P[top], 0.0], ":", color="k",
            label="initial unloading slope")
    a2.set(xlabel="loss of height D0 - H [cm]", ylabel="P [kgf/cm]",
           title=f"springback {springback:.4f} cm (elastic estimate {estimate:.4f})")
    a2.legend()
    fig.savefig(out / "springback.png", dpi=130)
    plt.close(fig)
    print(f"crushed to height {H[top]:.4f} cm under P = {P[top]:.1f} kgf/cm; released: height "
          f"{H[free]:.4f} cm, springback {springback:.4f} cm ({100 * springback / delta:.2f} % of the "
          f"approach), elastic estimate {estimate:.4f}; force left {P[free]:.2e}; max plastic strain "
          f"{p[top]:.4f} -> {p[free]:.4f}; pressed again: P = {P[-1]:.1f} ({reload:.4f} of before); "
          f"{res.message}; {'OK' if ok else 'FAILED'}")
sys.exit(0 if ok else 1)

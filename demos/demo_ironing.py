# %% [markdown]
# # Ironing: a rigid cylinder pressed into an elastic block, then dragged over it with friction
#
# A rigid cylinder of radius 2 cm is pressed 0.2 mm into an elastic block (4 cm long, 1 cm deep,
# plane strain, its bottom bonded to a rigid base) and then dragged 8 mm along the block's top
# face, with Coulomb friction mu = 0.2 between the two. One job with two steps moves the cylinder:
# the first pushes it down, the second drags it sideways. The demo checks the indentation against
# Hertz's line contact and the sliding against Coulomb's law, and exits with status 1 if either
# check fails.
#
# Run: `python demos/demo_ironing.py [--out DIR]` (about 15 s), also under mpirun.

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

parser = argparse.ArgumentParser(description="a rigid cylinder indents an elastic block, then slides")
parser.add_argument("--out", default="results/demo_ironing")
args = parser.parse_args()
out = pathlib.Path(args.out)
comm = MPI.COMM_WORLD
logging.disable(logging.INFO)                 # the form compiler's messages

# %% [markdown]
# ## The problem
# Units: cm and kgf (E = 1000 kgf/cm^2, a stiff elastomer); forces are per cm of the cylinder's
# length.
# The cylinder starts touching the top face at x0. Its motion is a function of the contact item's
# factor f: down by `depth` while f goes from 0 to 1 (step 1), then sideways by `drag` while f
# goes from 1 to 2 (step 2). Step 2 follows f = 1 + s^2 over its fraction s, so that its first
# increments are short while the contact goes over from sticking to slipping.
#
# The contact is Nitsche's (no penetration, gamma0 = 10). The friction threshold is mu times the
# pressure of the last converged increment (a lagged pressure), which is the current pressure once
# the sliding is steady. P2 triangles of 0.4 mm: four or five across the contact's half-width.

# %%
L, H = 4.0, 1.0                        # block [cm]
E, nu = 1000.0, 0.3                    # [kgf/cm^2]
R, x0 = 2.0, 1.6                       # cylinder radius, position of its axis [cm]
depth, drag, mu = 0.02, 0.8, 0.2       # indentation, drag distance [cm], friction coefficient

mesh = cm.rectangle(L, H, 0.04, comm=comm)        # facet groups left, right, bottom, top
body = cm.Body(mesh, "plane_strain", cm.Elastic(E, nu))
cylinder = cm.Circle((x0, H + R), R,
                     motion=lambda f: (drag * max(f - 1.0, 0.0), -depth * min(f, 1.0)))
contact = cm.Contact("top", cylinder, method="nitsche", gamma0=10.0, mu=mu)
items = [cm.Fixed("bottom"), contact]
steps = [cm.Step(3, ramp={contact: 1.0}, name="indent"),
         cm.Step(16, ramp={contact: lambda s: 1.0 + s ** 2}, name="drag")]


def peak_pressure(model):
    contact.update_fields()                        # nodal contact pressure along the top face
    return contact.boundary_values(contact.pressure)[1].max()


def slip_share(model):
    stick, slip = contact.stick_slip()             # lengths of the contact set that stick / slip
    return slip / (stick + slip) if stick + slip > 0 else 0.0


probes = [cm.ContactForce(contact, "contact", component=None),   # contact_fx, contact_fy
          cm.ContactLength(contact, "half_width", scale=0.5),
          cm.Value("p_max", peak_pressure),
          cm.Value("slip_share", slip_share),
          cm.Value("travel", lambda model: cylinder.displacement(contact.factor)[0])]


class PressureProfile(cm.Writer):
    """Keeps the contact pressure along the top face at the end of the indentation (time 1)."""

    def write(self, run, row, increment):
        if abs(row["time"] - 1.0) < 1e-9:
            contact.update_fields()
            self.x, self.p = contact.boundary_values(contact.pressure)   # reference x, pressure


profile = PressureProfile()
job = cm.Job(body, items, steps, probes,
             writers=[cm.VTK(out, overwrite=True), cm.HistoryCSV(out / "history.csv"), profile])

# %%
if comm.rank == 0:
    out.mkdir(parents=True, exist_ok=True)
comm.barrier()
res = job.run()

# %% [markdown]
# ## Check (a): Hertz's line contact at the end of the indentation
# A rigid cylinder pressed with P per unit length onto an elastic half-space touches it over the
# half-width a = sqrt(4 P R / (pi E*)), E* = E / (1 - nu^2), under the semi-elliptic pressure
# p = p0 sqrt(1 - x^2/a^2) with the peak p0 = 2 P / (pi a) (Johnson, Contact Mechanics, 1985,
# chapter 4). With P taken from the computed force, the computed half-width and peak pressure
# should match within 5 %:
# * the contact set's extent is resolved to about a quarter of an element at each edge, +-3 % of
#   a at a = 0.18 cm;
# * the block is not a half-space: it is 1 cm deep (a/H = 0.18) and bonded to a rigid base, which
#   raises the peak by about 1 %;
# * the friction that acts while the cylinder goes down holds the surface back and peaks the
#   pressure by about 2.5 % more (a frictionless run of this demo is 1 % above Hertz's peak).
#
# In 2D the indentation depth itself depends on the block's depth and support, so the check
# relates the force to the contact's size and pressure rather than to the depth.

# %%
Es = E / (1 - nu ** 2)
end = next((r for r in res.rows if abs(r["time"] - 1.0) < 1e-9), None)
if end is not None:
    P = -end["contact_fy"]                                   # the cylinder pushes down
    a_hertz = np.sqrt(4 * P * R / (np.pi * Es))
    p0_hertz = 2 * P / (np.pi * a_hertz)
    ratio_a, ratio_p = end["half_width"] / a_hertz, end["p_max"] / p0_hertz
hertz_ok = end is not None and abs(ratio_a - 1) <= 0.05 and abs(ratio_p - 1) <= 0.05

# %% [markdown]
# ## Check (b): Coulomb's law while the cylinder slides
# Once the whole contact slips, the tangential force is mu times the normal force. The history
# holds the force's components in fixed axes, T = fx and N = -fy, while Coulomb's law holds along
# the cylinder's surface, whose normal turns by +-a/R (+-5 degrees) across the contact: the sliding
# cylinder's pressure is not centred under its axis (its centre trails by a few hundredths of a,
# the coupling of normal and tangential surface displacements of an elastic body; Johnson 1985,
# chapter 7), so the pressure's resultant leans back a little; the lagged threshold (the pressure
# of the increment before, a little behind the current one) adds to this, and T / (mu N) comes out
# 1 to 2 % below 1. The check asks for 3 % over every increment in full slip (slip_share, the
# fraction of the contact set whose friction is at its threshold, above 0.99).

# %%
sliding = [r for r in res.rows if r["time"] > 1.0 and r["slip_share"] >= 0.99]
ratio_T = np.array([abs(r["contact_fx"]) / (mu * abs(r["contact_fy"])) for r in sliding])
coulomb_ok = len(sliding) >= 8 and bool(np.all(np.abs(ratio_T - 1) <= 0.03))
ok = res.completed and hertz_ok and coulomb_ok

# %% [markdown]
# ## The chart
# Left: the contact pressure at the end of the indentation against Hertz's semi-ellipse for the
# computed force (the nodal values are a lumped projection, which dips below zero just outside the
# contact). Right: the tangential force against mu times the normal force along the drag;
# the open markers are increments in which part of the contact still sticks.

# %%
if comm.rank == 0:
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(11, 4.2), layout="constrained")
    if end is not None:
        order = np.argsort(profile.x[:, 0])
        xs, ps = profile.x[order, 0] - x0, profile.p[order]
        near = np.abs(xs) <= 1.6 * a_hertz
        a1.plot(xs[near], ps[near], "o", ms=3.5, label="computed, at the nodes of the top face")
        xx = np.linspace(-a_hertz, a_hertz, 201)
        a1.plot(xx, p0_hertz * np.sqrt(np.clip(1 - (xx / a_hertz) ** 2, 0, None)), "-",
                label=f"Hertz, P = {P:.2f} kgf/cm")
        a1.set(xlabel="x - x0 along the top face [cm]", ylabel="contact pressure [kgf/cm$^2$]",
               title="end of the indentation", ylim=(-0.1 * ps.max(), 1.3 * ps.max()))
        a1.legend(loc="upper left", fontsize=8)
    drag_rows = [r for r in res.rows if r["time"] >= 1.0 - 1e-9]
    if drag_rows:
        travel = np.array([r["travel"] for r in drag_rows])
        T = np.array([abs(r["contact_fx"]) for r in drag_rows])
        N = np.array([-r["contact_fy"] for r in drag_rows])
        full = np.array([r["slip_share"] >= 0.99 for r in drag_rows])
        zoom = a2.inset_axes([0.14, 0.14, 0.36, 0.42])
        for ax in (a2, zoom):
            ax.plot(travel, mu * N, "-", color="C1", label=r"$\mu$ x normal force N")
            ax.plot(travel, T, "-", color="C0", lw=0.8)
            ax.plot(travel[full], T[full], "o", color="C0", ms=4, label="tangential force T, full slip")
            ax.plot(travel[~full], T[~full], "o", color="C0", mfc="white", ms=4,
                    label="T, partly sticking")
        zoom.set_xlim(-0.002, 0.04)
        zoom.set_title("first 0.4 mm", fontsize=8)
        zoom.tick_params(labelsize=7)
        a2.set(xlabel="drag distance of the cylinder [cm]", ylabel="force [kgf per cm of length]",
               title=rf"drag with Coulomb friction, $\mu$ = {mu}", ylim=(0, 1.25 * mu * N.max()))
        a2.legend(loc="lower right", fontsize=8)
    fig.savefig(out / "ironing.png", dpi=130)
    plt.close(fig)
    if end is not None:
        print(f"Hertz at the end of the indentation (P = {P:.4g} kgf/cm): half-width "
              f"{end['half_width']:.4g} cm, Hertz {a_hertz:.4g} cm, ratio {ratio_a:.4f}; peak pressure "
              f"{end['p_max']:.4g} kgf/cm^2, Hertz {p0_hertz:.4g}, ratio {ratio_p:.4f} (tolerance 5 %)")
    if len(sliding):
        print(f"Coulomb in full slip ({len(sliding)} increments): T / (mu N) from {ratio_T.min():.4f} "
              f"to {ratio_T.max():.4f} (tolerance 3 %)")
    print(f"{res.message}; {'OK' if ok else 'FAILED'}: ParaView {out / 'results.pvd'}")
sys.exit(0 if ok else 1)

# %% [markdown]
# # Metal ring crushed between rigid plates (plane strain, elastic-plastic)
#
# The `ring` scene: a ring OD 11.43, wall 0.866 (E = 1.89e6, nu = 0.3, J2 flow theory with the
# mild-steel hardening table of the scene) crushed between two rigid plates (mu = 0.1) to a total
# approach delta = 6.6. One quarter is modelled with symmetry conditions; the upper plate moves down by
# delta / 2. Run: `.venv/bin/python demos/demo_ring.py [--out DIR] [--set key=value ...]`
# (for instance `--set law=chen` or `--set plane=plane_stress`).

# %%
import argparse
import logging
import pathlib

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from mpi4py import MPI  # noqa: E402

from comove_dolfinx.job import run_scene  # noqa: E402
from comove_dolfinx.plotting import Snapshots, draw_plane, read_history, snapshot_grid  # noqa: E402
from comove_dolfinx.scenes import get_scene, split_delta  # noqa: E402

logging.disable(logging.INFO)
parser = argparse.ArgumentParser(description="the ring scene with pictures")
parser.add_argument("--out", default="results/demo_ring")
parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE")
args = parser.parse_args()
out = pathlib.Path(args.out)
scene = get_scene("ring", args.set)

# %% [markdown]
# Keep the deformed quarter at a few approaches, coloured by the equivalent plastic strain.

# %%
d = scene.delta_max
snaps = Snapshots([0.15 * d, 0.3 * d, 0.6 * d, d], field="plastic_strain")
result = run_scene(scene, out, callbacks=[snaps])

# %% [markdown]
# Load against approach with the thin-ring elastic stiffness (delta = 0.1488 P R^3 / (E' I), E' = E /
# (1 - nu^2) in plane strain), the rigid-plastic estimates of the collapse load (four hinges,
# P0 = 4 M_p / R) and the DeRunz-Hodge post-collapse curve P0 / sqrt(1 - (delta/D)^2), D = 2R (theory.md
# 6.4); contact width and the gap at the crown, which opens when the contact zone splits in two.
# A strain-hardening ring must carry more than the rigid-perfectly-plastic ring: the demo checks that
# P stays above the DeRunz-Hodge curve once the ring has collapsed.
# The contact width moves in steps of about a facet: the zone is two or three facets wide and the
# pressure is sampled at the facets' quadrature points.

# %%
if MPI.COMM_WORLD.rank == 0:
    def plate(ax, snap):
        draw_plane(ax, scene.R_out + scene.gap - 0.5 * snap.load, -0.3, scene.R_out + 1.0,
                   below=False)

    snapshot_grid(snaps.taken, plate, out / "ring_shapes.png",
                  "ring (quarter): deformed configurations", load_name="delta [cm]")
    h = read_history(out / "history.csv", origin=True)
    h["crown_gap"][0] = scene.gap
    t = scene.wall
    R = scene.R_out - t / 2
    s0 = scene.table().sigma_y(0.0)
    plane_strain = scene.plane == "plane_strain"
    k = 2 / np.sqrt(3) if plane_strain else 1.0
    P0 = 4 * k * s0 * t ** 2 / 4 / R
    E1 = scene.E / (1 - scene.nu ** 2) if plane_strain else scene.E
    stiffness = E1 * t ** 3 / 12 / (0.1488 * R ** 3)
    dd = np.linspace(0, d, 200)

    def derunz_hodge(delta):
        return P0 / np.sqrt(1 - (delta / (2 * R)) ** 2)

    fig, (a1, a2) = plt.subplots(1, 2, figsize=(11, 4))
    a1.plot(h["load"], h["force"], "-", label="co-moving S-R, " + scene.law)
    a1.plot([0, P0 / stiffness], [0, P0], ":", color="k", label="thin ring, elastic")
    a1.plot(dd, derunz_hodge(dd), "--", label="DeRunz-Hodge (rigid-plastic)")
    a1.axhline(P0, color="grey", lw=0.8, ls=":", label="collapse load $P_0$")
    a1.set(xlabel="plate approach delta [cm]", ylabel="P [kgf per cm of ring]",
           title="load against approach")
    a1.legend()
    a2.plot(h["load"], h["contact_width"], label="contact width [cm]")
    a2.plot(h["load"], 100 * np.maximum(h["crown_gap"], 0), label="crown gap x 100 [cm]")
    split = split_delta(h["load"], h["crown_gap"], h["contact_width"])
    if split is not None:
        a2.axvline(split, color="grey", ls="--", lw=0.8)
        print(f"the contact zone splits at delta = {split:.4g} (the crown lifts off the plate)")
    else:
        print("the contact zone does not split within the run")
    a2.set(xlabel="plate approach delta [cm]", title="contact on the plate")
    a2.legend()
    fig.tight_layout()
    fig.savefig(out / "ring_curves.png", dpi=130)
    plt.close(fig)
    collapsed = h["load"] >= 1.0
    ratio = h["force"][collapsed] / derunz_hodge(h["load"][collapsed])
    if ratio.size:
        print(f"P / DeRunz-Hodge for delta >= 1: {ratio.min():.3f} to {ratio.max():.3f} "
              f"({'above' if ratio.min() > 1 else 'NOT above'} the rigid-plastic curve, as hardening "
              "requires)")
    print(f"{result.message}; ParaView: {out / 'results.xdmf'} (plastic_strain); pictures: "
          f"{out}/ring_*.png")

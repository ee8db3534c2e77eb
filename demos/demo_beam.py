# %% [markdown]
# # Cantilever pressed onto a rigid foundation
#
# The `beam` scene: a cantilever L = 10, h = 0.5 (plane stress, E = 1000, nu = 0.3) clamped at x = 0,
# loaded by a pressure q that follows its deforming upper face, and pressed onto a rigid plane 3 cm
# below (Coulomb friction mu = 0.1, pressure lagged one increment). The S-R co-moving update advances
# the stress. Run: `.venv/bin/python demos/demo_beam.py [--out DIR] [--set key=value ...]`, also under
# `mpirun -n 2`.

# %%
import argparse
import logging
import pathlib

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from mpi4py import MPI  # noqa: E402

from comove_dolfinx.job import run_scene  # noqa: E402
from comove_dolfinx.plotting import Snapshots, draw_plane, read_history, snapshot_grid  # noqa: E402
from comove_dolfinx.scenes import get_scene  # noqa: E402

logging.disable(logging.INFO)
parser = argparse.ArgumentParser(description="the beam scene with pictures")
parser.add_argument("--out", default="results/demo_beam")
parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE")
args = parser.parse_args()
out = pathlib.Path(args.out)
scene = get_scene("beam", args.set)

# %% [markdown]
# Run the scene, keeping the deformed beam at a few load levels (the first converged increment at or
# beyond each).

# %%
q = scene.q_max
snaps = Snapshots([0.05 * q, 0.25 * q, 0.5 * q, q])
result = run_scene(scene, out, callbacks=[snaps])

# %% [markdown]
# Deformed configurations with the foundation, coloured by the von Mises stress, and the tip
# deflection and contact length against the load.

# %%
if MPI.COMM_WORLD.rank == 0:
    def plane(ax, snap):
        draw_plane(ax, -scene.gap, -0.5, scene.L + 0.5)

    snapshot_grid(snaps.taken, plane, out / "beam_shapes.png", "beam: deformed configurations",
                  load_name="q [kgf/cm$^2$]")
    h = read_history(out / "history.csv", origin=True)
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(10, 4))
    a1.plot(h["load"], -h["tip_uy"], "o-", ms=3, label="$-u_y$ at the tip")
    a1.plot(h["load"], -h["tip_ux"], "s-", ms=3, label="$-u_x$ at the tip")
    a1.axhline(scene.gap, color="grey", ls="--", lw=0.8, label="gap")
    a1.set(xlabel="q [kgf/cm$^2$]", ylabel="displacement [cm]", title="tip (x = L, y = 0)")
    a1.legend()
    a2.plot(h["load"], h["contact_length"], "o-", ms=3)
    a2.set(xlabel="q [kgf/cm$^2$]", ylabel="contact length [cm]", title="contact (deformed length)")
    fig.tight_layout()
    fig.savefig(out / "beam_curves.png", dpi=130)
    plt.close(fig)
    print(f"{result.message}; ParaView: {out / 'results.xdmf'}; pictures: {out}/beam_*.png")

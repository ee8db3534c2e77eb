# %% [markdown]
# # Thick circular plate pressed onto a rigid base (axisymmetric)
#
# The `plate` scene: a plate R = 10, t = 2 (E = 1000, nu = 0.3), its lower rim (0 <= z <= 0.25) held in
# z and free in r, loaded by a pressure p on its upper face that follows the deforming face, and
# pressed onto a rigid base 1.5 below (mu = 0.1). Axisymmetric: integrals weighted by 2 pi r, hoop
# strain u_r / r. Run: `.venv/bin/python demos/demo_plate.py [--out DIR] [--set key=value ...]`.

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
parser = argparse.ArgumentParser(description="the plate scene with pictures")
parser.add_argument("--out", default="results/demo_plate")
parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE")
args = parser.parse_args()
out = pathlib.Path(args.out)
scene = get_scene("plate", args.set)

# %%
p = scene.p_max
snaps = Snapshots([0.2 * p, 0.5 * p, p])
result = run_scene(scene, out, callbacks=[snaps])

# %% [markdown]
# The section r-z and its mirror image give the whole diameter; colour: von Mises stress.

# %%
if MPI.COMM_WORLD.rank == 0:
    def base(ax, snap):
        draw_plane(ax, -scene.gap, -scene.R - 0.5, scene.R + 0.5)

    snapshot_grid(snaps.taken, base, out / "plate_shapes.png", "plate: deformed configurations",
                  mirror=True, xlabel="r [cm]", ylabel="z [cm]", load_name="p [kgf/cm$^2$]")
    h = read_history(out / "history.csv", origin=True)
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(10, 4))
    a1.plot(h["load"], -h["center_uz"], "o-", ms=3, label="$-u_z$ at the centre")
    a1.plot(h["load"], h["rim_ur"], "s-", ms=3, label="$u_r$ at the lower rim")
    a1.axhline(scene.gap, color="grey", ls="--", lw=0.8, label="gap")
    a1.set(xlabel="p [kgf/cm$^2$]", ylabel="displacement [cm]")
    a1.legend()
    a2.plot(h["load"], h["contact_radius"], "o-", ms=3)
    a2.set(xlabel="p [kgf/cm$^2$]", ylabel="contact radius [cm]", title="contact (deformed radius)")
    fig.tight_layout()
    fig.savefig(out / "plate_curves.png", dpi=130)
    plt.close(fig)
    print(f"{result.message}; ParaView: {out / 'results.xdmf'}; pictures: {out}/plate_*.png")

"""Pictures: snapshots of the deformed body gathered on rank 0, drawn with matplotlib.

A :class:`Snapshot` holds the deformed positions of the mesh vertices (x + u), the triangles of the
(first-order view of the) mesh and a smooth vertex field (von Mises stress, or the equivalent plastic
strain of elastic-plastic bodies: the cell averages of the quadrature data averaged at each vertex
over its cells, drawn with Gouraud shading rather than as a checkerboard of cells), gathered from
every rank onto rank 0; other ranks hold ``None``. :class:`Snapshots` is a job writer.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from dolfinx import fem

from .. import compat
from ..mechanics.material_data import von_mises
from .writers import Writer


@dataclass
class Snapshot:
    load: float                     # physical load level (history's ``load``)
    xy: np.ndarray                  # (vertices, 2) deformed positions
    triangles: np.ndarray           # (cells, 3) vertex numbers
    values: np.ndarray              # (vertices,) vertex values
    label: str                      # what ``values`` are


class Snapshots(Writer):
    """A writer that keeps the deformed body at chosen load levels (the history's ``load``).

    ``levels`` are physical load levels; the first converged increment at or beyond each is kept
    (so a run with few increments keeps fewer pictures). ``field`` is "von_mises" or
    "plastic_strain".
    """

    def __init__(self, levels, field: str = "von_mises", column: str = "load"):
        self.levels, self.column = sorted(levels), column
        self.field = field
        self.taken: list[Snapshot] = []
        self._next = 0
        self._V1 = None

    def write(self, run, row, inc) -> None:
        model, load = run.model, row[self.column]
        if self._next >= len(self.levels) or load < self.levels[self._next] - 1e-12:
            return
        while self._next < len(self.levels) and load >= self.levels[self._next] - 1e-12:
            self._next += 1
        snap = self.take(model, row["load"])
        if snap is not None:
            self.taken.append(snap)

    def take(self, model, load: float) -> Snapshot | None:
        msh = model.mesh
        if self._V1 is None:
            self._V1 = compat.function_space(msh, "Lagrange", 1, (2,))
            self._u1 = fem.Function(self._V1)
        V1, u1 = self._V1, self._u1
        u1.interpolate(model.u)
        imap = V1.dofmap.index_map
        n_own = imap.size_local
        X = V1.tabulate_dof_coordinates()[:n_own, :2]
        xy = X + u1.x.array.reshape(-1, 2)[:n_own]
        gidx = imap.local_to_global(np.arange(n_own, dtype=np.int32))
        n_cells = msh.topology.index_map(msh.topology.dim).size_local
        local = compat.cell_dofs(V1, n_cells)
        tri = imap.local_to_global(local.ravel()).reshape(-1, 3)
        rule = model.rule
        if self.field == "plastic_strain" and model.p is not None:
            vals, label = rule.cell_average(model.p.x.array)[:n_cells], "equivalent plastic strain"
        else:
            vals = rule.cell_average(von_mises(model.cauchy_stress()))[:n_cells]
            label = "von Mises stress [kgf/cm$^2$]"
        comm = msh.comm
        parts = comm.gather((gidx, xy, tri, vals), root=0)
        if comm.rank != 0:
            return None
        n = imap.size_global
        XY = np.zeros((n, 2))
        for g, p, _, _ in parts:
            XY[g] = p
        T = np.concatenate([t for _, _, t, _ in parts])
        Vals = np.concatenate([v for _, _, _, v in parts])
        # vertex values: the mean of the cell values around each vertex
        acc, cnt = np.zeros(n), np.zeros(n)
        np.add.at(acc, T.ravel(), np.repeat(Vals, 3))
        np.add.at(cnt, T.ravel(), 1.0)
        return Snapshot(load, XY, T, acc / np.maximum(cnt, 1.0), label)


def draw(ax, snap: Snapshot, vmin=None, vmax=None, mirror: bool = False, cmap: str = "viridis"):
    """The deformed body coloured by its vertex field (and its mirror image in x = 0 if asked)."""
    import matplotlib.tri as mtri
    art = None
    for sign in ((1.0, -1.0) if mirror else (1.0,)):
        tri = mtri.Triangulation(sign * snap.xy[:, 0], snap.xy[:, 1], snap.triangles)
        art = ax.tripcolor(tri, snap.values, vmin=vmin, vmax=vmax, cmap=cmap, shading="gouraud")
    ax.set_aspect("equal")
    return art


def draw_plane(ax, y: float, x0: float, x1: float, below: bool = True) -> None:
    """A rigid plane y = const seen edge-on, hatched on its solid side."""
    ax.plot([x0, x1], [y, y], color="k", lw=1.5)
    h = 0.04 * (x1 - x0)
    ax.fill_between([x0, x1], y, y - h if below else y + h, facecolor="none", edgecolor="grey",
                    hatch="///", lw=0)


def snapshot_grid(snaps: list[Snapshot], obstacle, path, title: str, mirror: bool = False,
                  xlabel: str = "x [cm]", ylabel: str = "y [cm]", load_name: str = "load",
                  columns: int = 1, clip: float | None = None) -> None:
    """Panels of equal size (``columns`` per row), one per snapshot, one colour scale shared by all;
    ``obstacle(ax, snap)`` draws the obstacle. ``clip``: the scale's top at this percentile of the
    values (a corner singularity would otherwise saturate it; the colour bar shows the overflow)."""
    import matplotlib.pyplot as plt
    if not snaps:
        return
    vals = np.concatenate([s.values for s in snaps])
    vmin = float(vals.min())
    vmax = float(np.percentile(vals, clip)) if clip else float(vals.max())
    n = len(snaps)
    rows = -(-n // columns)
    width = 8.0 if columns == 1 else 4.5 * columns
    fig, axes = plt.subplots(rows, columns, figsize=(width, 4.0), squeeze=False, sharex=True, sharey=True,
                             layout="constrained")                # the height is set once drawn (below)
    art = None
    for ax, s in zip(axes.ravel(), snaps):
        art = draw(ax, s, vmin, vmax, mirror)
        obstacle(ax, s)
        ax.set_title(f"{load_name} = {s.load:.4g}", fontsize=9)
    for ax in axes.ravel()[n:]:
        ax.set_visible(False)
    for ax in axes[:, 0]:
        ax.set_ylabel(ylabel)
    for ax in axes[-1, :]:
        ax.set_xlabel(xlabel)
    # the panels' height from their drawn extent (body and obstacles, equal axes), so that they fill
    # the width without blank space beside or between them
    (x0, x1), (y0, y1) = axes[0, 0].get_xlim(), axes[0, 0].get_ylim()
    panel = (width - 1.9) / columns                        # less the colour bar and the y labels
    fig.set_size_inches(width, 0.7 + rows * (panel * (y1 - y0) / (x1 - x0) + 0.45))
    fig.suptitle(title)
    fig.colorbar(art, ax=axes.ravel().tolist(), label=snaps[0].label, shrink=0.8,
                 extend="max" if clip and vmax < vals.max() else "neither")
    fig.savefig(path, dpi=130)
    plt.close(fig)

"""Pictures for the demos: snapshots of the deformed body gathered on rank 0, drawn with matplotlib.

A :class:`Snapshot` holds the deformed positions of the mesh vertices (x + u), the triangles of the
(first-order view of the) mesh and one value per cell (von Mises stress, or the equivalent plastic
strain of elastic-plastic bodies), gathered from every rank onto rank 0; other ranks hold ``None``.
"""
from __future__ import annotations

import csv
from dataclasses import dataclass

import numpy as np
from dolfinx import fem

from . import compat
from .materials import von_mises


@dataclass
class Snapshot:
    load: float                     # physical load level (history's ``load``)
    xy: np.ndarray                  # (vertices, 2) deformed positions
    triangles: np.ndarray           # (cells, 3) vertex numbers
    values: np.ndarray              # (cells,) cell values
    label: str                      # what ``values`` are


class Snapshots:
    """A run_scene callback that keeps the deformed body at chosen load levels.

    ``levels`` are physical load levels; the first converged increment at or beyond each is kept
    (so a run with few increments keeps fewer pictures). ``field`` is "von_mises" or
    "plastic_strain".
    """

    def __init__(self, levels, field: str = "von_mises"):
        self.levels = sorted(levels)
        self.field = field
        self.taken: list[Snapshot] = []
        self._next = 0
        self._V1 = None

    def __call__(self, scene, model, inc) -> None:
        load = inc.load * scene.load_max
        if self._next >= len(self.levels) or load < self.levels[self._next] - 1e-12:
            return
        while self._next < len(self.levels) and load >= self.levels[self._next] - 1e-12:
            self._next += 1
        snap = self.take(model, load)
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
        return Snapshot(load, XY, T, Vals, label)


def read_history(path, origin: bool = False) -> dict[str, np.ndarray]:
    """Columns of a history.csv as arrays; with ``origin`` led by the unloaded state (a row of zeros:
    no load, displacement, force or contact), so that curves start where the body did."""
    with open(path) as fh:
        rows = list(csv.DictReader(fh))
    lead = [0.0] if origin else []
    return {k: np.array(lead + [float(r[k]) for r in rows]) for k in (rows[0] if rows else [])}


def draw(ax, snap: Snapshot, vmin=None, vmax=None, mirror: bool = False, cmap: str = "viridis"):
    """The deformed body coloured by its cell values (and its mirror image in x = 0 if asked)."""
    import matplotlib.tri as mtri
    art = None
    for sign in ((1.0, -1.0) if mirror else (1.0,)):
        tri = mtri.Triangulation(sign * snap.xy[:, 0], snap.xy[:, 1], snap.triangles)
        art = ax.tripcolor(tri, facecolors=snap.values, vmin=vmin, vmax=vmax, cmap=cmap,
                           edgecolors="none")
    ax.set_aspect("equal")
    return art


def draw_plane(ax, y: float, x0: float, x1: float, below: bool = True) -> None:
    """A rigid plane y = const seen edge-on, hatched on its solid side."""
    ax.plot([x0, x1], [y, y], color="k", lw=1.5)
    h = 0.04 * (x1 - x0)
    ax.fill_between([x0, x1], y, y - h if below else y + h, facecolor="none", edgecolor="grey",
                    hatch="///", lw=0)


def snapshot_grid(snaps: list[Snapshot], obstacle, path, title: str, mirror: bool = False,
                  xlabel: str = "x [cm]", ylabel: str = "y [cm]", load_name: str = "load") -> None:
    """One panel per snapshot, shared colour scale; ``obstacle(ax, snap)`` draws the obstacle."""
    import matplotlib.pyplot as plt
    if not snaps:
        return
    vmin = min(float(s.values.min()) for s in snaps)
    vmax = max(float(s.values.max()) for s in snaps)
    n = len(snaps)
    fig, axes = plt.subplots(n, 1, figsize=(8, 1.0 + 2.2 * n), squeeze=False, layout="constrained")
    art = None
    for ax, s in zip(axes[:, 0], snaps):
        art = draw(ax, s, vmin, vmax, mirror)
        obstacle(ax, s)
        ax.set_title(f"{load_name} = {s.load:.4g}", fontsize=9)
        ax.set_ylabel(ylabel)
    axes[-1, 0].set_xlabel(xlabel)
    fig.suptitle(title)
    fig.colorbar(art, ax=axes[:, 0].tolist(), label=snaps[0].label, shrink=0.8)
    fig.savefig(path, dpi=130)
    plt.close(fig)

"""The benchmarks' charts (PNG, drawn by rank 0 with matplotlib's Agg backend)."""
from __future__ import annotations

import pathlib

import numpy as np

from .runs import COMM


def _pyplot():
    """matplotlib.pyplot on the Agg backend (no display needed)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    return plt


def lines(path, series: dict, xlabel: str, ylabel: str, title: str, logy=True) -> None:
    """One line per series: {label: (x, y, spread)}, log x (and y, unless ``logy`` is False),
    error bars of half the spread."""
    if COMM.rank != 0:
        return
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(6.4, 4.2))
    colours = plt.get_cmap("tab20").colors            # more series than the default ten colours
    for k, (label, (x, y, err)) in enumerate(series.items()):
        ax.errorbar(x, y, yerr=np.asarray(err) / 2, marker="osD^v<>"[k % 7], capsize=3, label=label,
                    color=colours[(2 * k) % 20 if k < 10 else (2 * k + 1) % 20])
    ax.set_xscale("log")
    if logy:
        ax.set_yscale("log")
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.set_title(title, fontsize=10)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def floor_chart(path: pathlib.Path, rows: list[dict], goal: float = 1.3) -> None:
    """Two panels: CPU s per iteration and per floor iteration against dofs (absolute: they move
    with the host's speed between sizes), and their ratio (what the floor's pairing makes hold)
    with the goal."""
    if COMM.rank != 0:
        return
    plt = _pyplot()
    d = [int(r["dofs"]) for r in rows]

    def col(key):
        return np.array([float(r[key]) for r in rows])
    fig, (a, b) = plt.subplots(1, 2, figsize=(10, 4))
    a.errorbar(d, col("iteration_cpu_s"), yerr=col("iteration_spread_s") / 2, marker="o", capsize=3,
               label="Newton iteration (ring)")
    a.errorbar(d, col("floor_cpu_s"), yerr=col("floor_spread_s") / 2, marker="s", capsize=3,
               label="floor: elastic K, R, MUMPS")
    a.set_yscale("log")
    a.set_ylabel("CPU s per iteration")
    a.set_title("per iteration (moves with the host's speed)", fontsize=10)
    b.errorbar(d, col("ratio"), yerr=col("ratio_spread") / 2, marker="o", capsize=3, color="C3",
               label="iteration / floor (median of runs)")
    b.axhline(goal, color="0.3", ls="--", lw=1, label=f"goal {goal}")
    b.set_ylim(1.0, max(2.0, float(col("ratio").max()) + 0.2))
    b.set_ylabel("ratio")
    b.set_title("ratio, the floor sampled within each run", fontsize=10)
    for ax in (a, b):
        ax.set_xscale("log")
        ax.set_xlabel("dofs")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8)
    fig.suptitle("ring: one Newton iteration against the linear-elastic floor", fontsize=11)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def parts_chart(path: pathlib.Path, rows: list[dict]) -> None:
    """Horizontal bars, one group per part of the first size: the three conditions."""
    plt = _pyplot()
    size = rows[0]["size"]
    rows = [r for r in rows if r["size"] == size]
    y = np.arange(len(rows))
    fig, ax = plt.subplots(figsize=(7.4, 4.4))
    for k, (key, label) in enumerate((("alone_us", "back to back"),
                                      ("after_factorisation_us", "after a factorisation and solve"),
                                      ("after_idle_us", "after 4 ms of the interpreter"))):
        ax.barh(y + (k - 1) * 0.27, [r[key] for r in rows], height=0.27, label=label)
    ax.set_yticks(y, [r["part"] for r in rows], fontsize=8)
    ax.invert_yaxis()
    ax.set_xscale("log")
    ax.set_xlabel("wall time of one call, microseconds")
    ax.set_title(f"ring, {rows[0]['dofs']} dofs: the parts of an iteration and when they run", fontsize=10)
    ax.grid(True, axis="x", which="both", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)

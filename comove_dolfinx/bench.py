"""Speed and accuracy benchmarks; each writes its figures to CSV files and charts, never asserts.

    python -m comove_dolfinx.bench elastica --out results/bench     # updates x increments
    python -m comove_dolfinx.bench contact  --out results/bench     # beam/plate: methods, gamma0
    python -m comove_dolfinx.bench ring     --out results/bench     # ring: mesh sizes

Timings are wall-clock seconds of the increment loop (forms already compiled), on whatever machine
runs them; compare them within one run.
"""
from __future__ import annotations

import argparse
import csv
import logging
import pathlib
import time

from mpi4py import MPI

from .scenes import get_scene
from .solver import IncrementalSolver, StepSettings

# lam = 5: v/L and (L - x_tip)/L of the inextensible elastica (theory.md 7.1)
ELASTICA_5 = (0.71379, 0.38763)


def _write_csv(path: pathlib.Path, rows: list[dict]) -> None:
    if MPI.COMM_WORLD.rank != 0 or not rows:
        return
    with open(path, "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)


def elastica(out: pathlib.Path, updates=None, steps=(1, 2, 5, 10, 20)) -> list[dict]:
    """Tip-deflection error at lam = 5 and wall time against the number of equal increments."""
    from .updates import UPDATES
    rows = []
    for name in updates or list(UPDATES):
        for n in steps:
            scene = get_scene("elastica", [f"update={name}", f"n_steps={n}"])
            model = scene.build_model(scene.mesh_data(MPI.COMM_WORLD))
            model.finalize()
            solver = IncrementalSolver(model, StepSettings(n_steps=n, max_cutbacks=0))
            t0 = time.perf_counter()
            res = solver.run()
            wall = time.perf_counter() - t0
            ux, uy = scene.history_row(model).values()
            done = res.completed
            rows.append({"update": name, "increments": n, "converged": int(done),
                         "tip_deflection": -uy if done else float("nan"),
                         "error_percent": 100 * (-uy / scene.L / ELASTICA_5[0] - 1) if done
                         else float("nan"),
                         "newton_its": sum(res.newton_its), "wall_s": wall})
    _write_csv(out / "elastica_increments.csv", rows)
    if MPI.COMM_WORLD.rank == 0:
        _plot_elastica(out, rows)
    return rows


def _plot_elastica(out, rows):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(10, 4))
    for name in dict.fromkeys(r["update"] for r in rows):
        rs = [r for r in rows if r["update"] == name and r["converged"]]
        a1.loglog([r["increments"] for r in rs], [max(abs(r["error_percent"]), 1e-3) for r in rs],
                  "o-", label=name)
        a2.loglog([r["wall_s"] for r in rs], [max(abs(r["error_percent"]), 1e-3) for r in rs],
                  "o-", label=name)
    a1.axhline(1.0, color="grey", lw=0.8, ls="--")
    a1.set(xlabel="increments", ylabel="|tip deflection error| [%]",
           title="elastica, lam = 5 (error floor 1e-3 %)")
    a2.set(xlabel="wall time of the increments [s]", ylabel="|tip deflection error| [%]")
    a1.legend()
    fig.tight_layout()
    fig.savefig(out / "elastica_increments.png", dpi=120)
    plt.close(fig)


def main(argv=None) -> int:
    logging.disable(logging.INFO)
    p = argparse.ArgumentParser(prog="python -m comove_dolfinx.bench", description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("study", choices=["elastica", "contact", "ring", "all"])
    p.add_argument("--out", default="results/bench")
    args = p.parse_args(argv)
    out = pathlib.Path(args.out)
    if MPI.COMM_WORLD.rank == 0:
        out.mkdir(parents=True, exist_ok=True)
    MPI.COMM_WORLD.barrier()
    studies = {"elastica": elastica}
    for name in (list(studies) if args.study == "all" else [args.study]):
        if name not in studies:
            print(f"study {name!r} is not available yet")
            continue
        rows = studies[name](out)
        if MPI.COMM_WORLD.rank == 0:
            for r in rows:
                print(", ".join(f"{k}={v:.4g}" if isinstance(v, float) else f"{k}={v}"
                                for k, v in r.items()))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

"""Speed and accuracy benchmarks; each writes its figures to CSV files and charts, never asserts.

    python -m comove_dolfinx.bench elastica --out results/bench     # updates x increments
    python -m comove_dolfinx.bench contact  --out results/bench     # beam/plate: methods, gamma0
    python -m comove_dolfinx.bench ring     --out results/bench     # ring: mesh sizes
    python -m comove_dolfinx.bench ring_steps --out results/bench   # ring: increments, friction lag
    python -m comove_dolfinx.bench ring_newton --out results/bench  # ring: penalty, Newton test
    python -m comove_dolfinx.bench ring_tolerance --out results/bench  # ring: rtol x increments

Timings are wall-clock seconds, on whatever machine runs them; compare them within one run. The
elastica study times the increment loop alone; the contact and ring studies run whole scenes through
``run_scene`` (results of each under out/runs/) and report the wall time of the run (with output) and,
apart, the part of it spent building and compiling the model (``compile_s``: seconds when the process
meets a kind of model first and its forms are not in the JIT cache, hundredths afterwards).
"""
from __future__ import annotations

import argparse
import csv
import logging
import pathlib
import time

from mpi4py import MPI

from .mechanics.model import Model
from .presets import get_scene
from .solver import IncrementalSolver, StepSettings

# lam = 5: v/L and (L - x_tip)/L of the inextensible elastica (docs/theory.md section 8.1)
ELASTICA_5 = (0.71379, 0.38763)


def _write_csv(path: pathlib.Path, rows: list[dict]) -> None:
    if MPI.COMM_WORLD.rank != 0 or not rows:
        return
    with open(path, "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)


def elastica(out: pathlib.Path, updates=None, steps=(1, 2, 3, 4, 5, 10, 20)) -> list[dict]:
    """Tip-deflection error at lam = 5 and wall time against the number of equal increments."""
    from .mechanics.updates import UPDATES
    rows = []
    for name in updates or list(UPDATES):
        for n in steps:
            scene = get_scene("elastica", [f"update={name}", f"n_steps={n}"])
            body, items, probes = scene.build(scene.mesh_data(MPI.COMM_WORLD))
            model = Model(body, items)
            model.finalize()
            tip = probes[0]
            tip.attach(model)
            solver = IncrementalSolver(model, StepSettings(n_steps=n, max_cutbacks=0))
            t0 = time.perf_counter()
            res = solver.run()
            wall = time.perf_counter() - t0
            ux, uy = tip(model).values()
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


def _plot_panels(path: pathlib.Path, rows: list[dict], group: str, panels: list[dict]) -> None:
    """One figure with a panel per entry of ``panels`` and in each a curve per value of
    ``row[group]``; a panel gives x and y (functions of a row), labels, scales, optional hline."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(1, len(panels), figsize=(5 * len(panels), 4))
    for key in dict.fromkeys(r[group] for r in rows):
        rs = [r for r in rows if r[group] == key]
        for ax, p in zip(axes, panels):
            ax.plot([p["x"](r) for r in rs], [p["y"](r) for r in rs], "o-", label=f"{group} {key:g}"
                    if isinstance(key, float) else str(key))
    for ax, p in zip(axes, panels):
        ax.set(xscale=p.get("xscale", "linear"), yscale=p.get("yscale", "linear"),
               xlabel=p["xlabel"], ylabel=p["ylabel"], title=p.get("title", ""))
        if "hline" in p:
            ax.axhline(p["hline"], color="grey", lw=0.8, ls="--")
    axes[0].legend()
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def _plot_elastica(out, rows):
    def err(r):
        return max(abs(r["error_percent"]), 1e-3)
    label = "|tip deflection error| [%]"
    _plot_panels(out / "elastica_increments.png", [r for r in rows if r["converged"]], "update", [
        dict(x=lambda r: r["increments"], y=err, xscale="log", yscale="log", hline=1.0,
             xlabel="increments", ylabel=label, title="elastica, lam = 5 (error floor 1e-3 %)"),
        dict(x=lambda r: r["wall_s"], y=err, xscale="log", yscale="log",
             xlabel="wall time of the increments [s]", ylabel=label)])


def _run(name: str, sets: list[str], out: pathlib.Path, tag: str,
         newton=None) -> tuple[dict, list[dict]]:
    """Run scene ``name`` with overrides (and Newton settings instead of the scene's) into
    out/runs/<tag>; (run.json, history rows)."""
    import json

    from .cli import run_scene
    scene = get_scene(name, sets)
    folder = out / "runs" / tag
    run_scene(scene, folder, progress=False, newton=newton, overwrite=True)
    MPI.COMM_WORLD.barrier()
    info = json.loads((folder / "run.json").read_text())
    with open(folder / "history.csv") as fh:
        rows = [{k: float(v) for k, v in r.items()} for r in csv.DictReader(fh)]
    return info, rows


def _its(info: dict) -> dict:
    its = info["newton_its"]
    return {"completed": int(info["completed"]), "increments": len(its),
            "newton_mean": sum(its) / len(its) if its else float("nan"),
            "newton_max": max(its) if its else 0, "failed_its": info.get("failed_its", 0),
            "wall_s": info["wall_s"],
            "compile_s": info["timing"].get("setup and compilation", 0.0)}


CONTACT_VARIANTS = (("penalty", []), ("penalty_gamma0x10", ["gamma0=1000"]),
                    ("nitsche", ["contact=nitsche"]),
                    ("nitsche_gamma0x10", ["contact=nitsche", "gamma0=1000"]))


def contact(out: pathlib.Path) -> list[dict]:
    """Beam and plate at the scene defaults: penalty against Nitsche, and gamma0 multiplied by 10."""
    rows = []
    for name, defl, extent in (("beam", "tip_uy", "contact_length"),
                               ("plate", "center_uz", "contact_radius")):
        for tag, sets in CONTACT_VARIANTS:
            info, hist = _run(name, sets, out, f"{name}_{tag}")
            last = hist[-1] if hist else {}
            rows.append({"scene": name, "variant": tag, "gamma0": info["parameters"]["gamma0"],
                         "load": last.get("load", float("nan")),
                         "deflection": -last.get(defl, float("nan")),
                         "extent": last.get(extent, float("nan")),
                         "contact_force": last.get("contact_force", float("nan")),
                         "max_penetration": info.get("max_penetration", float("nan")),
                         "first_contact_load": info.get("first_contact_load") or float("nan"),
                         **_its(info)})
    _write_csv(out / "contact_methods.csv", rows)
    return rows


RING_DELTAS = (1.0, 2.0, 4.0, 6.6)


def _at(hist: list[dict], key: str, load: float) -> float:
    """Linear interpolation of a history column at a load level (nan beyond the run)."""
    import numpy as np
    x = [0.0] + [r["load"] for r in hist]
    y = [0.0] + [r[key] for r in hist]
    return float(np.interp(load, x, y)) if hist and load <= x[-1] + 1e-9 else float("nan")


def _p_against(hist: list[dict], ref: list[dict]) -> dict:
    """P at RING_DELTAS and its deviation in percent from the reference run's."""
    row = {}
    for d in RING_DELTAS:
        P, P_ref = _at(hist, "force", d), _at(ref, "force", d)
        row[f"P_at_{d:g}"] = P
        row[f"dP_at_{d:g}_percent"] = 100 * (P / P_ref - 1)
    return row


def _split(hist: list[dict]) -> float:
    from .presets import split_delta
    d = split_delta(*([r[k] for r in hist] for k in ("load", "crown_gap", "contact_width")))
    return float("nan") if d is None else d


def ring(out: pathlib.Path, factors=(1.0, 0.5, 2.0)) -> list[dict]:
    """The whole crush at the scene defaults and at half and twice the mesh size."""
    from .presets import Ring
    rows, curves = [], {}
    for f in factors:
        size = Ring.size * f
        info, hist = _run("ring", [f"size={size:g}"], out, f"ring_size{size:g}")
        curves[size] = hist
        rows.append({"size": size, "dofs": info["dofs"],
                     **{f"P_at_{d:g}": _at(hist, "force", d) for d in RING_DELTAS},
                     "split_delta": _split(hist),
                     "max_plastic_strain": hist[-1]["max_plastic_strain"] if hist else float("nan"),
                     **_its(info)})
    _write_csv(out / "ring_mesh.csv", rows)
    if MPI.COMM_WORLD.rank == 0:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        fig, ax = plt.subplots(figsize=(6, 4))
        for size, hist in curves.items():
            ax.plot([0] + [r["load"] for r in hist], [0] + [r["force"] for r in hist],
                    label=f"size {size:g} cm")
        ax.set(xlabel="plate approach delta [cm]", ylabel="P [kgf/cm]", title="ring crush")
        ax.legend()
        fig.tight_layout()
        fig.savefig(out / "ring_mesh.png", dpi=120)
        plt.close(fig)
    return rows


RING_STEPS = (10, 20, 30, 36, 60, 120)   # 36: the scene's default


def ring_steps(out: pathlib.Path, steps=RING_STEPS) -> list[dict]:
    """Accuracy against cost for the ring: the whole crush in n nominal increments (friction
    pressure lagged, the paper's scheme), each P(delta) compared with the finest run; and the
    scene's default increments with the pressure re-lagged to true Coulomb (relag=true); and Chen's
    single-parameter rate law (law=chen) at 1, 4 and 16 times the default increments, against the
    same J2 reference."""
    from .presets import Ring
    runs = [(f"lagged_n{n}", [f"n_steps={n}"]) for n in steps]
    runs.append((f"coulomb_n{Ring.n_steps}", [f"n_steps={Ring.n_steps}", "relag=true"]))
    runs += [(f"chen_n{k * Ring.n_steps}", [f"n_steps={k * Ring.n_steps}", "law=chen"])
             for k in (1, 4, 16)]
    results = {tag: _run("ring", sets, out, f"ring_{tag}") for tag, sets in runs}
    ref = results[f"lagged_n{max(steps)}"][1]
    rows = [{"run": tag, **_p_against(hist, ref), **_its(info)}
            for tag, (info, hist) in results.items()]
    _write_csv(out / "ring_increments.csv", rows)
    return rows


def _ring_newton_runs():
    from .solver import NewtonSettings
    tight = dict(line_search="energy", energy_eta=0.2)        # rtol 1e-8 of the initial residual
    force = dict(tight, scale="force")
    return (("gamma0_10_tight", ["gamma0=10"], NewtonSettings(**tight)),
            ("gamma0_1_tight_eta0.8", [], NewtonSettings(line_search="energy")),
            ("gamma0_1_tight", [], NewtonSettings(**tight)),
            ("gamma0_1_rtol1e-4", [], NewtonSettings(**force, rtol=1e-4)),
            ("default", [], None),
            ("gamma0_0.3", ["gamma0=0.3"], None),
            ("gamma0_0.1_tight", ["gamma0=0.1"], NewtonSettings(**tight)),
            ("gamma0_0.1", ["gamma0=0.1"], None),
            ("gamma0_0.03", ["gamma0=0.03"], None))


def ring_newton(out: pathlib.Path) -> list[dict]:
    """Newton iterations against accuracy for the ring: the penalty weight gamma0, the convergence
    test (1e-8 of the initial residual, or 1e-4 / 1e-3 of ||F_int||) and the energy line search's
    eta, each P(delta) against the stiffest penalty with the tight test (gamma0 = 10)."""
    results = {tag: _run("ring", sets, out, f"ring_newton_{tag}", newton)
               for tag, sets, newton in _ring_newton_runs()}
    ref = results["gamma0_10_tight"][1]
    rows = [{"run": tag, "gamma0": info["parameters"]["gamma0"], **_p_against(hist, ref),
             "split_delta": _split(hist), "max_penetration": info["max_penetration"], **_its(info)}
            for tag, (info, hist) in results.items()]
    _write_csv(out / "ring_newton.csv", rows)
    return rows


RING_TOLERANCES = (1e-3, 3e-3, 5e-3)
RING_TOLERANCE_STEPS = (30, 32, 34, 36, 38, 40)
RING_TIGHT = 1e-6


def _deviation(hist: list[dict], ref: list[dict], key: str, relative: bool = False) -> float:
    """Largest |hist - ref| of column ``key`` (or |hist / ref - 1| with ``relative``, where ref is
    not 0) over the load levels both runs reached."""
    ref_at = {round(r["load"], 9): r[key] for r in ref}
    pairs = [(r[key], ref_at[k]) for r in hist if (k := round(r["load"], 9)) in ref_at]
    dev = [abs(a / b - 1) if relative else abs(a - b) for a, b in pairs if not (relative and b == 0)]
    return max(dev) if dev else float("nan")


def ring_tolerance(out: pathlib.Path, steps=RING_TOLERANCE_STEPS, rtols=RING_TOLERANCES) -> list[dict]:
    """What a looser convergence test costs in accuracy: for each nominal number of increments, the
    crush with the scene's test (out-of-balance force below rtol ||F_int||) at each rtol, compared at
    every load level it shares with a run of the same increments converged to RING_TIGHT: the largest
    deviation of P (percent of the tight run's P there) and of the crown gap. ``same_path`` says
    whether both runs took the same increments (a cut-back in one of them puts increment error into
    the deviation). The increments' own error is read off ``ring_steps``; a test is loose enough
    when its deviation stays well below it."""
    import dataclasses

    from .presets import Ring
    base = Ring().newton_settings()
    rows = []
    for n in steps:
        _, ref = _run("ring", [f"n_steps={n}"], out, f"ring_tol_n{n}_tight",
                      dataclasses.replace(base, rtol=RING_TIGHT))
        for rtol in rtols:
            info, hist = _run("ring", [f"n_steps={n}"], out, f"ring_tol_n{n}_rtol{rtol:g}",
                              dataclasses.replace(base, rtol=rtol))
            same = [round(r["load"], 9) for r in hist] == [round(r["load"], 9) for r in ref]
            rows.append({"n_steps": n, "rtol": rtol, "same_path": int(same),
                         "max_dP_percent": 100 * _deviation(hist, ref, "force", relative=True),
                         "max_dgap": _deviation(hist, ref, "crown_gap"),
                         "split_delta": _split(hist), "split_delta_tight": _split(ref),
                         **_its(info)})
    _write_csv(out / "ring_tolerance.csv", rows)
    if MPI.COMM_WORLD.rank == 0:
        _plot_tolerance(out, rows)
    return rows


def _plot_tolerance(out, rows):
    _plot_panels(out / "ring_tolerance.png", rows, "rtol", [
        dict(x=lambda r: r["n_steps"], y=lambda r: r["newton_mean"], hline=5.0,
             xlabel="nominal increments", ylabel="Newton iterations per increment (mean)",
             title="ring crush"),
        dict(x=lambda r: r["n_steps"], y=lambda r: max(r["max_dP_percent"], 1e-4), yscale="log",
             xlabel="nominal increments", ylabel=f"largest |P - P(rtol {RING_TIGHT:g})| / P [%]")])


def main(argv=None) -> int:
    logging.disable(logging.INFO)
    p = argparse.ArgumentParser(prog="python -m comove_dolfinx.bench", description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("study", choices=["elastica", "contact", "ring", "ring_steps", "ring_newton",
                                     "ring_tolerance", "all"])
    p.add_argument("--out", default="results/bench")
    args = p.parse_args(argv)
    out = pathlib.Path(args.out)
    if MPI.COMM_WORLD.rank == 0:
        out.mkdir(parents=True, exist_ok=True)
    MPI.COMM_WORLD.barrier()
    studies = {"elastica": elastica, "contact": contact, "ring": ring, "ring_steps": ring_steps,
               "ring_newton": ring_newton, "ring_tolerance": ring_tolerance}
    for name in (list(studies) if args.study == "all" else [args.study]):
        rows = studies[name](out)
        if MPI.COMM_WORLD.rank == 0:
            for r in rows:
                print(", ".join(f"{k}={v:.4g}" if isinstance(v, float) else f"{k}={v}"
                                for k, v in r.items()))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

"""The study's numbers and pictures: the reference, the errors, the Pareto front, the claim table.

Everything here works on the rows of runner.run_case (plain dicts), so it can be re-run on a saved
``runs.csv`` without running anything.
"""
from __future__ import annotations

import math
import pathlib

from ..io.csv_tables import read_table, write_table
from .plan import ScenePlan

NAN = float("nan")


def richardson(q: list[float], ratio: float = 2.0) -> tuple[float, float, float]:
    """(extrapolated value, estimated error of the finest, observed order) from three values of a
    sequence refined by ``ratio`` each time (coarse to fine). Where the differences do not shrink
    monotonically (order outside 0.5..6) the finest value is kept and its last change is the error."""
    q1, q2, q3 = q
    d1, d2 = q2 - q1, q3 - q2
    if any(math.isnan(v) for v in q):
        return NAN, NAN, NAN
    if d2 == 0.0:
        return q3, 0.0, NAN
    if d1 * d2 > 0.0 and abs(d1) > abs(d2):
        p = math.log(abs(d1) / abs(d2)) / math.log(ratio)
        if 0.5 <= p <= 6.0:
            ext = q3 + d2 / (ratio ** p - 1.0)
            return ext, abs(ext - q3), p
    return q3, abs(d2), NAN


def reference(plan: ScenePlan, ref_rows: dict[str, dict]) -> dict:
    """The scene's reference value and its estimated error. Closed form where there is one; else
    q(mesh -> 0 at 2 n0) + [q(n -> inf) - q(2 n0)] on the default mesh, both by Richardson, and the
    sum of the two remainders as the error estimate."""
    qh = [ref_rows[f"h{k}"]["q"] for k in range(3)]
    qn = [ref_rows[f"n{k}"]["q"] for k in range(3)]
    h_ext, h_err, h_p = richardson(qh)
    n_ext, n_err, n_p = richardson(qn)
    converged = h_ext + (n_ext - qn[1])
    out = {"mesh_values": qh, "mesh_order": h_p, "increment_values": qn, "increment_order": n_p,
           "converged": converged, "converged_error": h_err + n_err}
    if plan.closed_form is not None:
        out.update(value=plan.closed_form, error=0.0, how="closed form")
    else:
        out.update(value=converged, error=h_err + n_err,
                   how="Richardson in mesh size (at 2x the increments) + in increments")
    return out


def add_errors(rows: list[dict], ref: float) -> None:
    for r in rows:
        r["error_percent"] = 100.0 * abs(r["q"] / ref - 1.0)      # nan where q could not be read


def on_cost_axis(r: dict) -> bool:
    """A run whose CPU time buys its error: completed, with q read. (A run that stopped after the
    ring's delta = 1 has q, but its CPU time is that of a shorter run than the others'.)"""
    return r.get("status", "completed") == "completed" and not math.isnan(r.get("error_percent", NAN))


def pareto(rows: list[dict]) -> list[dict]:
    """The completed runs that no other completed run beats in both CPU time and error."""
    ok = sorted((r for r in rows if on_cost_axis(r)), key=lambda r: (r["cpu_s"], r["error_percent"]))
    front, best = [], math.inf
    for r in ok:
        if r["error_percent"] < best:
            front.append(r)
            best = r["error_percent"]
    return front


def claim_rows(plan: ScenePlan, rows: list[dict]) -> list[dict]:
    """Per stress update, from its increments sweep on the default mesh: the fewest increments and
    the least CPU time that bring q within 1 % and 0.1 % of (a) the reference, (b) the update's own
    limit of many increments (Richardson on its three finest runs: the time-integration error alone)."""
    out = []
    for u in plan.updates:
        sweep = sorted((r for r in rows if r["family"] == f"update {u}"), key=lambda r: r["x"])
        if not sweep:
            continue
        fine = [r["q"] for r in sweep[-3:]]
        limit = richardson(fine)[0] if len(fine) == 3 else NAN
        row = {"scene": plan.name, "update": u, "own_limit": limit}
        for tol in (1.0, 0.1):
            for name, err in (("reference", lambda r: r["error_percent"]),
                              ("own", lambda r: 100.0 * abs(r["q"] / limit - 1.0))):
                hit = [r for r in sweep if r["status"] == "completed" and err(r) <= tol]
                row[f"n_{name}_{tol:g}%"] = min((int(r["x"]) for r in hit), default=None)
                row[f"cpu_{name}_{tol:g}%"] = min((r["cpu_s"] for r in hit), default=None)
        out.append(row)
    return out


def write_csv(path: pathlib.Path, rows: list[dict]) -> None:
    write_table(path, rows)


def chart(plan: ScenePlan, rows: list[dict], ref: dict, path: pathlib.Path) -> None:
    """Error against CPU seconds, a curve per family, the Pareto front; beside it q against the
    increments for each update, with the reference band."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import matplotlib.ticker  # noqa: F401
    import matplotlib.transforms  # noqa: F401
    fig, (ax, bx) = plt.subplots(1, 2, figsize=(14, 5.6), layout="constrained")
    families = list(dict.fromkeys(r["family"] for r in rows))
    cmap = plt.get_cmap("tab20")
    floor = 1e-4
    for i, fam in enumerate(families):
        rs = sorted((r for r in rows if r["family"] == fam), key=lambda r: r["x"])
        ok = [r for r in rs if on_cost_axis(r)]
        style = "o-" if fam.startswith("update") else ("s--" if fam.startswith("mesh") else "^:")
        ax.plot([r["cpu_s"] for r in ok], [max(r["error_percent"], floor) for r in ok], style, ms=4,
                color=cmap(i % 20), label=fam)
        bad = [r for r in rs if not on_cost_axis(r)]                  # along the top edge
        ax.plot([r["cpu_s"] for r in bad], [0.97] * len(bad), "x", color=cmap(i % 20), ms=8, mew=2,
                transform=matplotlib.transforms.blended_transform_factory(ax.transData, ax.transAxes))
    front = pareto(rows)
    ax.step([r["cpu_s"] for r in front], [max(r["error_percent"], floor) for r in front], "k-",
            where="post", lw=2.2, alpha=0.35, label="Pareto front")
    for lvl in (1.0, 0.1):
        ax.axhline(lvl, color="grey", lw=0.7, ls="--")
    ax.set(xscale="log", yscale="log", xlabel="CPU seconds of the whole process (median of repeats)",
           ylabel="|q / q_ref - 1| [%]",
           title=f"{plan.name}: {plan.label}\nreference {ref['value']:.6g}, {ref['how']},\n"
                 f"estimated error {100 * ref['error'] / abs(ref['value']):.2g} %  (x at the top: run failed)")
    fmt = matplotlib.ticker.FuncFormatter(lambda v, _: f"{v:g}")
    ax.xaxis.set_major_formatter(fmt)
    ax.xaxis.set_minor_formatter(fmt)
    ax.tick_params(axis="x", which="minor", labelsize=7)
    ax.legend(fontsize=7, ncol=2, loc="best")
    for i, fam in enumerate(families):
        if not fam.startswith("update"):
            continue
        rs = sorted((r for r in rows if r["family"] == fam and not math.isnan(r["q"])), key=lambda r: r["x"])
        bx.plot([r["x"] for r in rs], [r["q"] for r in rs], "o-", ms=4, color=cmap(i % 20), label=fam)
    v, e = ref["value"], ref["error"]
    bx.axhspan(v - max(e, 1e-12), v + max(e, 1e-12), color="k", alpha=0.15)
    bx.axhline(v, color="k", lw=1, label=f"reference ({ref['how']})")
    bounds = "".join(f"\n{name}: {b:.4g}" for name, b in plan.bounds.items())
    bx.set(xscale="log", xlabel="increments (nominal)", ylabel=plan.label,
           title=f"q against the increments (default mesh){bounds}")
    bx.xaxis.set_major_formatter(fmt)
    bx.legend(fontsize=7)
    fig.savefig(path, dpi=110)
    plt.close(fig)


def read_rows(path: pathlib.Path) -> list[dict]:
    """The rows of a saved runs.csv, numbers as numbers."""
    def num(v):
        try:
            return int(v)
        except ValueError:
            try:
                return float(v)
            except ValueError:
                return v
    return [{k: num(v) for k, v in r.items()} for r in read_table(path)]


def _fmt(v, spec=".3g", unit=""):
    if v is None or (isinstance(v, float) and math.isnan(v)):
        return "-"
    return (format(v, spec) if isinstance(v, float) else str(v)) + unit


def markdown(plan: ScenePlan, rows: list[dict], ref: dict, claims: list[dict]) -> str:
    """A short summary: the reference, the Pareto front, the claim table, the failures."""
    lines = [f"## {plan.name}: {plan.label}", "",
             f"Reference {ref['value']:.6g} ({ref['how']}; estimated error "
             f"{100 * ref['error'] / abs(ref['value']):.2g} %). "
             f"Own converged value {ref['converged']:.6g} (mesh order {_fmt(ref['mesh_order'], '.2f')}, "
             f"increment order {_fmt(ref['increment_order'], '.2f')}, remainder "
             f"{100 * ref['converged_error'] / abs(ref['converged']):.2g} %).", ""]
    for name, b in plan.bounds.items():
        lines.append(f"Bound: {name} = {b:.4g}.")
    lines += ["", "Pareto front (no run is both cheaper and more accurate):", "",
              "| run | CPU s | error % | Newton its | increments |", "|---|---|---|---|---|"]
    for r in pareto(rows):
        lines.append(f"| {r['family']}: {r['settings']} | {r['cpu_s']:.2f} | {r['error_percent']:.3g} | "
                     f"{r['newton_its']} | {r['increments']} |")
    lines += ["", "Fewest increments (and least CPU s) to reach 1 % / 0.1 %: against the reference, and "
              "against the update's own many-increment limit (its time-integration error alone):", "",
              "| update | ref 1 % | ref 0.1 % | own 1 % | own 0.1 % |", "|---|---|---|---|---|"]
    for c in claims:
        cell = [f"{_fmt(c[f'n_{k}'])}" + (f" ({c[f'cpu_{k}']:.2f} s)" if c[f"cpu_{k}"] is not None else "")
                for k in ("reference_1%", "reference_0.1%", "own_1%", "own_0.1%")]
        lines.append(f"| {c['update']} | " + " | ".join(cell) + " |")
    failed = [r for r in rows if r["status"] != "completed"]
    if failed:
        lines += ["", "Runs that did not complete:", ""]
        lines += [f"- {r['family']}: {r['settings']}: {r['message']}" for r in failed]
    return "\n".join(lines) + "\n"

"""What the map writes: the CSV files, the heat maps and the summary stability.md."""
from __future__ import annotations

import dataclasses
import math
import pathlib

from ..io.csv_tables import read_table, write_table
from .causes import SHORT


@dataclasses.dataclass
class Panel:
    """One heat map: rows (label, --set list), columns (label, --set list), what the columns vary."""

    title: str
    rows: list
    columns: list
    column_name: str


FIELDS = ["scene", "panel", "method", "column", "sets", "n_increments", "gamma0", "max_cutbacks", "status",
          "cutbacks", "load_reached", "load_max", "cause", "newton_its", "failed_its", "increments",
          "cpu_s", "wall_s", "result", "max_penetration", "penetration_per_h", "chatter_solves",
          "set_changes_last_fail", "peak_gamma",
          "max_omega2", "message", "press_its", "slide_its"]
RESULT_LABEL = {"elastica": "tip v", "beam": "tip v", "plate": "w0", "ring": "P", "friction": "Q/μP"}
SCENES = ("elastica", "beam", "plate", "ring", "shear", "friction")


def write_csv(path: pathlib.Path, rows: list[dict]) -> None:
    """The map's columns (FIELDS), numbers to 6 significant digits."""
    write_table(path, [{k: (f"{v:.6g}" if isinstance(v, float) else v) for k, v in r.items()} for r in rows],
                FIELDS)


read_csv = read_table


def _f(x) -> float:
    try:
        return float(x)
    except (TypeError, ValueError):
        return float("nan")


# --------------------------------------------------------------------------------------------------
# Heat maps
# --------------------------------------------------------------------------------------------------
COLOURS = {"converged": "#4caf50", "cutbacks": "#ffc107", "failed": "#e53935", "": "#bdbdbd"}


def _cell_text(r: dict) -> str:
    cut = int(float(r["cutbacks"] or 0))
    if r["status"] == "failed":
        cause = str(r["cause"])
        if cause.startswith("non-monotone"):
            return (f"oscillates:\ns12 peaks at\nγ = {_f(r.get('peak_gamma')):.3g}" +
                    (f"\n({cut} cut)" if cut else ""))
        return f"{SHORT.get(cause, cause)}\nat {float(r['load_reached']):.3g}/{float(r['load_max']):.3g}"
    its = int(float(r["newton_its"] or 0))
    text = (f"ok, {its} its" if r["status"] == "converged" else f"{cut} cut, {its} its")
    press, slide = _f(r.get("press_its")), _f(r.get("slide_its"))
    if math.isfinite(press):                      # the friction case: per increment, by phase
        text += f"\npress {press:.1f}, slide {slide:.1f}"
    pen = _f(r.get("penetration_per_h"))
    if math.isfinite(pen):
        text += f"\npen {pen:.2g} h"
    label = RESULT_LABEL.get(r.get("scene", ""))
    if label and math.isfinite(_f(r.get("result"))):
        text += f"\n{label} {_f(r['result']):.4g}"
    return text


def heatmap(path: pathlib.Path, rows: list[dict], panel_list: list[Panel]) -> None:
    """One panel per Panel: rows methods, columns its values, coloured by status, text inside."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.patches import Patch, Rectangle
    heights = [len(p.rows) + 1.6 for p in panel_list]
    width = max(len(p.columns) for p in panel_list)
    fig, axes = plt.subplots(len(panel_list), 1, figsize=(2.2 + 1.45 * width, 0.62 * sum(heights) + 0.8),
                             gridspec_kw={"height_ratios": heights}, squeeze=False)
    for k, (ax, p) in enumerate(zip(axes[:, 0], panel_list)):
        cells = {(r["method"], r["column"]): r for r in rows if int(r["panel"]) == k}
        for i, (label, _) in enumerate(p.rows):
            for j, (col, _) in enumerate(p.columns):
                r = cells.get((label, col))
                status = r["status"] if r else ""
                ax.add_patch(Rectangle((j, i), 1, 1, facecolor=COLOURS[status], edgecolor="white", lw=2))
                ax.text(j + 0.5, i + 0.5, _cell_text(r) if r else "not run", ha="center", va="center",
                        fontsize=8.5)
        ax.set_xlim(0, len(p.columns))
        ax.set_ylim(len(p.rows), 0)
        ax.set_xticks([j + 0.5 for j in range(len(p.columns))], [c for c, _ in p.columns])
        ax.set_yticks([i + 0.5 for i in range(len(p.rows))], [lab for lab, _ in p.rows])
        ax.set_xlabel(p.column_name)
        ax.set_title(p.title, fontsize=9.5)
        ax.tick_params(length=0)
        for s in ax.spines.values():
            s.set_visible(False)
    handles = [Patch(color=COLOURS[s], label=lab) for s, lab in
               (("converged", "converged"), ("cutbacks", "converged with cut-backs"), ("failed", "failed"))]
    fig.legend(handles=handles, loc="lower center", ncol=3, fontsize=8, frameon=False)
    fig.tight_layout(rect=(0, 0.04, 1, 1))
    fig.savefig(path, dpi=130)
    plt.close(fig)


def replot(out: pathlib.Path, panels_of) -> None:
    """The heat maps again from the CSV files in ``out`` (no runs); ``panels_of(scene)``: its panels."""
    for scene in SCENES:
        path = out / f"{scene}.csv"
        if path.exists():
            heatmap(out / f"{scene}.png", read_csv(path), panels_of(scene))


# --------------------------------------------------------------------------------------------------
# The summary
# --------------------------------------------------------------------------------------------------
def summary(out: pathlib.Path, panels_of) -> str:
    """stability.md from every scene CSV in ``out``: per row of each grid (``panels_of(scene)``), where
    it fails or needs cut-backs, and the specific breaking points."""
    lines = ["# Stability map", "",
             "Generated by `python -m comove_dolfinx.stability` from the CSV files in this folder "
             "(docs/stability.md explains the cases). Load levels are the scene's `load` column "
             "(elastica lam, beam q, plate p, ring delta, shear gamma).", ""]
    for scene in SCENES:
        path = out / f"{scene}.csv"
        if not path.exists():
            continue
        rows = read_csv(path)
        lines += [f"## {scene}", "", f"Heat map: `{scene}.png`; runs: `{scene}.csv`.", ""]
        for k, panel in enumerate(panels_of(scene)):
            lines += [f"### {panel.title}", ""]
            what = panel.column_name
            for method, _ in panel.rows:
                rs = [r for r in rows if int(r["panel"]) == k and r["method"] == method]
                if not rs:
                    continue
                fails = [f"{what} {r['column']}: {r['cause']}" +
                         ("" if scene == "shear" else
                          f" at load {_f(r['load_reached']):.4g} of {_f(r['load_max']):.4g}")
                         for r in rs if r["status"] == "failed"]
                cuts = [f"{r['column']} ({r['cutbacks']})" for r in rs if r["status"] == "cutbacks"]
                text = f"- **{method}**: "
                text += ("fails at " + "; ".join(fails)) if fails else "no failure"
                if cuts:
                    text += f". Cut-backs (count) at {what} " + ", ".join(cuts)
                pens = [(r["column"], _f(r["penetration_per_h"])) for r in rs
                        if r["status"] != "failed" and math.isfinite(_f(r["penetration_per_h"]))]
                if pens and what == "gamma0":
                    text += ". Largest penetration / h: " + ", ".join(f"{c}: {p:.3g}" for c, p in pens)
                lines.append(text + ".")
            lines.append("")
        lines.append("")
        lines += _specific(scene, rows)
    text = "\n".join(lines) + "\n"
    (out / "stability.md").write_text(text)
    return text


def _specific(scene: str, rows: list[dict]) -> list[str]:
    out = []
    if scene == "ring":
        ref = {(r["method"].split()[1], r["column"]): _f(r["result"]) for r in rows
               if r["method"].startswith("j2 ") and r["status"] != "failed"}
        devs = []
        for r in rows:
            key = (r["method"].split()[-1], r["column"])
            if r["method"].startswith("chen ") and key in ref and r["status"] != "failed":
                devs.append(f"{r['method']}, n_increments {r['column']}: P(6.6) = {_f(r['result']):.5g} "
                            f"({100 * (_f(r['result']) / ref[key] - 1):+.3f} % against j2 {key[0]}; "
                            f"{r['cutbacks']} cut-backs)")
        if devs:
            out += ["Chen's law against J2 (same update, same increments; P = force at the end of the "
                    "crush):", ""] + [f"- {d}" for d in devs] + [""]
    if scene == "friction":
        out += ["Newton iterations per pressing and per sliding increment of every run, and Q / (mu P) at "
                "the end, are in `friction_detail.csv`.", ""]
    if scene == "shear":
        out += ["Peak of the shear stress (where it first falls) and the distance from the closed form "
                "up to gamma = 3 are in `shear_detail.csv`; the curves at dgamma = 0.1 in "
                "`shear_curves.png`.", ""]
    return out

"""One study of speed against accuracy across methods, per scene (docs/study.md).

    comove study ring --out results/study          # or: elastica, beam, plate, all
    make study                                       # all four scenes

Per scene it writes ``runs.csv`` (every run: method, settings, status, q, error, Newton iterations,
CPU seconds), ``reference.json``, ``pareto.png`` (error against CPU seconds, a curve per method, the
Pareto front; q against the increments) and ``summary.md``; over the scenes ``claim.csv`` and
``study.md``: for each stress update the fewest increments and the least CPU to reach 1 % and 0.1 %.

The runs go through a ``concurrent.futures`` executor (executors.py): local processes, or the workers
of an MPI pool when started as ``mpiexec -n N python -m mpi4py.futures -m comove_dolfinx.study ...``.
"""
from __future__ import annotations

import json
import pathlib
import time

from .plan import PLANS

__all__ = ["PLANS", "study"]


def study(scene: str, out: pathlib.Path, repeat: int = 3, jobs: int = 2, quick: bool = False,
          echo=print, pool=None) -> tuple[list[dict], dict, list[dict]]:
    """Run the study of ``scene`` into out/<scene> through the executor ``pool`` (default: ``jobs``
    local processes at a time); (rows, reference, claim rows)."""
    from . import executors, report, runner
    if pool is None:
        with executors.make("local", jobs) as local:
            return study(scene, out, repeat, jobs, quick, echo, local)
    plan = PLANS[scene]
    folder = out / scene
    folder.mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter()

    def say(case, row):
        echo(f"  {scene}: {case.family:22s} {' '.join(case.sets):45s} {row['status']:10s} "
             f"q {row['q']:.6g}  {row['newton_its']:4d} its  {row['cpu_s']:6.2f} s")
    ref_cases = plan.reference_cases()
    ref_rows = dict(zip(ref_cases, runner.run_all(plan, list(ref_cases.values()), folder, 1, jobs, say,
                                                  pool)))
    ref = report.reference(plan, ref_rows)
    (folder / "reference.json").write_text(json.dumps({**ref, "runs": ref_rows}, indent=1, default=str))
    rows = runner.run_all(plan, plan.cases(quick), folder, repeat, jobs, say, pool)
    report.add_errors(rows, ref["value"])
    claims = report.claim_rows(plan, rows)
    report.write_csv(folder / "runs.csv", rows)
    report.chart(plan, rows, ref, folder / "pareto.png")
    (folder / "summary.md").write_text(report.markdown(plan, rows, ref, claims))
    echo(f"{scene}: {len(rows)} runs (+{len(ref_rows)} for the reference) in "
         f"{time.perf_counter() - t0:.0f} s; {folder / 'pareto.png'}, {folder / 'summary.md'}")
    return rows, ref, claims


def replot(scene: str, out: pathlib.Path) -> tuple[list[dict], dict, list[dict]]:
    """Charts, summary and claim rows again from a finished study's runs.csv and reference.json."""
    from . import report
    plan, folder = PLANS[scene], out / scene
    rows = report.read_rows(folder / "runs.csv")
    ref = json.loads((folder / "reference.json").read_text())
    report.add_errors(rows, ref["value"])
    claims = report.claim_rows(plan, rows)
    report.chart(plan, rows, ref, folder / "pareto.png")
    (folder / "summary.md").write_text(report.markdown(plan, rows, ref, claims))
    return rows, ref, claims


def main(scenes: list[str], out: pathlib.Path, repeat: int, jobs: int, quick: bool,
         again: bool = False, executor: str = "local") -> int:
    """The study of ``scenes`` into ``out`` through one executor of kind ``executor`` ("local" or
    "mpi", executors.py) for all of them, or (``again``) its charts and summaries from the saved runs."""
    from . import executors, report
    claims, parts = [], []
    t0 = time.perf_counter()
    pool = None if again else executors.make(executor, jobs)
    try:
        for s in scenes:
            _, _, c = replot(s, out) if again else study(s, out, repeat, jobs, quick, pool=pool)
            claims += c
            parts.append((out / s / "summary.md").read_text())
    finally:
        if pool is not None:
            pool.shutdown()
    if pool is not None:
        print(f"study: {len(scenes)} scene(s) through the {executor} executor "
              f"({executors.workers(executor, jobs)} runs at a time) in {time.perf_counter() - t0:.1f} s wall")
    report.write_csv(out / "claim.csv", claims)
    (out / "study.md").write_text("# Speed against accuracy\n\n" + "\n".join(parts))
    return 0

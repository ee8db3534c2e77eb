"""output: what writing the results costs, as a share of each scene's and demo's run at its defaults.

    python -m comove_dolfinx.benchmarks output --repeats 3 --out DIR

Every case runs in a process of its own, as a user starts it (``comove run SCENE --out ...`` for the
scenes, ``python demos/demo_NAME.py --out ...`` for the demos), once untimed to fill the caches
(mesh, forms) and then ``--repeats`` times, the job's timer on the CPU clock
(``job.TIMING_CLOCK = time.process_time``). Per run: the job's CPU seconds (from its compilation to
its end), the output's (the writers: VTK, history, ``run.json``, checkpoints), and for a demo the
CPU seconds of what it does after its job (its checks and its pictures). The shares are the output's
of the job, and the output and what follows the job of both. ``output.csv`` has the medians and the
spreads (max - min) over the repeats. One rank: the output's share does not depend on the ranks'
count more than the run does.
"""
from __future__ import annotations

import json
import os
import pathlib
import subprocess
import sys
import time

import numpy as np

SCENES = ("elastica", "beam", "plate", "ring")
DEMOS = ("beam", "ironing", "plate", "ring", "seal", "springback", "tube")
ROOT = pathlib.Path(__file__).resolve().parents[2]


def cases(names=None) -> list[str]:
    """The cases, ``scene:NAME`` and ``demo:NAME`` (``names``: a subset of them)."""
    every = [f"scene:{s}" for s in SCENES] + [f"demo:{d}" for d in DEMOS]
    return [c for c in every if names is None or c in names or c.split(":")[1] in names]


def _one(case: str, out: str) -> dict:
    """Run ``case`` in this process with the job's timer on the CPU clock; its figures."""
    import runpy

    from .. import job as jobmod
    jobmod.TIMING_CLOCK = time.process_time
    seen = []
    run = jobmod.Job.run

    def timed(self, *args, **kwargs):
        c0 = time.process_time()
        res = run(self, *args, **kwargs)
        seen.append({"job": time.process_time() - c0, "output": float(res.timing.get("output", 0.0)),
                     "end": time.process_time()})
        return res
    jobmod.Job.run = timed
    kind, name = case.split(":")
    if kind == "scene":
        from ..cli import main
        main(["run", name, "--out", out, "--overwrite", "--no-progress"])
    else:
        sys.argv = [f"demo_{name}.py", "--out", out]
        try:
            runpy.run_path(str(ROOT / "demos" / f"demo_{name}.py"), run_name="__main__")
        except SystemExit as end:          # a demo ends with its checks' exit code
            if end.code:
                raise
    after = time.process_time() - seen[-1]["end"] if seen else 0.0
    return {"job": sum(s["job"] for s in seen), "output": sum(s["output"] for s in seen),
            "after": after if kind == "demo" else 0.0}


def _spawn(case: str, out: pathlib.Path) -> dict:
    """One run of ``case`` in a new process; its figures."""
    env = dict(os.environ, MPLBACKEND="Agg")
    cmd = [sys.executable, "-m", "comove_dolfinx.benchmarks.output_share", case, str(out)]
    done = subprocess.run(cmd, capture_output=True, text=True, env=env, cwd=out.parent)
    lines = [ln for ln in done.stdout.splitlines() if ln.startswith("{")]
    if done.returncode != 0 or not lines:
        raise RuntimeError(f"{case} failed (exit {done.returncode}): {done.stderr.strip()[-400:]}")
    return json.loads(lines[-1])


def output(out: pathlib.Path, repeats: int = 3, names=None) -> list[dict]:
    """Each case once untimed, then ``repeats`` times; a row per case, written to output.csv."""
    from .runs import say, write_csv
    if not (ROOT / "demos").is_dir() and any(c.startswith("demo:") for c in cases(names)):
        raise SystemExit(f"output: the demos are not beside the package ({ROOT / 'demos'}): run it from "
                         "a clone of the repository, or give --scenes with scenes only")
    rows = []
    for case in cases(names):
        folder = out / case.replace(":", "_")
        folder.parent.mkdir(parents=True, exist_ok=True)
        _spawn(case, folder)
        runs = [_spawn(case, folder) for _ in range(repeats)]
        row = {"case": case}
        for key in ("job", "output", "after"):
            v = np.array([r[key] for r in runs])
            row[f"{key}_cpu_s"], row[f"{key}_spread_s"] = float(np.median(v)), float(np.ptp(v))
        share = [r["output"] / r["job"] for r in runs]
        with_after = [(r["output"] + r["after"]) / (r["job"] + r["after"]) for r in runs]
        row["share"], row["share_with_after"] = float(np.median(share)), float(np.median(with_after))
        rows.append(row)
        say(f"output {case}: job {row['job_cpu_s']:.3f} s CPU, output {row['output_cpu_s']:.3f} s "
            f"({100 * row['share']:.1f} %), after the job {row['after_cpu_s']:.3f} s "
            f"(with it {100 * row['share_with_after']:.1f} %)")
        write_csv(out / "output.csv", [row], append=True)
    return rows


if __name__ == "__main__":
    figures = _one(sys.argv[1], sys.argv[2])
    sys.stdout.flush()
    print(json.dumps(figures), flush=True)

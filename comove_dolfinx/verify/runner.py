"""``comove verify``: run the cases, gather their checks into one table, exit 0 only if all hold.

Each case runs as a process of its own (``python -m comove_dolfinx.verify.runner --case NAME``),
which writes its checks to ``out/NAME.json``, its picture to ``out/NAME.png`` and its output to
``out/NAME.log``: a case starts with a clean memory and JIT state, a crash (or a case that runs
out of memory) costs that case only, and the kernel's accounting of the finished child (os.wait4)
gives its whole CPU time, start-up and compilation included. The parent process loads neither
dolfinx nor MPI. The price is each process's start-up, about 0.8 s of CPU: the four contact cases on
their small meshes took 7.4 s of CPU in one process, whose memory grew to 240 MB, and 10.3 s as four
processes of at most 193 MB each (2-core AMD EPYC, shared, 2026-11-28); on the full meshes the whole
suite takes about a minute of CPU, and the start-ups are a few per cent of it.

The table (``out/verify.csv`` and ``out/verify.md``, also printed) has one row per check:
benchmark, source, quantity, reference, result, relative error, tolerance, status (ok, FAIL,
skipped), Newton iterations and CPU seconds of the runs behind the result. A case whose module is
not in the package is skipped with a line saying so; a case that crashes or writes no picture is a
failure.
"""
from __future__ import annotations

import argparse
import json
import math
import os
import pathlib
import subprocess
import sys

from . import CASES, Check, available

COLUMNS = ("benchmark", "source", "quantity", "reference", "result", "error", "tolerance", "status",
           "newton_its", "cpu_s")


def check_args(name: str, out: str) -> tuple[list[str], str | None]:
    """(the cases to run, None) or ([], the one-line message) for ``comove verify NAME --out OUT``;
    makes the output folder."""
    if name != "all" and name not in CASES:
        return [], f"verify {name!r}: no such case; choose one of {', '.join(CASES)}, or all"
    if not out.strip():
        return [], "--out '': give the output folder"
    try:
        pathlib.Path(out).mkdir(parents=True, exist_ok=True)
    except OSError as e:
        return [], f"--out {out}: cannot make the folder ({e.strerror}); choose another place"
    if not os.access(out, os.W_OK):
        return [], f"--out {out}: the folder is not writable; choose another place"
    return (list(CASES) if name == "all" else [name]), None


def _launch(name: str, out: pathlib.Path, small: bool) -> tuple[int, float]:
    """The case in a process of its own; (its exit code, its CPU seconds with its children)."""
    cmd = [sys.executable, "-m", "comove_dolfinx.verify.runner", "--case", name, "--out", str(out)]
    if small:
        cmd.append("--small")
    env = dict(os.environ, OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1", MPLBACKEND="Agg")
    with open(out / f"{name}.log", "w") as log:
        proc = subprocess.Popen(cmd, stdout=log, stderr=subprocess.STDOUT, env=env)
        _, status, usage = os.wait4(proc.pid, 0)
    return os.waitstatus_to_exitcode(status), usage.ru_utime + usage.ru_stime


def _failure(name: str, why: str) -> Check:
    return Check(name, "", f"the case ran: {why}", 1.0, float("nan"), 0.0)


def _gather(name: str, out: pathlib.Path, code: int) -> list[Check]:
    """The checks the case wrote, or one failed row saying why there are none."""
    try:
        rows = json.loads((out / f"{name}.json").read_text())
    except (OSError, ValueError):
        tail = ""
        try:
            lines = [ln for ln in (out / f"{name}.log").read_text().splitlines() if ln.strip()]
            tail = lines[-1] if lines else ""
        except OSError:
            pass
        return [_failure(name, f"exit code {code}, no checks written ({tail or 'no output'}; see {name}.log)")]
    fields = {f for f in Check.__dataclass_fields__}
    checks = [Check(**{k: v for k, v in r.items() if k in fields}) for r in rows]
    if code != 0:
        checks.append(_failure(name, f"exit code {code} (see {name}.log)"))
    if not (out / f"{name}.png").is_file():
        checks.append(_failure(name, f"no picture {name}.png"))
    return checks


def _fmt(value, key: str) -> str:
    if isinstance(value, float):
        if key == "cpu_s":
            return f"{value:.1f}"
        if not math.isfinite(value):
            return "-"
        return f"{value:.3g}" if key in ("error", "tolerance") else f"{value:.6g}"
    return str(value)


def write_table(checks: list[Check], out: pathlib.Path) -> str:
    """out/verify.csv and out/verify.md; returns the Markdown table."""
    from ..io.csv_tables import write_table as write_csv
    rows = [c.row() for c in checks]
    for r, c in zip(rows, checks):
        if c.skipped:
            r["status"] = f"skipped: {c.skipped}"
    write_csv(out / "verify.csv", rows, COLUMNS)
    head = ["benchmark", "source", "quantity", "reference", "result", "error", "tolerance", "status",
            "Newton its", "CPU s"]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for r in rows:
        lines.append("| " + " | ".join(_fmt(r[k], k) for k in COLUMNS) + " |")
    text = "\n".join(lines) + "\n"
    (out / "verify.md").write_text(text)
    return text


def main(names: list[str], out: pathlib.Path, small: bool = False) -> int:
    """Run ``names`` into ``out``; 0 if every check holds, 1 otherwise."""
    checks, cost = [], []
    for name in names:
        if not available(name):
            print(f"verify: {name} skipped: its module comove_dolfinx/verify/{name}.py is not in this version",
                  flush=True)
            continue
        print(f"verify: {name} ...", flush=True)
        for stale in (f"{name}.json", f"{name}.png"):
            (out / stale).unlink(missing_ok=True)
        code, cpu = _launch(name, out, small)
        found = _gather(name, out, code)
        bad = sum(c.status == "FAIL" for c in found)
        print(f"verify: {name}: {len(found) - bad} of {len(found)} checks hold, {cpu:.1f} s CPU", flush=True)
        checks += found
        cost.append((name, cpu))
    if not checks:
        print("verify: no case ran")
        return 1
    print(write_table(checks, out), end="")
    failed = [c for c in checks if c.status == "FAIL"]
    total = sum(c for _, c in cost)
    print(f"verify: {len(checks) - len(failed)} of {len(checks)} checks hold "
          f"({sum(c.status == 'skipped' for c in checks)} skipped), {len(cost)} cases, {total:.1f} s CPU in all; "
          f"tables {out / 'verify.md'}, {out / 'verify.csv'}")
    return 1 if failed else 0


def _plain(value):
    """NumPy scalars as Python numbers for JSON."""
    return value.item() if hasattr(value, "item") else str(value)


def run_case(name: str, out: pathlib.Path, small: bool) -> int:
    """In the case's own process: run it and write out/NAME.json (rank 0)."""
    import importlib
    import logging
    logging.disable(logging.INFO)          # the form compiler's messages
    module = importlib.import_module(f"{__package__}.{name}")
    checks = module.run(out, small=small)
    from mpi4py import MPI
    if MPI.COMM_WORLD.rank == 0:
        (out / f"{name}.json").write_text(json.dumps([c.row() for c in checks], indent=1, default=_plain))
    return 0


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description="run one verification case (comove verify runs this)")
    parser.add_argument("--case", required=True, choices=CASES)
    parser.add_argument("--out", required=True)
    parser.add_argument("--small", action="store_true")
    a = parser.parse_args()
    sys.exit(run_case(a.case, pathlib.Path(a.out), a.small))

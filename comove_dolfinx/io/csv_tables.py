"""Tables as CSV files: a job's history, and the tables of the study, the stability map and the cost
benchmarks. Light (csv and NumPy only): the study's parent process reads its runs without dolfinx."""
from __future__ import annotations

import csv
import pathlib

import numpy as np


def read_history(path, origin: bool = False) -> dict[str, np.ndarray]:
    """A history CSV as columns; with ``origin`` led by the unloaded state (a row of zeros: no load,
    displacement, force or contact), so that curves start where the body did."""
    rows = read_table(path)
    lead = [0.0] if origin else []
    return {k: np.array(lead + [float(r[k]) for r in rows]) for k in (rows[0] if rows else [])}


def write_table(path, rows: list[dict], fieldnames=None, append: bool = False) -> None:
    """``rows`` (dicts) as CSV: the columns ``fieldnames`` (default every key, in the order they
    first appear; other keys are left out); with ``append``, below the rows of an existing file."""
    if not rows and fieldnames is None:
        return
    keys = list(fieldnames) if fieldnames is not None else list(dict.fromkeys(k for r in rows for k in r))
    path = pathlib.Path(path)
    new = not (append and path.exists())
    with open(path, "w" if new else "a", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=keys, extrasaction="ignore")
        if new:
            w.writeheader()
        w.writerows(rows)


def read_table(path) -> list[dict]:
    """A CSV file's rows as dicts of strings."""
    with open(path, newline="") as fh:
        return list(csv.DictReader(fh))

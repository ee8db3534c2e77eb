"""Tables as CSV files: a job's history, and the tables of the study, the stability map and the cost
benchmarks. Light (csv and NumPy only): the study's parent process reads its runs without dolfinx."""
from __future__ import annotations

import csv
import pathlib
import warnings

import numpy as np

#: history columns that were renamed: old name -> new name
RENAMED = {"step": "increment"}


class Columns(dict):
    """A history's columns (or one of its rows) by name; a renamed column's old name
    (:data:`RENAMED`) still reads the column, with a DeprecationWarning."""

    def __missing__(self, key):
        new = RENAMED.get(key) if isinstance(key, str) else None
        if new is None or new not in self:
            raise KeyError(key)
        warnings.warn(f"the history column {key!r} is now called {new!r}", DeprecationWarning, stacklevel=2)
        return self[new]


def current_names(columns) -> dict[str, str]:
    """Each of ``columns`` (a history's header) under today's name: a renamed column's old name
    (:data:`RENAMED`) becomes its new one, unless the header has that name already."""
    columns = list(columns)
    return {c: RENAMED[c] if c in RENAMED and RENAMED[c] not in columns else c for c in columns}


def read_history(path, origin: bool = False) -> Columns:
    """A history CSV as columns; with ``origin`` led by the unloaded state (a row of zeros: no load,
    displacement, force or contact), so that curves start where the body did. A history written
    before a column was renamed is read under the new name (``step`` as ``increment``)."""
    rows = read_table(path)
    lead = [0.0] if origin else []
    names = current_names(rows[0] if rows else [])
    return Columns({new: np.array(lead + [float(r[old]) for r in rows]) for old, new in names.items()})


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

"""The cost benchmark's bookkeeping (comove_dolfinx.cost, docs/performance.md): a one-increment
floor study of the ring writes its table and chart, and its figures are consistent with each other."""
import numpy as np
import pytest

from comove_dolfinx import cost
from comove_dolfinx.tables import read_table


def test_floor_study_writes_a_consistent_table(tmp_path):
    rows = cost.floor(tmp_path, sizes=(0.22,), repeats=1, increments=1)
    (row,) = read_table(tmp_path / "floor.csv")
    assert (tmp_path / "floor.png").stat().st_size > 0
    assert int(row["dofs"]) == rows[0]["dofs"] > 1000 and int(row["iterations"]) >= 1
    # the floor is its three parts, and the ratio (one run) is the iteration over the floor
    parts = sum(float(row[k]) for k in ("floor_matrix_s", "floor_vector_s", "floor_solve_s"))
    assert float(row["floor_cpu_s"]) == pytest.approx(parts, rel=1e-9)
    assert float(row["ratio"]) == pytest.approx(float(row["iteration_cpu_s"]) / parts, rel=1e-9)
    # every iteration evaluates the residual at least once, and the Timer's parts fit in the run
    assert float(row["residuals_per_it"]) >= 1.0
    timed = sum(float(row[f"{k}_s_per_it"]) for k in ("solve", "jacobian", "assembly", "stress_update"))
    assert 0.0 < timed <= float(row["iteration_cpu_s"]) * 1.05 and np.isfinite(float(row["ratio"]))

"""mechanics/ufl_dag.py: merging equal subexpressions keeps the expression's value."""
import numpy as np
import ufl
from dolfinx import fem
from mpi4py import MPI

from comove_dolfinx import compat, geometry
from comove_dolfinx.mechanics.ufl_dag import unique_nodes


def _objects(expr) -> int:
    """Distinct objects of a UFL DAG (a walk by identity)."""
    seen, stack = set(), [expr]
    while stack:
        e = stack.pop()
        if id(e) not in seen:
            seen.add(id(e))
            stack.extend(e.ufl_operands)
    return len(seen)


def _chain(u, n):
    """n steps of a Newton-like recursion that rebuilds its equal subexpressions at every step, as
    the return maps written out in UFL do: each step holds two equal copies of the step before."""
    def step(k):
        if k == 0:
            return u[0] * u[1] + 1.0
        return ufl.sqrt(step(k - 1) * step(k - 1) + 1.0) / (1.0 + 0.5 * step(k - 1))
    return step(n)


def test_unique_nodes_merges_copies_and_keeps_the_value(tmp_path):
    md = geometry.rectangle(1.0, 1.0, 0.5, order=2, comm=MPI.COMM_SELF, cache_dir=str(tmp_path))
    V = compat.function_space(md.mesh, "Lagrange", 2, shape=(2,))
    u = fem.Function(V)
    u.interpolate(lambda x: np.stack([0.3 + x[0] * x[1], 0.2 - 0.1 * x[0]]))
    e = _chain(u, 6)                     # 3^6 copies of the first step built, all equal
    merged = unique_nodes(e)
    # equal subexpressions are one object: a few objects per step instead of thousands
    assert _objects(e) > 1000
    assert _objects(merged) < 100
    # the same value: the integrals of both over the mesh, on a shorter chain (the form compiler
    # expands the unmerged one into a tree)
    short = _chain(u, 2)
    vals = [md.mesh.comm.allreduce(fem.assemble_scalar(compat.form(f * ufl.dx(domain=md.mesh))), op=MPI.SUM)
            for f in (short, unique_nodes(short))]
    assert abs(vals[0] - vals[1]) <= 1e-14 * abs(vals[0]) and abs(vals[0]) > 0.1

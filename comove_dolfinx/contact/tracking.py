"""Whether a result computed from UFL expressions is still current: the values that the expressions
depend on (their functions' arrays and their constants' values), compared with those of the last
computation. The contact's fields and profile are recomputed only when something changed."""
from __future__ import annotations

import numpy as np
import ufl
from mpi4py import MPI


def terminals(exprs) -> tuple[list, list]:
    """(coefficients, constants) that the UFL expressions or forms ``exprs`` depend on, each once; the walk
    marks the nodes it has seen by identity (mechanics/ufl_dag.py says why)."""
    seen, funcs, consts = set(), {}, {}
    stack = [i.integrand() for e in exprs if isinstance(e, ufl.Form) for i in e.integrals()]
    stack += [e for e in exprs if not isinstance(e, ufl.Form)]
    while stack:
        e = stack.pop()
        if id(e) in seen:
            continue
        seen.add(id(e))
        if isinstance(e, ufl.Coefficient):
            funcs[id(e)] = e
        elif isinstance(e, ufl.Constant):
            consts[id(e)] = e
        stack.extend(e.ufl_operands)
    return list(funcs.values()), list(consts.values())


class Dependencies:
    """What the UFL expressions or forms ``exprs`` depend on, but the constants ``ignore`` (found on
    first use); :meth:`stale` tells whether any of it changed since :meth:`mark`."""

    def __init__(self, comm, exprs, ignore=()):
        self.comm, self._exprs, self._ignore = comm, list(exprs), list(ignore)
        self._terminals = None
        self._key = self._marked = None

    def stale(self) -> bool:
        """Whether anything changed since the last :meth:`mark` (or there was none), on any rank.
        Collective."""
        if self._terminals is None:
            funcs, consts = terminals(self._exprs)
            self._terminals = (funcs, [c for c in consts if all(c is not i for i in self._ignore)])
        funcs, consts = self._terminals
        self._key = tuple(hash(f.x.array.tobytes()) for f in funcs) + \
            tuple(np.asarray(c.value).tobytes() for c in consts)
        return bool(self.comm.allreduce(self._key != self._marked, op=MPI.LOR))

    def mark(self) -> None:
        """The result is now current: computed from the values :meth:`stale` last saw."""
        self._marked = self._key

"""UFL expressions as DAGs whose equal subexpressions are one object.

UFL 2022.2 finds an expression's terminals (its domain, its coefficients) with a walk that marks
the nodes it has seen in a set, so that a node equal to one seen but not the same object is compared
by value, subtree against subtree. The return maps written out step by step in UFL (the saturation
law's Newton steps in Nitsche's facet stress, mechanics/return_maps_ufl.py) rebuild equal
subexpressions many times over, and that walk then takes minutes where the expression has a few
thousand nodes (``dolfinx.fem.Expression`` starts with it). :func:`unique_nodes` rebuilds the
expression once, in time linear in its number of distinct objects, so that equal subexpressions
are identical and every later walk is linear too.
"""
from __future__ import annotations

from ufl.core.terminal import Terminal


def unique_nodes(expr):
    """The UFL expression ``expr`` with structurally equal subexpressions merged into one object
    (the same expression: the value and the derivatives do not change)."""
    memo: dict[int, object] = {}           # id of a node of expr -> its merged node
    table: dict[tuple, object] = {}        # (type, identities of merged operands) -> merged node
    stack = [(expr, False)]
    while stack:                           # post-order, each object of expr visited once
        e, ready = stack.pop()
        if id(e) in memo:
            continue
        if not ready:
            stack.append((e, True))
            stack.extend((o, False) for o in e.ufl_operands if id(o) not in memo)
            continue
        ops = tuple(memo[id(o)] for o in e.ufl_operands)
        key = (type(e), repr(e)) if isinstance(e, Terminal) else (type(e),) + tuple(id(o) for o in ops)
        if key not in table:
            same = all(a is b for a, b in zip(ops, e.ufl_operands))
            table[key] = e if same else e._ufl_expr_reconstruct_(*ops)
        memo[id(e)] = table[key]
    return memo[id(expr)]

"""States the Taylor tests start from: a model run through its first increments, then one Newton
correction into the next (a deformed state away from equilibrium, where every term is active)."""
from comove_dolfinx.solver import IncrementalSolver, StepSettings


def one_correction_into(m, t_converged: float = 0.4, t_next: float = 0.6, increments: int = 2):
    """Run the finalized model ``m`` to ``t_converged`` in ``increments`` increments, set the load
    of ``t_next`` and take one Newton correction from there; the solver."""
    solver = IncrementalSolver(m, StepSettings(n_increments=increments, t_end=t_converged))
    res = solver.run()
    assert res.completed, res.message
    m.set_load(t_next)
    newton = solver.newton
    newton.residual()
    m.assemble_jacobian(newton.A)
    assert newton._solve_linear() is None
    m.u.x.array[:] += m.du.x.array
    m.evaluate_stress()
    return solver


def pressed_block(cache, obstacle, **contact):
    """A block (1 x 0.5 x 0.5, P2, elastic) with a follower pressure and a dead traction, pressed onto
    ``obstacle`` by its top face, which moves down and sideways in x and y (the contact on its bottom
    face, gamma0 = 10, with the keywords ``contact``): two converged increments, then one Newton
    correction into the next, in contact; (model, contact)."""
    import comove_dolfinx as cm
    from comove_dolfinx.contact import Contact
    from comove_dolfinx.loads import Displacement, Pressure, Traction
    from comove_dolfinx.mechanics.body import Body
    from comove_dolfinx.mechanics.model import Model
    md = cm.box(1.0, 0.5, 0.5, 0.25, cache_dir=cache)
    c = Contact("bottom", obstacle, gamma0=10.0, **contact)
    items = [Displacement("top", (0.06, 0.03, -0.06)), Pressure("right", 5.0), Traction("left", (2.0, -1.0, 0.5)), c]
    m = Model(Body(md, "solid", cm.Elastic(1000.0, 0.3)), items)
    m.finalize()
    one_correction_into(m)
    assert c.zone().in_contact
    return m, c

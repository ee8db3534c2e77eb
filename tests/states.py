"""States the Taylor tests start from: a model run through its first increments, then one Newton
correction into the next (a deformed state away from equilibrium, where every term is active)."""
from comove_dolfinx import compat
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
    compat.assemble_matrix(newton.A, m.jacobian_form, m.bcs)
    assert newton._solve_linear() is None
    m.u.x.array[:] += m.du.x.array
    m.evaluate_stress()
    return solver

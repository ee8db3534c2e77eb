"""The benchmark against plain dolfinx (comove_dolfinx.benchmarks.plain_dolfinx, iteration_dolfinx;
docs/performance.md): the neo-Hookean problem that dolfinx's own Newton solver solves is a consistent
one (Newton converges quadratically on it), it tends to linear elasticity with the ring's constants
for a small push (the difference shrinking in proportion to the push), and the study writes its table
and its pairs on the ring's own mesh."""
import json

import numpy as np
import pytest

from comove_dolfinx import benchmarks, compat   # first: the PyPI wheel's bootstrap comes with it
from comove_dolfinx.benchmarks.plain_dolfinx import PlainNeoHooke, lame
from comove_dolfinx.io.csv_tables import read_table


@pytest.fixture(scope="module")
def ring():
    """(scene, model) of the ring at its default mesh (1386 dofs)."""
    return benchmarks.build("ring", 0.22)


def test_newton_converges_quadratically_on_the_neo_hookean_press(ring):
    """From rest to a push of 0.2 (a fifth of the wall): once the supports hold (first iteration),
    each residual, relative to that first one, is at most ten times the square of the last down to
    1e-14, and the ratio of two successive residuals falls at each step: the Jacobian is the
    derivative of the residual. A tangent off by a constant factor would fall by a fixed ratio
    (linearly)."""
    scene, model = ring
    norms = []
    problem = PlainNeoHooke(model, scene.R_out, monitor=norms.append)
    result = problem.run([0.2])
    assert result["converged"] and result["iterations"] >= 3
    r = np.array(norms[1:]) / norms[1]
    r = r[r > 1e-14]
    assert r.size >= 3, r
    assert np.all(r[1:] <= 10 * r[:-1] ** 2), r
    ratios = r[1:] / r[:-1]
    assert np.all(ratios[1:] < ratios[:-1]), r


def _linear_elastic(model, bcs):
    """The solution of linear elasticity (the ring's lambda, mu) with the Dirichlet conditions bcs."""
    import ufl
    from dolfinx import fem
    from petsc4py import PETSc
    V = model.V
    u, v = ufl.TrialFunction(V), ufl.TestFunction(V)
    lam, mu = lame(model.elastic.E, model.elastic.nu)

    def sigma(w):
        eps = ufl.sym(ufl.grad(w))
        return lam * ufl.tr(eps) * ufl.Identity(2) + 2 * mu * eps
    a = compat.form(ufl.inner(sigma(u), ufl.sym(ufl.grad(v))) * model.rule.dx)
    A = compat.create_matrix(a)
    compat.assemble_matrix(A, a, bcs)
    x = fem.Function(V)
    b = compat.petsc_vec(x).duplicate()                # no load but the supports' displacements
    compat.assemble_vector(b, None, a, bcs, compat.petsc_vec(x), alpha=1.0)
    ksp = PETSc.KSP().create(model.comm)
    ksp.setOperators(A)
    ksp.setType("preonly")
    ksp.getPC().setType("lu")
    ksp.getPC().setFactorSolverType("mumps")
    ksp.solve(b, compat.petsc_vec(x))
    return x.x.array.copy()


def test_a_small_push_gives_linear_elasticity(ring):
    """For a push of 1e-5 and 1e-4 the neo-Hookean displacement is the linear-elastic one with the
    same Lame constants and supports, up to the strains' square: the relative difference is small
    and grows tenfold with the push."""
    scene, model = ring
    problem = PlainNeoHooke(model, scene.R_out)
    diffs = []
    for push in (1e-5, 1e-4):
        assert problem.run([push])["converged"]
        u = problem.u.x.array.copy()
        lin = _linear_elastic(model, problem.bcs)
        diffs.append(np.linalg.norm(u - lin) / np.linalg.norm(lin))
    assert diffs[1] < 1e-3
    assert 5.0 < diffs[1] / diffs[0] < 20.0, diffs


def test_dolfinx_study_writes_its_table_and_pairs(tmp_path):
    """One size, two pairs: the table's row and the pairs' file, the two problems on one mesh (the
    same dofs), each iteration's time positive, the ratio the median of the pairs' ratios."""
    rows = benchmarks.against_dolfinx(tmp_path, sizes=(0.22,), repeats=2, increments=1)
    (row,) = read_table(tmp_path / "dolfinx.csv")
    assert int(row["dofs"]) == rows[0]["dofs"] > 1000
    assert int(row["ring_iterations"]) >= 1 and int(row["plain_iterations"]) >= 1
    pairs = json.loads((tmp_path / "dolfinx_pairs.json").read_text())["pairs"]["0.22"]
    assert len(pairs) == 2 and all(p["ring_s"] > 0 and p["plain_s"] > 0 for p in pairs)
    ratios = [p["ring_s"] / p["plain_s"] for p in pairs]
    assert float(row["ratio"]) == pytest.approx(np.median(ratios))
    assert float(row["ratio_spread"]) == pytest.approx(max(ratios) - min(ratios))


def test_the_dolfinx_study_refuses_a_bad_scene_parameter(capsys):
    """A scene parameter the ring does not know is a one-line usage error before any run."""
    with pytest.raises(SystemExit):
        benchmarks.main(["dolfinx", "--set", "wall=-1", "--sizes", "0.22"])
    err = capsys.readouterr().err.strip().splitlines()
    assert "wall" in err[-1]

"""Every dolfinx, basix and ufl call whose API differs between the supported versions.

comove_dolfinx runs on three API levels, chosen at import time from ``dolfinx.__version__``:

* 0.5  (Debian 12's python3-dolfinx-real 0.5.2): ufl elements, ``VectorFunctionSpace``, ``u.vector``,
  ``jit_params``, ``Expression.eval(cells)``, ``scale=`` in the lifting;
* 0.9  (Debian 13's python3-dolfinx-real 0.9.0): basix.ufl elements and ``fem.functionspace``,
  ``x.petsc_vec``, ``jit_options``, ``Expression.eval(mesh, cells)``, ``alpha=``, 2-D dofmap arrays;
* 0.11 (the current release; the PyPI wheel dolfinx-solver-real): as 0.9, and ``dolfinx.io.gmsh``
  whose ``model_to_mesh`` returns a named tuple; ``create_mesh(comm, cells, element, x)``.

Nothing else in the package touches these APIs or a private attribute. The differences were found by
running the test suite on each level (facts listed per function).
"""
from __future__ import annotations

import basix
import dolfinx
import numpy as np
import ufl
from dolfinx import fem
from dolfinx.fem import petsc as fem_petsc
from petsc4py import PETSc

SUPPORTED = ("0.5", "0.9", "0.11")
VERSION = tuple(int(v) for v in dolfinx.__version__.split(".")[:2])
LEVEL = f"{VERSION[0]}.{VERSION[1]}"
_OLD = VERSION < (0, 9)

ScalarType = PETSc.ScalarType

_CELLS = {name: getattr(basix.CellType, name) for name in ("triangle", "quadrilateral", "tetrahedron",
                                                             "hexahedron")}


def check_version() -> None:
    """SystemExit naming the tested API levels unless the installed dolfinx is one of them."""
    if LEVEL not in SUPPORTED:
        raise SystemExit(f"comove_dolfinx is tested with dolfinx {', '.join(SUPPORTED)} (Debian 12, "
                         f"Debian 13, the current PyPI release); found {dolfinx.__version__}. "
                         "Install one of these (see docs/install.md).")


# ------------------------------------------------------------------------------------------------
# Spaces and elements
# ------------------------------------------------------------------------------------------------
def cell_name(mesh) -> str:
    """'triangle', 'quadrilateral', 'tetrahedron', 'hexahedron' (ufl.Cell's method to ufl 2025, then property)."""
    name = mesh.ufl_cell().cellname
    return name() if callable(name) else name


def function_space(mesh, family: str, degree: int, shape: tuple = ()):
    """A Lagrange ("Lagrange") or discontinuous Lagrange ("DG") space of scalars, vectors (n,) or
    tensors (n, m). Degree <= 2, where the Lagrange variants of the versions share their points."""
    if family not in ("Lagrange", "DG"):
        raise ValueError(f"family {family!r}: Lagrange or DG")
    shape = tuple(shape)
    if _OLD:
        fam = "CG" if family == "Lagrange" else ("DG" if mesh.ufl_cell().is_simplex() else "DQ")
        if shape == ():
            return fem.FunctionSpace(mesh, (fam, degree))
        if len(shape) == 1 and shape[0] == mesh.geometry.dim:
            return fem.VectorFunctionSpace(mesh, (fam, degree))
        cell = mesh.ufl_cell()
        if len(shape) == 1:
            return fem.FunctionSpace(mesh, ufl.VectorElement(fam, cell, degree, dim=shape[0]))
        return fem.TensorFunctionSpace(mesh, (fam, degree), shape=shape)
    return fem.functionspace(mesh, (family, degree, shape) if shape else (family, degree))


def quadrature_space(mesh, degree: int, shape: tuple = ()):
    """Space of values at the points of the default quadrature rule of ``degree`` (scalars, vectors
    (n,) or tensors (n, m)); its dofmap is the identity, cell by cell, then point, then component."""
    shape = tuple(shape)
    cell = mesh.ufl_cell()
    if _OLD:
        if shape == ():
            el = ufl.FiniteElement("Quadrature", cell, degree, quad_scheme="default")
        elif len(shape) == 1:
            el = ufl.VectorElement("Quadrature", cell, degree, dim=shape[0], quad_scheme="default")
        else:
            el = ufl.TensorElement("Quadrature", cell, degree, shape=shape, quad_scheme="default")
        return fem.FunctionSpace(mesh, el)
    import basix.ufl
    el = basix.ufl.quadrature_element(cell_name(mesh), value_shape=shape, scheme="default",
                                      degree=degree)
    return fem.functionspace(mesh, el)


def element_degree(V) -> int:
    """Polynomial degree of a (possibly blocked) Lagrange space."""
    el = V.ufl_element()
    if _OLD:
        sub = el.sub_elements()[0] if el.num_sub_elements() else el
        return sub.degree()
    return el.embedded_superdegree


def cell_dofs(V, num_cells: int) -> np.ndarray:
    """Dofs (block numbers) of the first ``num_cells`` cells, shape (num_cells, dofs per cell)."""
    dl = V.dofmap.list
    arr = dl.array.reshape(-1, V.dofmap.dof_layout.num_dofs) if _OLD else np.asarray(dl)
    return arr[:num_cells]


def geometry_dofs(mesh) -> np.ndarray:
    """Geometry nodes of every local cell, shape (cells, nodes per cell)."""
    geo = mesh.geometry
    if _OLD:
        return geo.dofmap.array.reshape(geo.dofmap.num_nodes, -1)
    return np.asarray(geo.dofmaps[0] if VERSION >= (0, 10) else geo.dofmap)


def lagrange_tabulate(cell: str, degree: int, points: np.ndarray) -> np.ndarray:
    """Values (points, dofs) of the discontinuous Lagrange basis on the reference cell (equispaced
    points, which all versions use up to degree 2)."""
    ct, fam, var = _CELLS[cell], basix.ElementFamily.P, basix.LagrangeVariant.equispaced
    if _OLD:
        el = basix.create_element(fam, ct, degree, var, True)
    else:
        el = basix.create_element(fam, ct, degree, var, discontinuous=True)
    return el.tabulate(0, points)[0, :, :, 0]


def fix_coordinate_element(mesh) -> None:
    """dolfinx 0.5 / ffcx 0.5 only: give the mesh's coordinate element the variant "equispaced"
    before the first compilation (ffcx sets it in place at the first compilation, which changes the
    cache keys of the forms compiled later in the process). Not needed from 0.9 on."""
    if not _OLD:
        return
    domain = mesh.ufl_domain()
    element = domain.ufl_coordinate_element()
    if element._sub_element._variant is None:
        scalar = ufl.FiniteElement(element.family(), element.cell(), element.degree(),
                                   element.quadrature_scheme(), variant="equispaced")
        domain._ufl_coordinate_element = ufl.VectorElement(scalar)


def cell_sizes(mesh, cells: np.ndarray) -> np.ndarray:
    """Cell diameters (circumdiameter of triangles) of the given local cells."""
    tdim = mesh.topology.dim
    if _OLD:
        return dolfinx.cpp.mesh.h(mesh._mesh, tdim, cells)
    return mesh.h(tdim, cells)


def geometry_degree(mesh) -> int:
    """Degree of the coordinate element (one per mesh; 0.10 lists them as cmaps)."""
    geo = mesh.geometry
    return (geo.cmaps[0] if VERSION >= (0, 10) else geo.cmap).degree


# ------------------------------------------------------------------------------------------------
# Forms, expressions, PETSc objects
# ------------------------------------------------------------------------------------------------
def form(expr, jit_options: dict | None = None):
    if _OLD:
        return fem.form(expr, jit_params=jit_options or {})
    return fem.form(expr, jit_options=jit_options or {})


def expression(expr, points: np.ndarray):
    return fem.Expression(expr, points)


def evaluate(expr, mesh, cells: np.ndarray) -> np.ndarray:
    """Values of a compiled expression at its points in the given cells, (cells, points * size)."""
    vals = expr.eval(cells) if _OLD else expr.eval(mesh, cells)
    return np.asarray(vals).reshape(len(cells), -1)


def petsc_vec(f) -> PETSc.Vec:
    """The PETSc vector sharing the memory of a Function's dofs."""
    return f.vector if _OLD else f.x.petsc_vec


def create_matrix(a, kind: str | None = None) -> PETSc.Mat:
    """A PETSc matrix for the bilinear form ``a``: dolfinx's default (AIJ), or of the PETSc type
    ``kind`` ("baij"); the type is the second argument on every level (``mat_type`` up to 0.9,
    ``kind`` from 0.10)."""
    if kind is None:
        return fem_petsc.create_matrix(a)
    return fem_petsc.create_matrix(a, kind)


def create_vector(L) -> PETSc.Vec:
    if VERSION >= (0, 10):
        return fem_petsc.create_vector(L.function_spaces[0])
    return fem_petsc.create_vector(L)


def assemble_vector(b: PETSc.Vec, L, a=None, bcs=(), x: PETSc.Vec | None = None,
                    alpha: float = -1.0, add=None, lift: bool = True,
                    plus: PETSc.Vec | None = None) -> None:
    """Zero b and assemble the linear form L; with a bilinear form ``a``, lift the Dirichlet values
    of ``bcs`` relative to x and set the constraint rows to alpha (g - x), as Newton needs. Ghost
    contributions are summed once, after the lifting, so the owned entries are complete. ``add``:
    (owned dofs, values) added to b before the constraint rows are set (nodal forces). ``lift``
    False skips the lifting, which adds exactly nothing when x meets the constraints (g - x = 0,
    see :func:`constraint_gap`) and costs a pass of a's kernel and the packing of its coefficients.
    ``plus``: an assembled vector of b's layout (its ghost contributions summed) added to b's owned
    entries before the constraint rows are set; L may then be None (nothing more to assemble)."""
    with b.localForm() as loc:
        loc.set(0.0)
    if L is not None:
        fem_petsc.assemble_vector(b, L)
    if a is not None and lift:
        if _OLD:
            fem_petsc.apply_lifting(b, [a], bcs=[list(bcs)], x0=[x], scale=alpha)
        else:
            fem_petsc.apply_lifting(b, [a], bcs=[list(bcs)], x0=[x], alpha=alpha)
    b.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
    if plus is not None:
        b.axpy(1.0, plus)
    if add is not None:
        with b.localForm() as loc:
            np.add.at(loc.array, add[0], add[1])       # (a dof may appear in two items)
    if a is None:
        return
    _set_bc(b, bcs, x, alpha)


def _set_bc(b: PETSc.Vec, bcs, x: PETSc.Vec, alpha: float) -> None:
    """The owned constraint rows of b set to alpha (g - x)."""
    if _OLD:
        fem_petsc.set_bc(b, list(bcs), x, alpha)
    elif VERSION >= (0, 10):
        for bc in bcs:
            bc.set(b.array_w, x.array_r, alpha)
    else:
        fem_petsc.set_bc(b, list(bcs), x, alpha)


def constraint_gap(work: PETSc.Vec, bcs, x: PETSc.Vec) -> float:
    """``max |g - x|`` over the Dirichlet dofs of ``bcs`` on every rank (collective); ``work``, a vector
    of x's layout, is overwritten."""
    with work.localForm() as loc:
        loc.set(0.0)
    _set_bc(work, bcs, x, 1.0)
    return work.norm(PETSc.NormType.NORM_INFINITY)


def constrained(work: PETSc.Vec, bcs) -> np.ndarray:
    """Whether each owned entry of ``work``'s layout is a dof of one of ``bcs`` (work overwritten):
    the constraint rows set twice, against x = 1 and x = 2, differ by 1 there, whatever g is."""
    x, rows = work.duplicate(), []
    for value in (1.0, 2.0):
        x.set(value)
        work.set(0.0)
        _set_bc(work, bcs, x, 1.0)
        rows.append(work.array.copy())
    x.destroy()
    return rows[0] - rows[1] > 0.5


def assemble_matrix(A: PETSc.Mat, a, bcs=()) -> None:
    """Zero A and assemble the bilinear form with the Dirichlet rows and columns of ``bcs``."""
    A.zeroEntries()
    fem_petsc.assemble_matrix(A, a, bcs=list(bcs))
    A.assemble()


# ------------------------------------------------------------------------------------------------
# Meshes from Gmsh
# ------------------------------------------------------------------------------------------------
def model_to_mesh(model, comm, rank: int, gdim: int = 2):
    """(mesh, cell tags, facet tags) of the gmsh model held by ``rank``."""
    if VERSION >= (0, 10):
        from dolfinx.io import gmsh as gmsh_io
        data = gmsh_io.model_to_mesh(model, comm, rank, gdim=gdim)
        return data.mesh, data.cell_tags, data.facet_tags
    from dolfinx.io import gmshio
    return gmshio.model_to_mesh(model, comm, rank, gdim=gdim)


# -- dolfinx's own Newton solver (the benchmarks' reference: what a user writes without this package)
def plain_newton(F, u, bcs, J, petsc_options: dict, rtol: float, prefix: str = "plain_",
                 monitor=None):
    """A solve function for ``F(u; v) = 0`` by dolfinx's own Newton solver as its demos set it up:
    up to 0.9 ``fem.petsc.NonlinearProblem`` with ``nls.petsc.NewtonSolver`` (the "incremental"
    criterion: correction below ``rtol`` times the first), from 0.10 the new ``NonlinearProblem`` on
    SNES (``newtonls`` without a line search; step and residual tests at ``rtol``); the linear solver
    from ``petsc_options`` (keys without ``prefix``). Calling it solves from the current ``u`` and
    returns (iterations, converged); ``monitor`` gets the norm of each residual evaluated."""
    if VERSION >= (0, 10):
        return _snes_newton(F, u, bcs, J, petsc_options, rtol, prefix, monitor)
    from dolfinx.nls.petsc import NewtonSolver
    problem = fem_petsc.NonlinearProblem(F, u, bcs=list(bcs), J=J)
    if monitor is not None:
        residual = problem.F

        def reported(x, b):
            residual(x, b)
            monitor(b.norm())
        problem.F = reported
    solver = NewtonSolver(u.function_space.mesh.comm, problem)
    solver.convergence_criterion = "incremental"
    solver.rtol, solver.atol, solver.max_it = rtol, 0.0, 50
    solver.error_on_nonconvergence = False
    ksp = solver.krylov_solver
    ksp.setOptionsPrefix(prefix)
    opts = PETSc.Options()
    for key, value in petsc_options.items():
        opts[f"{prefix}{key}"] = value
    ksp.setFromOptions()

    def solve():
        n, converged = solver.solve(u)
        return int(n), bool(converged)
    solve.keep = (problem, solver)                  # the objects live as long as the function
    return solve


def plain_newton_kind() -> str:
    """Which of dolfinx's Newton solvers :func:`plain_newton` uses here: "NewtonSolver" or "SNES"."""
    return "SNES" if VERSION >= (0, 10) else "NewtonSolver"


def _snes_newton(F, u, bcs, J, petsc_options: dict, rtol: float, prefix: str, monitor):
    """``plain_newton`` from dolfinx 0.10 on: ``fem.petsc.NonlinearProblem`` on SNES."""
    options = {"snes_type": "newtonls", "snes_linesearch_type": "basic", "snes_rtol": rtol,
               "snes_atol": 0.0, "snes_stol": rtol, "snes_max_it": 50, **petsc_options}
    problem = fem_petsc.NonlinearProblem(F, u, bcs=list(bcs), J=J, petsc_options_prefix=prefix,
                                         petsc_options=options)
    if monitor is not None:
        problem.solver.setMonitor(lambda snes, it, norm: monitor(norm))

    def solve():
        problem.solve()
        snes = problem.solver
        return int(snes.getIterationNumber()), snes.getConvergedReason() > 0
    solve.keep = (problem,)
    return solve


_GMSH_CELLS = {2: ("triangle", 1), 9: ("triangle", 2), 3: ("quadrilateral", 1), 10: ("quadrilateral", 2),
               4: ("tetrahedron", 1), 11: ("tetrahedron", 2), 5: ("hexahedron", 1), 12: ("hexahedron", 2)}
"""Gmsh's element type -> (cell, degree) of the cells that comove_dolfinx reads."""


def mesh_from_gmsh_arrays(comm, gmsh_type: int, x: np.ndarray, cells: np.ndarray, cell_values: np.ndarray,
                          facets: np.ndarray | None, facet_values: np.ndarray | None, gdim: int):
    """(mesh, cell tags, facet tags) from the arrays of a gmsh mesh held by one rank, as
    :func:`model_to_mesh` makes them from the gmsh model itself, without gmsh: the nodes ``x``
    (n, 3) in the order of their gmsh tags, the cells (gmsh's element type ``gmsh_type``; gmsh's
    node order, numbered from 0) and the facets of the physical groups with their group tags. The
    other ranks pass empty arrays (0 rows; ``facets`` None on every rank when there are no facet
    groups). The mesh is distributed as that function distributes it: the same partition."""
    shape, degree = _GMSH_CELLS[gmsh_type]
    ctype = dolfinx.cpp.mesh.to_type(shape)
    perm = dolfinx.cpp.io.perm_gmsh
    ordered = cells[:, perm(ctype, cells.shape[1])].copy()       # dolfinx's node order
    if _OLD:
        cell = ufl.Cell(shape, geometric_dimension=gdim)
        domain = ufl.Mesh(ufl.VectorElement(ufl.FiniteElement("Lagrange", cell, degree, variant="equispaced")))
        mesh = dolfinx.mesh.create_mesh(comm, ordered, x[:, :gdim], domain)
    else:
        domain = _gmsh_reader().ufl_mesh(gmsh_type, gdim, dtype=dolfinx.default_real_type)
        x = x[:, :gdim].astype(dolfinx.default_real_type, copy=False)
        if VERSION >= (0, 10):
            mesh = dolfinx.mesh.create_mesh(comm, ordered, domain, x)
        else:
            mesh = dolfinx.mesh.create_mesh(comm, ordered, x, domain)
    tdim = mesh.topology.dim
    if facets is not None and VERSION < (0, 10):   # (0.10 on: tags take the nodes in gmsh's order)
        facets = facets[:, perm(dolfinx.cpp.mesh.cell_entity_type(ctype, tdim - 1, 0), facets.shape[1])]
    cell_tags = _tags(mesh, tdim, ordered if VERSION < (0, 10) else cells, cell_values)
    if facets is None:
        facet_tags = dolfinx.mesh.meshtags(mesh, tdim - 1, np.empty(0, np.int32), np.empty(0, np.int32))
    else:
        facet_tags = _tags(mesh, tdim - 1, facets, facet_values)
    return mesh, cell_tags, facet_tags


def _gmsh_reader():
    """dolfinx's gmsh module (0.9: ``dolfinx.io.gmshio``, from 0.10 ``dolfinx.io.gmsh``), which
    imports gmsh only in its file reader."""
    if VERSION >= (0, 10):
        from dolfinx.io import gmsh as reader
    else:
        from dolfinx.io import gmshio as reader
    return reader


def _tags(mesh, dim: int, entities: np.ndarray, values: np.ndarray):
    """Mesh tags of the entities of dimension ``dim`` given by their nodes (input numbering)."""
    if _OLD:
        local, local_values = dolfinx.cpp.io.distribute_entity_data(mesh._mesh, dim, entities, values)
    else:
        from dolfinx.io import distribute_entity_data
        local, local_values = distribute_entity_data(mesh, dim, entities, values)
    mesh.topology.create_connectivity(dim, 0 if dim == mesh.topology.dim else mesh.topology.dim)
    if VERSION >= (0, 10):
        from dolfinx.graph import adjacencylist
        adjacency = adjacencylist(local)
    else:
        adjacency = dolfinx.cpp.graph.AdjacencyList_int32(local)
    return dolfinx.mesh.meshtags_from_entities(mesh, dim, adjacency, local_values.astype(np.int32, copy=False))

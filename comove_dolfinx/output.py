"""Results: XDMF for ParaView, the CSV history, point probes. All MPI-safe, flushed every increment.

XDMF (``results.xdmf`` + ``.h5``), one time step per converged increment, time = load factor:
``displacement`` (exact: the mesh geometry has the displacement's degree, so every P2 node is written),
``cauchy_stress`` (3x3, cell averages, index 2 = out-of-plane / hoop), ``von_mises`` (cell averages),
``plastic_strain`` (equivalent, elastic-plastic bodies), the normal stress along convected fibres that
the scene names (physical components on the convected base, cell averages: ``fibre_stress`` along the
deformed beam axis, ``hoop_stress`` of the ring, ``radial_stress`` of the plate), plus fields
registered by other modules (e.g. the contact pressure). In ParaView: open results.xdmf (reader
"Xdmf3ReaderT"), apply "Warp By Vector" with the displacement to see the deformed body.
"""
from __future__ import annotations

import csv
import pathlib

import numpy as np
import ufl
from dolfinx import fem, io
from mpi4py import MPI

from . import compat
from .kinematics import fibre_stress, to_tensor
from .parallel import on_root


class Probe:
    """Value of a vector Lagrange function at a node of its space (e.g. the beam tip)."""

    def __init__(self, V, point, tol: float = 1e-8):
        X = V.tabulate_dof_coordinates()
        n_owned = V.dofmap.index_map.size_local
        d = np.linalg.norm(X[:n_owned, :len(point)] - np.asarray(point, dtype=float), axis=1)
        comm = V.mesh.comm
        local = (float(d.min()) if d.size else np.inf, comm.rank)
        best, owner = comm.allreduce(local, op=MPI.MINLOC)
        if best > tol:
            raise ValueError(f"no node of the mesh at {tuple(point)} (nearest at distance {best:.3g}); "
                             "choose a mesh size that puts a node there")
        self.comm, self.owner = comm, owner
        self.dof = int(np.argmin(d)) if comm.rank == owner else -1
        self.bs = V.dofmap.index_map_bs

    def __call__(self, f: fem.Function) -> np.ndarray:
        val = np.zeros(self.bs)
        if self.comm.rank == self.owner:
            val[:] = f.x.array[self.bs * self.dof: self.bs * (self.dof + 1)]
        return self.comm.allreduce(val, op=MPI.SUM)


class History:
    """CSV with one row per converged increment, written by rank 0 and flushed at once (a failure
    to write is raised on every rank)."""

    def __init__(self, path: pathlib.Path, columns: list[str], comm=MPI.COMM_WORLD):
        self.columns = list(columns)
        self.rows: list[dict] = []
        self.comm = comm
        self._fh = None
        on_root(comm, self._open, path)

    def _open(self, path) -> None:
        self._fh = open(path, "w", newline="")
        self._writer = csv.writer(self._fh)
        self._writer.writerow(self.columns)
        self._fh.flush()

    def _write(self, values: dict) -> None:
        self._writer.writerow([_fmt(values[c]) for c in self.columns])
        self._fh.flush()

    def append(self, **values) -> None:
        missing = set(self.columns) - set(values)
        if missing:
            raise KeyError(f"history row lacks {sorted(missing)}")
        self.rows.append(values)
        on_root(self.comm, self._write, values)

    def close(self) -> None:
        if self._fh is not None:
            self._fh.close()
            self._fh = None


def _fmt(v) -> str:
    if isinstance(v, (int, np.integer)):
        return str(int(v))
    return f"{float(v):.10g}"


class FibreStress:
    """Normal Cauchy stress along the convected fibre a = F A of a reference direction A, a.sigma.a /
    a.a (the diagonal physical component on the convected base, kinematics.fibre_stress), as cell
    averages in a DG0 function. ``A``: in-plane unit vector, a constant or a UFL expression of the
    reference coordinates (e.g. the ring's hoop direction)."""

    def __init__(self, model, name: str, A):
        rule = model.rule
        A3 = ufl.as_vector([A[0], A[1], 0.0])
        self.rule = rule
        self.expr = rule.expression(fibre_stress(to_tensor(model.sigma), model.F, A3))
        DG0 = compat.function_space(model.mesh, "DG", 0)
        self.function = fem.Function(DG0, name=name)
        self.cell_dofs = compat.cell_dofs(DG0, len(rule.cells))[:, 0]

    def values(self) -> np.ndarray:
        """Cell averages over the local and ghost cells at the current iterate."""
        return self.rule.cell_average(self.rule.evaluate(self.expr)[:, 0])

    def update(self) -> fem.Function:
        self.function.x.array[self.cell_dofs] = self.values()
        return self.function


class XDMFOutput:
    """Per-increment XDMF of a model's fields (``extra`` adds (name, callable -> Function) pairs,
    ``fibres`` (name, reference direction) pairs of :class:`FibreStress`)."""

    def __init__(self, path: pathlib.Path, model, extra=(), fibres=()):
        msh = model.mesh
        gdeg = compat.geometry_degree(msh)
        if model.degree != gdeg:
            raise ValueError(
                f"displacement degree {model.degree} on a mesh of geometry order {gdeg}: XDMF would "
                f"keep only the vertex values. Build the mesh with order={model.degree}.")
        self.model = model
        self.file = io.XDMFFile(msh.comm, str(path), "w")
        self.file.write_mesh(msh)
        DG0 = compat.function_space(msh, "DG", 0)
        T0 = compat.function_space(msh, "DG", 0, (3, 3))
        self.stress = fem.Function(T0, name="cauchy_stress")
        self.mises = fem.Function(DG0, name="von_mises")
        self.plastic = fem.Function(DG0, name="plastic_strain") if model.plasticity else None
        self.extra = list(extra)
        self.fibres = [FibreStress(model, name, A) for name, A in fibres]
        # DG0 dof of each local and ghost cell (the numbering need not follow the cells)
        self.cell_dofs = compat.cell_dofs(DG0, len(model.rule.cells))[:, 0]
        self.cell_dofs_T = compat.cell_dofs(T0, len(model.rule.cells))[:, 0]

    def write(self, t: float) -> None:
        m, rule = self.model, self.model.rule
        sig = rule.cell_average(m.cauchy_stress())            # (cells, 4)
        T = np.zeros((sig.shape[0], 3, 3))
        T[:, 0, 0], T[:, 1, 1], T[:, 2, 2] = sig[:, 0], sig[:, 1], sig[:, 2]
        T[:, 0, 1] = T[:, 1, 0] = sig[:, 3]
        self.stress.x.array.reshape(-1, 9)[self.cell_dofs_T] = T.reshape(-1, 9)
        s = T - np.trace(T, axis1=1, axis2=2)[:, None, None] / 3.0 * np.eye(3)
        self.mises.x.array[self.cell_dofs] = np.sqrt(1.5 * np.einsum("cij,cij->c", s, s))
        funcs = [m.u, self.stress, self.mises]
        if self.plastic is not None:
            self.plastic.x.array[self.cell_dofs] = rule.cell_average(m.p.x.array)
            funcs.append(self.plastic)
        funcs += [f.update() for f in self.fibres]
        funcs += [make() for _, make in self.extra]
        for f in funcs:
            self.file.write_function(f, t)

    def close(self) -> None:
        self.file.close()

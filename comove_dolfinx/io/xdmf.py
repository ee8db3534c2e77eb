"""Fields per converged increment in XDMF (+ HDF5) for ParaView; time = the job's time column.

``displacement`` (exact: the mesh geometry has the displacement's degree, so every P2 node is written),
``cauchy_stress`` (3x3, cell averages; in 2D index 2 = out-of-plane / hoop), ``von_mises`` (cell averages),
``plastic_strain`` (equivalent, elastic-plastic bodies), the normal stress along convected fibres
(``fibres``: physical components on the convected base, cell averages, e.g. the ring's hoop stress)
and, for every contact item, ``contact_pressure`` (and ``contact_shear`` with friction) on the
contact boundary.

Each field is its own XDMF time series on its own grid (dolfinx's XDMFFile writes them so): ParaView's
XDMF readers show one block per field, and "Warp By Vector" warps only the displacement's block, so a
deformed body coloured by a stress needs the blocks merged first. For ParaView use the VTK writer
(io/vtk.py, the command's default: every field of an increment on one grid); this one is for
tools that read dolfinx's XDMF (dolfinx itself, meshio's XDMF time series per field).
"""
from __future__ import annotations

import pathlib

import numpy as np
import ufl
from dolfinx import fem, io

from .. import compat
from ..mechanics.kinematics import fibre_stress, to_tensor
from .writers import Writer


# the stored stress vectors' components in the 3x3 tensor: 2D (xx, yy, zz, xy), 3D (xx, yy, zz, xy, yz, xz)
_TENSOR_INDEX = {4: [(0, 0), (1, 1), (2, 2), (0, 1)], 6: [(0, 0), (1, 1), (2, 2), (0, 1), (1, 2), (0, 2)]}


def stress_tensors(sig: np.ndarray) -> np.ndarray:
    """Stored stress vectors (n, 4) of a 2D body or (n, 6) of a 3D body -> symmetric tensors (n, 3, 3)."""
    T = np.zeros((sig.shape[0], 3, 3))
    for k, (i, j) in enumerate(_TENSOR_INDEX[sig.shape[1]]):
        T[:, i, j] = T[:, j, i] = sig[:, k]
    return T


def von_mises(T: np.ndarray) -> np.ndarray:
    """Von Mises equivalent stress sqrt(3/2 s:s) of tensors (n, 3, 3)."""
    s = T - np.trace(T, axis1=1, axis2=2)[:, None, None] / 3.0 * np.eye(3)
    return np.sqrt(1.5 * np.einsum("cij,cij->c", s, s))


class FibreStress:
    """Normal Cauchy stress along the convected fibre a = F A of a reference direction A, a.sigma.a /
    a.a (kinematics.fibre_stress), as cell averages in a DG0 function. ``A``: a vector of the body's
    dimension (in-plane in 2D), or a function of the reference coordinates x (UFL) that returns one
    (e.g. the hoop direction)."""

    def __init__(self, model, name: str, A):
        rule = model.rule
        A = A(model.x) if callable(A) else A
        A3 = ufl.as_vector([A[0], A[1], A[2] if model.mesh.topology.dim == 3 else 0.0])
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


class XDMF(Writer):
    """The fields of the module docstring at every converged increment into ``path`` (.xdmf)."""

    def __init__(self, path, fibres=()):
        self.path, self.fibre_specs = pathlib.Path(path), list(fibres)
        self.file = None

    def open(self, run) -> None:
        model = run.model
        msh = model.mesh
        gdeg = compat.geometry_degree(msh)
        if model.degree != gdeg:
            raise ValueError(
                f"displacement degree {model.degree} on a mesh of geometry order {gdeg}: XDMF would "
                f"keep only the vertex values. Build the mesh with order={model.degree}.")
        self.model = model
        self.file = io.XDMFFile(msh.comm, str(self.path), "w")
        self.file.write_mesh(msh)
        DG0 = compat.function_space(msh, "DG", 0)
        T0 = compat.function_space(msh, "DG", 0, (3, 3))
        self.stress = fem.Function(T0, name="cauchy_stress")
        self.mises = fem.Function(DG0, name="von_mises")
        self.plastic = fem.Function(DG0, name="plastic_strain") if model.plastic else None
        self.fibres = [FibreStress(model, name, A) for name, A in self.fibre_specs]
        self.contacts = [item for item in model.items if item.kind == "contact"]
        # DG0 dof of each local and ghost cell (the numbering need not follow the cells)
        self.cell_dofs = compat.cell_dofs(DG0, len(model.rule.cells))[:, 0]
        self.cell_dofs_T = compat.cell_dofs(T0, len(model.rule.cells))[:, 0]

    def write(self, run, row, increment) -> None:
        m, rule = self.model, self.model.rule
        T = stress_tensors(rule.cell_average(m.cauchy_stress()))
        self.stress.x.array.reshape(-1, 9)[self.cell_dofs_T] = T.reshape(-1, 9)
        self.mises.x.array[self.cell_dofs] = von_mises(T)
        funcs = [m.u, self.stress, self.mises]
        if self.plastic is not None:
            self.plastic.x.array[self.cell_dofs] = rule.cell_average(m.p.x.array)
            funcs.append(self.plastic)
        funcs += [f.update() for f in self.fibres]
        for c in self.contacts:
            c.update_fields()
            funcs.append(c.pressure)
            if c.mu > 0:
                funcs.append(c.shear)
        t = row["time"]                 # increasing (the load may go down and up again)
        for f in funcs:
            self.file.write_function(f, t)

    def close(self, run, results) -> None:
        if self.file is not None:
            self.file.close()
            self.file = None

"""One ParaView dataset per converged increment: ``results.pvd`` and ``results_NNNNN.vtu``.

Every ``.vtu`` holds the whole body on the displacement's mesh, at its reference position (quadratic
triangles or tetrahedra for P2, 9-node quadrilaterals and 27-node hexahedra for Q2, so every node
of the solution is there) with all the fields of that increment, so that ParaView's open -> Warp By
Vector -> colour by any field works on each time step:

* point data: ``displacement`` (3 components; z = 0 for 2D bodies, for Warp By Vector) and, for
  every contact item, ``contact_pressure`` (and ``contact_shear`` with friction): the pressure that
  the contact law gives, per current area, projected onto the boundary's vertices with non-negative
  (linear) weights, so it is never negative; zero away from the contact boundary;
* cell data: ``cauchy_stress_cell_avg`` (3x3, the average over the cell of the stress at its
  quadrature points; for 2D bodies component zz is the out-of-plane or hoop stress),
  ``von_mises_cell_avg`` (of the averaged stress), ``plastic_strain_cell_avg`` (elastic-plastic
  bodies) and the fibre stresses (``<name>_cell_avg``).

The collection ``results.pvd`` lists the increments with their time (the job's ``time`` column;
io/pvd.py). Rank 0 gathers and writes; each dataset is written under a temporary name and renamed
into place before the collection names it, so a run that is killed leaves every increment it
converged readable and never half a file.
"""
from __future__ import annotations

import os
import pathlib

import numpy as np

from .. import compat
from ..checks import first, flag, text
from ..parallel import on_root
from . import vtu
from .folder import FolderError
from .pvd import Collection
from .writers import Writer
from .xdmf import FibreStress, stress_tensors, von_mises

# (dimension, nodes per cell) -> the cell type (vtu.VTK_TYPES) and the cell's nodes in VTK's order, or None.
# dolfinx's P2 triangle: vertices 0, 1, 2, then the edges opposite them (1-2, 0-2, 0-1); VTK's
# quadratic triangle: vertices, then the edges 0-1, 1-2, 2-0. dolfinx's (basix's) P2 tetrahedron:
# vertices 0-3, then the edges 2-3, 1-3, 1-2, 0-3, 0-2, 0-1; VTK's quadratic tetrahedron: vertices,
# then the edges 0-1, 1-2, 0-2, 0-3, 1-3, 2-3. dolfinx's quadrilateral: vertices in tensor order
# (x fastest), for Q2 then the edges 0-1, 0-2, 1-3, 2-3 and the centre; VTK's (bi)quadratic quad
# (type 28): vertices counter-clockwise, the edges 0-1, 1-2, 2-3, 3-0, the centre. dolfinx's
# hexahedron: vertices in tensor order (x fastest), for Q2 then the edges, the faces and the centre
# (basix's numbering); VTK's (tri)quadratic hexahedron (type 29, ParaView draws it curved):
# vertices counter-clockwise at z = 0, then z = 1, the edges 0-1, 1-2, 2-3, 3-0 (z = 0), the same
# at z = 1, the edges along z, the faces x = 0, x = 1, y = 0, y = 1, z = 0, z = 1, the centre.
_VTK_CELLS = {(2, 3): ("triangle", None), (2, 6): ("triangle6", [0, 1, 2, 5, 3, 4]),
              (2, 4): ("quad", [0, 1, 3, 2]), (2, 9): ("quad9", [0, 1, 3, 2, 4, 6, 7, 5, 8]),
              (3, 4): ("tetra", None), (3, 10): ("tetra10", [0, 1, 2, 3, 9, 6, 8, 7, 5, 4]),
              (3, 8): ("hexahedron", [0, 1, 3, 2, 4, 5, 7, 6]),
              (3, 27): ("hexahedron27", [0, 1, 3, 2, 4, 5, 7, 6, 8, 11, 13, 9, 16, 18, 19, 17, 10, 12, 15, 14,
                                         22, 23, 21, 24, 20, 25, 26])}


def _atomic_write(path: pathlib.Path, write) -> None:
    tmp = path.with_name(f".{path.name}.tmp")
    write(tmp)
    os.replace(tmp, path)


class VTK(Writer):
    """The fields of the module docstring at every converged increment, into ``folder``.

    A folder that holds the datasets of an earlier run (``<name>.pvd``, ``<name>_NNNNN.vtu``) is
    refused when the run starts (:class:`FolderError`), unless ``overwrite=True``, which removes them
    first, so that no dataset of the old run is left beside the new ones; a restarted run
    (``job.run(restart=...)``) goes on with the datasets up to its checkpoint.
    """

    def __init__(self, folder, name: str = "results", fibres=(), *, overwrite: bool = False):
        why = first(text("name", name, "a file name for the datasets, e.g. 'results'"), flag("overwrite", overwrite))
        if why is not None:
            raise FolderError(f"VTK: {why}")
        self.folder, self.name, self.fibre_specs = pathlib.Path(folder), name, list(fibres)
        self.overwrite = overwrite
        self.steps: list[tuple[float, str]] = []

    def _earlier(self) -> list[pathlib.Path]:
        """The datasets of an earlier run in the folder (the collection and its increments)."""
        pvd = self.folder / f"{self.name}.pvd"
        return ([pvd] if pvd.exists() else []) + sorted(self.folder.glob(f"{self.name}_[0-9]*.vtu"))

    def _take_folder(self, resumed: bool) -> None:
        """On rank 0: make the folder; refuse (or with ``overwrite`` remove) an earlier run's datasets,
        unless the run is a restart, which goes on with them."""
        if self.folder.exists() and not self.folder.is_dir():
            raise FolderError(f"VTK: {self.folder} is a file, not a folder: choose a folder")
        self.folder.mkdir(parents=True, exist_ok=True)
        old = [] if resumed else self._earlier()
        if old and not self.overwrite:
            shown = ", ".join(p.name for p in old[:2]) + (", ..." if len(old) > 2 else "")
            raise FolderError(f"VTK: {self.folder} holds the datasets of an earlier run ({shown}): pass "
                              "VTK(folder, overwrite=True) to replace them, or choose another folder")
        for p in old:
            p.unlink()

    # -- set-up ---------------------------------------------------------------------------------
    def open(self, run) -> None:
        m = run.model
        self.model, self.comm = m, m.comm
        V = m.V
        imap = V.dofmap.index_map
        n_own = imap.size_local
        self.n_own = n_own
        gidx = imap.local_to_global(np.arange(n_own, dtype=np.int32))
        X = V.tabulate_dof_coordinates()[:n_own]
        tdim = m.mesh.topology.dim
        n_cells = m.mesh.topology.index_map(tdim).size_local
        self.n_cells = n_cells
        cells = compat.cell_dofs(V, n_cells)
        cells = imap.local_to_global(cells.ravel()).reshape(n_cells, -1)
        self.cell_type, order = _VTK_CELLS[(tdim, cells.shape[1])]
        if order is not None:
            cells = cells[:, order]
        parts = self.comm.gather((gidx, X, cells), root=0)
        self.gidx_all = [g for g, _, _ in parts] if self.comm.rank == 0 else None
        if self.comm.rank == 0:
            n = imap.size_global
            self.points = np.zeros((n, 3))
            for g, x, _ in parts:
                self.points[g] = x
            self.cells = np.concatenate([c for _, _, c in parts])
        self.grid = None                     # (on rank 0, at the first write: vtu.Grid)
        self.collection = None               # (on rank 0, at the first write: pvd.Collection)
        self.fibres = [FibreStress(m, name, A) for name, A in self.fibre_specs]
        self.contacts = [item for item in m.items if item.kind == "contact"]
        on_root(self.comm, self._take_folder, bool(run.resumed_rows))
        self.steps = []
        if run.resumed_rows:             # a restarted run: the datasets up to its checkpoint
            import xml.etree.ElementTree as ET
            pvd = self.folder / f"{self.name}.pvd"
            sets = [(float(d.get("timestep")), d.get("file")) for d in ET.parse(pvd).getroot().iter("DataSet")]
            self.steps = sets[:len(run.resumed_rows)]

    # -- each increment -------------------------------------------------------------------------
    def _gather_points(self, values: np.ndarray) -> np.ndarray | None:
        """Owned nodal values (n_own, k) of the displacement's numbering -> global array on rank 0."""
        if self.comm.size == 1:
            return values
        parts = self.comm.gather(values, root=0)
        if self.comm.rank != 0:
            return None
        out = np.zeros((len(self.points), values.shape[1]))
        for g, v in zip(self.gidx_all, parts):
            out[g] = v
        return out

    def _gather_cells(self, values: np.ndarray) -> np.ndarray | None:
        if self.comm.size == 1:
            return values[: self.n_cells]
        parts = self.comm.gather(values[: self.n_cells], root=0)
        return np.concatenate(parts) if self.comm.rank == 0 else None

    def _boundary_field(self, contact, f) -> np.ndarray:
        """A contact output field (on the boundary's nodes) as values at the displacement's nodes."""
        out = np.zeros((self.n_own, 1))
        ok = contact.node_sdof >= 0
        out[contact.nodes[ok], 0] = f.x.array[contact.node_sdof[ok]]
        return out

    def write(self, run, row, increment) -> None:
        m, rule = self.model, self.model.rule
        u = m.u.x.array.reshape(-1, m.V.dofmap.index_map_bs)[: self.n_own]
        point = {"displacement": np.hstack([u, np.zeros((self.n_own, 3 - u.shape[1]))])}
        for k, c in enumerate(self.contacts):
            suffix = f"_{k + 1}" if len(self.contacts) > 1 else ""
            c.update_fields()
            point[f"contact_pressure{suffix}"] = self._boundary_field(c, c.pressure)
            if c.mu > 0:
                point[f"contact_shear{suffix}"] = self._boundary_field(c, c.shear)
        T = stress_tensors(rule.cell_average(m.cauchy_stress()))
        cell = {"cauchy_stress_cell_avg": T.reshape(-1, 9), "von_mises_cell_avg": von_mises(T)}
        if m.plastic is not None:
            cell["plastic_strain_cell_avg"] = rule.cell_average(m.p.x.array)
        for f in self.fibres:
            cell[f"{f.function.name}_cell_avg"] = f.values()
        point = {k: self._gather_points(v) for k, v in point.items()}
        cell = {k: self._gather_cells(v) for k, v in cell.items()}
        index = len(self.steps)
        fname = f"{self.name}_{index:05d}.vtu"
        self.steps.append((float(row["time"]), fname))
        on_root(self.comm, self._write_files, fname, point, cell)

    def _write_files(self, fname, point, cell) -> None:
        # uncompressed binary: zlib took three quarters of the write (2.2 ms against 0.5 ms for the
        # ring's 700 nodes) for files 2.2 times smaller
        if getattr(self, "grid", None) is None:
            self.grid = vtu.Grid(self.points, self.cell_type, self.cells)
        _atomic_write(self.folder / fname, lambda p: self.grid.write(p, point, cell))
        if self.collection is None:
            self.collection = Collection(self.folder / f"{self.name}.pvd")
        self.collection.add(self.steps)

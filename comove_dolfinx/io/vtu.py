"""VTK XML unstructured grids (``.vtu``) written from NumPy arrays, their data raw in the file's
appended section.

The VTK writer (vtk.py) writes one such file per increment, on the same points and cells. A
general mesh library (meshio) did it before; its import (every format it knows and its command
line's modules) cost the ring's run about as much as all its increments' output together, for a
layout this small: the points, one cell type, and float64 point and cell arrays. :class:`Grid`
turns the points and cells into bytes once; each file then adds only its fields. ParaView and
meshio read the files.
"""
from __future__ import annotations

from html import escape

import numpy as np

#: meshio's name of a cell type -> VTK's number for it
VTK_TYPES = {"triangle": 5, "triangle6": 22, "tetra": 10, "tetra10": 24}

_TYPES = {np.dtype("<f8"): "Float64", np.dtype("<i8"): "Int64", np.dtype("u1"): "UInt8"}


class _Appended:
    """The appended section: each array as its length in bytes (UInt64) and its bytes."""

    def __init__(self, offset: int = 0):
        self.blocks: list[bytes] = []
        self.offset = offset

    def element(self, name: str | None, array: np.ndarray) -> str:
        """Append ``array`` (float64, int64 or uint8; 1 or 2 dimensions); its DataArray element."""
        data = np.ascontiguousarray(array).tobytes()
        label = f' Name="{escape(name)}"' if name is not None else ""
        if array.ndim == 2:
            label += f' NumberOfComponents="{array.shape[1]}"'
        xml = f'<DataArray type="{_TYPES[array.dtype]}"{label} format="appended" offset="{self.offset}"/>'
        self.blocks += [np.uint64(len(data)).tobytes(), data]
        self.offset += 8 + len(data)
        return xml


class Grid:
    """The points (n, 3) and the cells (m, k) of one type (a key of :data:`VTK_TYPES`, nodes in
    VTK's order) of a series of files, turned into bytes once."""

    def __init__(self, points: np.ndarray, cell_type: str, cells: np.ndarray):
        i8 = np.dtype("<i8")
        cells = np.asarray(cells, dtype=i8)
        (m, k), n = cells.shape, len(points)
        self.section = _Appended()
        self.head = ['<?xml version="1.0"?>',
                     '<VTKFile type="UnstructuredGrid" version="1.0" byte_order="LittleEndian" '
                     'header_type="UInt64">', "<UnstructuredGrid>",
                     f'<Piece NumberOfPoints="{n}" NumberOfCells="{m}">',
                     "<Points>", self.section.element(None, np.asarray(points, dtype="<f8")), "</Points>",
                     "<Cells>", self.section.element("connectivity", cells.ravel()),
                     self.section.element("offsets", np.arange(k, k * m + 1, k, dtype=i8)),
                     self.section.element("types", np.full(m, VTK_TYPES[cell_type], dtype=np.uint8)),
                     "</Cells>"]
        self.geometry = b"".join(self.section.blocks)

    def write(self, path, point_data: dict, cell_data: dict) -> None:
        """Write the grid with the arrays of ``point_data`` ((n,) or (n, c)) and ``cell_data``
        ((m,) or (m, c)) to ``path``."""
        section, xml = _Appended(self.section.offset), list(self.head)
        for tag, data in (("PointData", point_data), ("CellData", cell_data)):
            xml.append(f"<{tag}>")
            xml += [section.element(name, np.asarray(v, dtype="<f8")) for name, v in data.items()]
            xml.append(f"</{tag}>")
        xml += ["</Piece>", "</UnstructuredGrid>", '<AppendedData encoding="raw">\n_']
        with open(path, "wb") as fh:
            fh.write("\n".join(xml).encode())
            fh.write(self.geometry)
            fh.write(b"".join(section.blocks))
            fh.write(b"\n</AppendedData>\n</VTKFile>\n")


def write(path, points: np.ndarray, cell_type: str, cells: np.ndarray, point_data: dict,
          cell_data: dict) -> None:
    """One file: :class:`Grid` of ``points`` and ``cells`` with the given fields."""
    Grid(points, cell_type, cells).write(path, point_data, cell_data)

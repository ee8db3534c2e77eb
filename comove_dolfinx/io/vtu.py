"""One VTK XML unstructured grid (``.vtu``) written from NumPy arrays, its data raw in the file's
appended section.

The VTK writer (vtk.py) writes one such file per increment. A general mesh library (meshio) did
it before; its import (every format it knows and its command line's modules) cost the ring's run
about as much as all its increments' output together, for a layout this small: the points, one
cell type, and float64 point and cell arrays. ParaView and meshio read the files.
"""
from __future__ import annotations

from html import escape

import numpy as np

#: meshio's name of a cell type -> VTK's number for it
VTK_TYPES = {"triangle": 5, "triangle6": 22, "tetra": 10, "tetra10": 24}


class _Appended:
    """The appended section: each array as its length in bytes (UInt64) and its bytes."""

    def __init__(self):
        self.blocks: list[bytes] = []
        self.offset = 0

    def add(self, array: np.ndarray) -> int:
        """Append ``array``; its offset in the section."""
        data = np.ascontiguousarray(array).tobytes()
        start = self.offset
        self.blocks += [np.uint64(len(data)).tobytes(), data]
        self.offset += 8 + len(data)
        return start


def _array(section: _Appended, name: str | None, array: np.ndarray) -> str:
    """The DataArray element of ``array`` (float64, int64 or uint8; 1 or 2 dimensions)."""
    kind = {np.dtype("<f8"): "Float64", np.dtype("<i8"): "Int64", np.dtype("u1"): "UInt8"}[array.dtype]
    label = f' Name="{escape(name)}"' if name is not None else ""
    if array.ndim == 2:
        label += f' NumberOfComponents="{array.shape[1]}"'
    return f'<DataArray type="{kind}"{label} format="appended" offset="{section.add(array)}"/>'


def write(path, points: np.ndarray, cell_type: str, cells: np.ndarray, point_data: dict,
          cell_data: dict) -> None:
    """Write the grid of ``points`` (n, 3) and ``cells`` (m, k) of one type (a key of
    :data:`VTK_TYPES`, nodes in VTK's order) with the arrays of ``point_data`` ((n,) or (n, c))
    and ``cell_data`` ((m,) or (m, c)) to ``path``."""
    f8, i8 = np.dtype("<f8"), np.dtype("<i8")
    cells = np.asarray(cells, dtype=i8)
    n, (m, k) = len(points), cells.shape
    section = _Appended()
    xml = ['<?xml version="1.0"?>',
           '<VTKFile type="UnstructuredGrid" version="1.0" byte_order="LittleEndian" header_type="UInt64">',
           "<UnstructuredGrid>", f'<Piece NumberOfPoints="{n}" NumberOfCells="{m}">',
           "<Points>", _array(section, None, np.asarray(points, dtype=f8)), "</Points>", "<Cells>",
           _array(section, "connectivity", cells.ravel()),
           _array(section, "offsets", np.arange(k, k * m + 1, k, dtype=i8)),
           _array(section, "types", np.full(m, VTK_TYPES[cell_type], dtype=np.uint8)), "</Cells>"]
    for tag, data in (("PointData", point_data), ("CellData", cell_data)):
        xml.append(f"<{tag}>")
        xml += [_array(section, name, np.asarray(v, dtype=f8)) for name, v in data.items()]
        xml.append(f"</{tag}>")
    xml += ["</Piece>", "</UnstructuredGrid>", '<AppendedData encoding="raw">\n_']
    with open(path, "wb") as fh:
        fh.write("\n".join(xml).encode())
        fh.write(b"".join(section.blocks))
        fh.write(b"\n</AppendedData>\n</VTKFile>\n")

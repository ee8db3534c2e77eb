"""VTK XML unstructured grids (``.vtu``) written from NumPy arrays, each array base64-encoded in
its DataArray element (VTK's "binary" format).

The VTK writer (vtk.py) writes one such file per increment, on the same points and cells. A
general mesh library (meshio) did it before; its import (every format it knows and its command
line's modules) cost the ring's run about as much as all its increments' output together, for a
layout this small: the points, one cell type, and float64 point and cell arrays. :class:`Grid`
encodes the points and cells once; each file then adds only its fields. ParaView and meshio read
the files (raw data in an appended section, which VTK reads as well, is misread by meshio 5.3 when
a file holds several arrays).
"""
from __future__ import annotations

import base64
from html import escape

import numpy as np

#: meshio's name of a cell type -> VTK's number for it
VTK_TYPES = {"triangle": 5, "triangle6": 22, "quad": 9, "quad9": 28, "tetra": 10, "tetra10": 24, "hexahedron": 12,
             "hexahedron27": 29}

_TYPES = {np.dtype("<f8"): "Float64", np.dtype("<i8"): "Int64", np.dtype("u1"): "UInt8"}


def _element(name: str | None, array: np.ndarray) -> str:
    """The DataArray element of ``array`` (float64, int64 or uint8; 1 or 2 dimensions): its length in
    bytes (UInt64) and its bytes, base64-encoded."""
    data = np.ascontiguousarray(array).tobytes()
    label = f' Name="{escape(name)}"' if name is not None else ""
    if array.ndim == 2:
        label += f' NumberOfComponents="{array.shape[1]}"'
    text = base64.b64encode(np.uint64(len(data)).tobytes() + data).decode()
    return f'<DataArray type="{_TYPES[array.dtype]}"{label} format="binary">{text}</DataArray>'


class Grid:
    """The points (n, 3) and the cells (m, k) of one type (a key of :data:`VTK_TYPES`, nodes in
    VTK's order) of a series of files, turned into bytes once."""

    def __init__(self, points: np.ndarray, cell_type: str, cells: np.ndarray):
        i8 = np.dtype("<i8")
        cells = np.asarray(cells, dtype=i8)
        (m, k), n = cells.shape, len(points)
        self.head = ['<?xml version="1.0"?>',
                     '<VTKFile type="UnstructuredGrid" version="1.0" byte_order="LittleEndian" '
                     'header_type="UInt64">', "<UnstructuredGrid>",
                     f'<Piece NumberOfPoints="{n}" NumberOfCells="{m}">',
                     "<Points>", _element(None, np.asarray(points, dtype="<f8")), "</Points>",
                     "<Cells>", _element("connectivity", cells.ravel()),
                     _element("offsets", np.arange(k, k * m + 1, k, dtype=i8)),
                     _element("types", np.full(m, VTK_TYPES[cell_type], dtype=np.uint8)),
                     "</Cells>"]

    def write(self, path, point_data: dict, cell_data: dict) -> None:
        """Write the grid with the arrays of ``point_data`` ((n,) or (n, c)) and ``cell_data``
        ((m,) or (m, c)) to ``path``."""
        xml = list(self.head)
        for tag, data in (("PointData", point_data), ("CellData", cell_data)):
            xml.append(f"<{tag}>")
            xml += [_element(name, np.asarray(v, dtype="<f8")) for name, v in data.items()]
            xml.append(f"</{tag}>")
        xml += ["</Piece>", "</UnstructuredGrid>", "</VTKFile>", ""]
        with open(path, "w") as fh:
            fh.write("\n".join(xml))


def write(path, points: np.ndarray, cell_type: str, cells: np.ndarray, point_data: dict,
          cell_data: dict) -> None:
    """One file: :class:`Grid` of ``points`` and ``cells`` with the given fields."""
    Grid(points, cell_type, cells).write(path, point_data, cell_data)

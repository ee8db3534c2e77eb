"""ParaView's collection file (``.pvd``) of a run's datasets, valid at every moment of the run.

The collection is written whole once (when the first dataset of a run, or of a restarted run, is
written: under a temporary name, renamed into place); each later dataset's line is then written
over the closing tags, with the closing tags after it, in one write at the known offset. The file
is never replaced during the run: replacing an existing file makes ext4 write it out at once
(its ``auto_da_alloc`` heuristic; 4 ms per increment on this project's test machine, most of
the ring scene's output time), where the one small write costs nothing of the kind. A run killed
between two writes leaves a complete collection of the datasets written so far.
"""
from __future__ import annotations

import pathlib
from html import escape

from .writers import write_atomic

_HEAD = '<?xml version="1.0"?>\n<VTKFile type="Collection" version="0.1">\n<Collection>\n'
_TAIL = "</Collection>\n</VTKFile>\n"


def _line(time: float, file: str) -> str:
    return f'  <DataSet timestep="{time:.12g}" part="0" file="{escape(file)}"/>\n'


class Collection:
    """The collection ``path`` of the datasets ``(time, file name)`` given to :meth:`add`."""

    def __init__(self, path: pathlib.Path):
        self.path = pathlib.Path(path)
        self.end: int | None = None           # offset of the closing tags, once the file is written

    def add(self, entries: list[tuple[float, str]]) -> None:
        """The collection of ``entries`` (all the datasets so far, the new one last): the whole
        file the first time, the last entry's line alone after that."""
        if self.end is None:
            body = (_HEAD + "".join(_line(t, f) for t, f in entries)).encode()
            write_atomic(self.path, (body + _TAIL.encode()).decode())
            self.end = len(body)
            return
        line = _line(*entries[-1]).encode()
        with open(self.path, "r+b") as f:
            f.seek(self.end)
            f.write(line + _TAIL.encode())
        self.end += len(line)

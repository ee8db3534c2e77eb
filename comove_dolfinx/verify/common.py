"""What the verification cases share: a job run with its cost, the contact pressure along a
boundary, the cases' meshes folder.

Imported by the case modules only (it loads dolfinx through the public API); the command's runner
does not import it.

Units are the case's own; CPU seconds are the process's user and system time including the child
processes it waited for (the C compiler of the form compiler), averaged over the MPI ranks.
"""
from __future__ import annotations

import os
import pathlib

import numpy as np
from mpi4py import MPI

from . import Check

#: the cases' Gmsh meshes are cached here (relative to the working folder, as the scenes' are)
MESHES = "meshes"


def cpu_seconds() -> float:
    """CPU seconds of this process and of the children it waited for (user + system)."""
    t = os.times()
    return t.user + t.system + t.children_user + t.children_system


def run_job(job, comm=MPI.COMM_WORLD):
    """Run ``job``; (its Results, Newton iterations with the failed ones, CPU seconds averaged over
    the ranks). A job that does not complete raises RuntimeError with its message (on every rank)."""
    start = cpu_seconds()
    res = job.run()
    cpu = comm.allreduce(cpu_seconds() - start, op=MPI.SUM) / comm.size
    if not res.completed:
        raise RuntimeError(f"the run stopped: {res.message}")
    return res, int(sum(res.newton_its) + res.failed_its), cpu


def profile(contact, model, axis: int = 0, current: bool = True) -> tuple[np.ndarray, np.ndarray]:
    """(coordinate ``axis``, contact pressure) at every node of the contact boundary, gathered on
    every rank and sorted along ``axis``: the nodal pressure field of ``contact.update_fields()`` at
    the nodes the item lists (``contact.nodes``, ``node_sdof``), at the current coordinate X + u or,
    with ``current=False``, the reference one X (the coordinate of a geometrically linear theory)."""
    contact.update_fields()
    nodes, sdof = contact.nodes, contact.node_sdof
    keep = sdof >= 0
    x = model.V.tabulate_dof_coordinates()[nodes[keep], axis]
    if current:
        x = x + model.u.x.array.reshape(-1, 2)[nodes[keep], axis]
    p = contact.pressure.x.array[sdof[keep]]
    comm = model.comm
    x, p = np.concatenate(comm.allgather(x)), np.concatenate(comm.allgather(p))
    order = np.argsort(x)
    return x[order], p[order]


def save_figure(fig, out: pathlib.Path, name: str, comm=MPI.COMM_WORLD) -> None:
    """Write ``fig`` to out/name.png on rank 0 and close it."""
    import matplotlib.pyplot as plt
    if comm.rank == 0:
        out.mkdir(parents=True, exist_ok=True)
        fig.savefig(out / f"{name}.png", dpi=110)
    plt.close(fig)


def triangles(mesh) -> np.ndarray:
    """The corners of this rank's cells, shape (cells, 3, 2), for drawing the mesh."""
    from .. import compat
    n = mesh.topology.index_map(mesh.topology.dim).size_local
    return mesh.geometry.x[compat.geometry_dofs(mesh)[:n, :3], :2]

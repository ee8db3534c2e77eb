"""The supports of a model: its Dirichlet conditions, the rigid motions they leave free, releasing a
support, and the reactions.

A support is an item of kind "support" (loads.Displacement, loads.Fixed). Where a support holds a
dof, the residual R = f_int - f_ext assembled without Dirichlet conditions is the force that the
support supplies: the reactions are read from it, and a released support's force (a nodal force
that the step ramps down) is taken from it.
"""
from __future__ import annotations

import numpy as np
from dolfinx import fem
from mpi4py import MPI

from .. import compat


def _centred(V, dim: int) -> tuple[int, np.ndarray, np.ndarray, float]:
    """(owned nodes n, their positions d relative to the centroid c of all the nodes, c, the rms
    distance ``size`` of the nodes from c) of the displacement space V. Collective."""
    n = V.dofmap.index_map.size_local
    X = V.tabulate_dof_coordinates()[:n, :dim]
    comm = V.mesh.comm
    total = max(comm.allreduce(n, op=MPI.SUM), 1)
    c = comm.allreduce(X.sum(axis=0), op=MPI.SUM) / total
    d = X - c
    size = float(np.sqrt(comm.allreduce(float((d ** 2).sum()), op=MPI.SUM) / total)) or 1.0
    return n, d, c, size


def rigid_motions(V) -> tuple[np.ndarray, np.ndarray, float]:
    """The two translations and the in-plane rotation of the 2-D displacement space V at this
    rank's owned nodes, (nodes, component, motion); the rotation is about the centroid c of all the
    nodes and divided by their rms distance ``size`` from it, so that the three are of one
    magnitude. Returns (modes, c, size). Collective."""
    n, d, c, size = _centred(V, 2)
    modes = np.zeros((n, 2, 3))
    modes[:, 0, 0] = modes[:, 1, 1] = 1.0
    modes[:, 0, 2], modes[:, 1, 2] = -d[:, 1] / size, d[:, 0] / size
    return modes, c, size


def rigid_motions_3d(V) -> tuple[np.ndarray, np.ndarray, float]:
    """The three translations and the three rotations (about x, y, z through the centroid, scaled as
    in :func:`rigid_motions`) of a 3D displacement space V at this rank's owned nodes, (nodes,
    component, motion). Returns (modes, c, size). Collective."""
    n, d, c, size = _centred(V, 3)
    modes = np.zeros((n, 3, 6))
    for k in range(3):
        modes[:, k, k] = 1.0
        modes[:, :, 3 + k] = np.cross(np.eye(3)[k], d) / size
    return modes, c, size


def describe_motions_3d(free: np.ndarray) -> list[str]:
    """In words, the rigid motions spanned by the columns (tx, ty, tz, rx, ry, rz) of ``free``."""
    out = []
    for f in free.T:
        f = f / np.abs(f).max()
        t, r = f[:3], f[3:]
        if np.abs(r).max() < 1e-8:
            axis = int(np.argmax(np.abs(t)))
            out.append("translation in " + ("xyz"[axis] if np.sum(np.abs(t) > 1e-8) == 1
                                            else "direction ({:.3g}, {:.3g}, {:.3g})".format(*t)))
        else:
            out.append("rotation about the axis ({:.3g}, {:.3g}, {:.3g})".format(*(r / np.linalg.norm(r))) +
                       ("" if np.abs(t).max() < 1e-8 else " with a translation"))
    return out


def describe_motions(free: np.ndarray, c: np.ndarray, size: float) -> list[str]:
    """In words, the rigid motions spanned by the columns (tx, ty, rot) of ``free``, in the units of
    :func:`rigid_motions` (centroid ``c``, rotation scaled by ``size``)."""
    if free.shape[1] == 3:
        return ["translation in x", "translation in y", "rotation"]
    out = []
    for tx, ty, rot in (f / np.abs(f).max() for f in free.T):
        if abs(rot) < 1e-8:
            t = np.array([tx, ty]) / np.hypot(tx, ty)
            out.append("translation in " + ("x" if abs(t[1]) < 1e-8 else "y" if abs(t[0]) < 1e-8
                                            else f"direction ({t[0]:.3g}, {t[1]:.3g})"))
        else:                                     # t + rot e_z x (x - c) / size = rot e_z x (x - p) / size
            p = c + size * np.array([-ty, tx]) / rot
            out.append(f"rotation about ({p[0]:.4g}, {p[1]:.4g})")
    return out


class Supports:
    """The supports of a model (mechanics/model.py): it reads the model's items, displacement space
    and, once compiled, its residual form and nodal loads."""

    def __init__(self, model):
        self.model = model

    @property
    def bcs(self) -> list:
        """The Dirichlet conditions of the items as they stand (a step may release a support)."""
        return [bc for item in self.model.items for bc in item.bcs]

    def _held(self, bcs) -> np.ndarray:
        """Which of this rank's owned (unrolled) dofs the Dirichlet conditions ``bcs`` hold."""
        work = compat.create_vector(self.model.residual_form)
        held = compat.constrained(work, bcs)
        work.destroy()
        return held

    def free_motions(self) -> list[str]:
        """The rigid-body motions that the Dirichlet conditions (as they stand) leave free, described
        in words; empty when they hold the body. In 3D the three translations and three rotations;
        in the plane: the translations and the rotation
        (the nullspace of the constrained dofs' rows of the three modes of :func:`rigid_motions`); in
        axisymmetry only the translation along the axis is rigid. Contact may hold a free motion
        once it closes; until it does, the tangent is singular along it. Collective."""
        m = self.model
        if m.kin.solid:
            modes, c, size = rigid_motions_3d(m.V)
            rows = modes[self._held(self.bcs).reshape(-1, 3)]
            G = m.comm.allreduce(rows.T @ rows, op=MPI.SUM)
            w, vecs = np.linalg.eigh(G)
            return describe_motions_3d(vecs[:, w <= 1e-10 * max(w.max(), 1.0)])
        modes, c, size = rigid_motions(m.V)
        rows = modes[self._held(self.bcs).reshape(-1, 2)]
        G = m.comm.allreduce(rows.T @ rows, op=MPI.SUM)
        if m.kin.axisymmetric:
            return [] if G[1, 1] > 0.0 else ["translation along the axis"]
        w, vecs = np.linalg.eigh(G)
        return describe_motions(vecs[:, w <= 1e-10 * max(w.max(), 1.0)], c, size)

    def release(self, item) -> None:
        """Take a support away (loads.Displacement.release): its force at the converged state,
        the residual at its dofs, becomes a nodal force that the step ramps down."""
        item.release(self.support_forces())

    def support_forces(self) -> np.ndarray:
        """This rank's owned entries of the residual R = f_int - f_ext (nodal forces included)
        without Dirichlet conditions, at the current state: at a constrained dof, the force the
        support supplies."""
        m = self.model
        b = compat.create_vector(m.residual_form)
        compat.assemble_vector(b, m.residual_form, add=m.nodal_loads())
        out = b.array.copy()
        b.destroy()
        return out

    def supports_of(self, name: str) -> list:
        """The supports (items of kind "support") of the tagged boundary ``name``, released or not."""
        return [it for it in self.model.items if it.kind == "support" and getattr(it, "boundary", None) == name]

    def reaction_forces(self, name: str) -> tuple[np.ndarray, np.ndarray]:
        """Reference positions (n, d) and forces (n, d) (d = 2, or 3 in 3D) that the supports of a tagged boundary exert
        on its nodes (this rank's owned nodes), from the residual at the current state
        (:meth:`support_forces`), in the components that those supports hold; zero in the others
        (at a corner node, the residual in a component that another boundary's support holds is
        that support's force) and once a step released them. Where supports of two boundaries hold
        the same component of a corner node, that node's force counts for both."""
        m = self.model
        R = self.support_forces()
        fdim = m.mesh.topology.dim - 1
        ft = m.meshdata.facet_tags
        facets = ft.indices[ft.values == m.meshdata.ds_id(name)]
        dofs = fem.locate_dofs_topological(m.V.sub(0), fdim, facets)
        bs = m.V.dofmap.index_map_bs
        nodes = np.unique(dofs // bs)
        nodes = nodes[nodes < m.V.dofmap.index_map.size_local]
        bcs = [bc for it in self.supports_of(name) for bc in it.bcs]
        held = self._held(bcs).reshape(-1, bs) if bcs else np.zeros((R.size // bs, bs), bool)
        f = np.where(held[nodes], R.reshape(-1, bs)[nodes], 0.0)
        return m.V.tabulate_dof_coordinates()[nodes, :bs], f

    def reaction(self, name: str) -> np.ndarray:
        """Total force (x, y; x, y, z in 3D) that the supports of a tagged boundary exert on it (all ranks;
        :meth:`reaction_forces`)."""
        return self.model.comm.allreduce(self.reaction_forces(name)[1].sum(axis=0), op=MPI.SUM)

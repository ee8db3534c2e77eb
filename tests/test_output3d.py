"""Output of 3D bodies: the VTK datasets (quadratic tetrahedra in VTK's node order, the displacement,
stress, plastic strain and fibre stress of a homogeneous deformation against its closed form), the
XDMF file, and a checkpoint that restarts a 3D run to the uninterrupted history."""
import shutil

import numpy as np
import pytest
from mpi4py import MPI

import comove_dolfinx as cm
from comove_dolfinx import geometry

# a displacement gradient with six distinct strain components (and a rotation part)
G = np.array([[2.0e-3, 1.2e-3, -0.4e-3], [0.2e-3, -0.6e-3, 0.9e-3], [0.8e-3, -0.3e-3, 1.1e-3]])
E, NU = 1000.0, 0.3
MU, K = E / (2 * (1 + NU)), E / (3 * (1 - 2 * NU))
SIGMA0, H = 0.5, 50.0                        # J2: yields at about a quarter of the final strain
# VTK's quadratic tetrahedron: its nodes 4-9 are the midpoints of these vertex pairs
VTK_EDGES = [(0, 1), (1, 2), (0, 2), (0, 3), (1, 3), (2, 3)]


def _pvd(folder):
    import xml.etree.ElementTree as ET
    return [(float(d.get("timestep")), folder / d.get("file"))
            for d in ET.parse(folder / "results.pvd").getroot().iter("DataSet")]


def _closed_form(plastic: bool):
    """(Cauchy stress, equivalent plastic strain) of the strain sym(G) under linear kinematics:
    elastic, or J2 with linear hardening on a proportional path (the radial return is exact)."""
    eps = 0.5 * (G + G.T)
    e = eps - np.trace(eps) / 3 * np.eye(3)
    e_eq = np.sqrt(2.0 / 3.0 * np.sum(e * e))
    p = max(0.0, (3 * MU * e_eq - SIGMA0) / (3 * MU + H)) if plastic else 0.0
    assert not plastic or p > 0.5 * e_eq          # well beyond yield
    s = 2 * MU * e * (1.0 - p / e_eq)            # q = 3 mu (e_eq - p) along e
    return s + K * np.trace(eps) * np.eye(3), p


def _homogeneous_job(tmp, order, plastic, writers):
    """A box whose six faces are held at u = t G X, two increments (linear kinematics)."""
    md = geometry.box(1.0, 0.5, 0.5, 0.25, order=order, comm=MPI.COMM_SELF, cache_dir=str(tmp))
    material = cm.J2(E, NU, cm.Hardening.linear(SIGMA0, H)) if plastic else cm.Elastic(E, NU)
    body = cm.Body(md, "solid", material, degree=order, update="small_strain")
    items = [cm.Displacement(face, field=lambda x, t: t * (G @ x))
             for face in ("left", "right", "front", "back", "bottom", "top")]
    probes = [cm.MaxPlasticStrain()] if plastic else []
    return cm.Job(body, items, [cm.Step(2)], probes=probes, writers=writers)


@pytest.mark.parametrize("order,plastic", [(1, False), (2, True)], ids=["p1-elastic", "p2-j2"])
def test_vtk_of_a_homogeneous_deformation(tmp_path, order, plastic):
    """Read back with meshio: tetrahedra (10-node, quadratic, for P2) whose mid-nodes sit halfway
    along VTK's edges; the points are the reference nodes, the displacement at each is G X, every
    cell's stress (all six components) and von Mises stress are the closed form's, and so is the
    plastic strain; the fibre stress is A . sigma . A along a 3D fibre A (F = I under linear kinematics)."""
    import meshio
    fibre = np.array([0.0, 0.6, 0.8])
    res = _homogeneous_job(tmp_path, order, plastic, [cm.VTK(tmp_path / "out", fibres=[("fibre", fibre)])]).run()
    assert res.completed
    steps = _pvd(tmp_path / "out")
    assert [t for t, _ in steps] == pytest.approx([0.5, 1.0])
    m = meshio.read(steps[-1][1])
    kind = {1: "tetra", 2: "tetra10"}[order]
    assert list(m.cells_dict) == [kind]
    cells, X = m.cells_dict[kind], m.points
    assert X.shape[1] == 3 and np.allclose(X.min(axis=0), 0.0) and np.allclose(X.max(axis=0), [1.0, 0.5, 0.5])
    if order == 2:
        for k, (a, b) in enumerate(VTK_EDGES):
            np.testing.assert_allclose(X[cells[:, 4 + k]], 0.5 * (X[cells[:, a]] + X[cells[:, b]]), atol=1e-12)
    vol = np.abs(np.einsum("ci,ci->c", np.cross(X[cells[:, 1]] - X[cells[:, 0]], X[cells[:, 2]] - X[cells[:, 0]]),
                           X[cells[:, 3]] - X[cells[:, 0]])) / 6.0
    assert vol.sum() == pytest.approx(0.25, rel=1e-12)        # the cells fill the box once
    np.testing.assert_allclose(m.point_data["displacement"], X @ G.T, atol=1e-12)
    sigma, p = _closed_form(plastic)
    S = m.cell_data["cauchy_stress_cell_avg"][0]
    assert S.shape == (len(cells), 9)
    scale = np.abs(sigma).max()
    np.testing.assert_allclose(S, np.tile(sigma.ravel(), (len(cells), 1)), rtol=0, atol=1e-8 * scale)
    s = sigma - np.trace(sigma) / 3 * np.eye(3)
    np.testing.assert_allclose(m.cell_data["von_mises_cell_avg"][0], np.sqrt(1.5 * np.sum(s * s)), rtol=1e-8)
    a = fibre                                    # linear kinematics: the fibre does not turn (F = I)
    np.testing.assert_allclose(m.cell_data["fibre_cell_avg"][0], a @ sigma @ a / (a @ a), rtol=1e-8)
    if plastic:
        ep = m.cell_data["plastic_strain_cell_avg"][0]
        np.testing.assert_allclose(ep, p, rtol=1e-8)
        assert res["max_plastic_strain"][-1] == pytest.approx(p, rel=1e-8)
    else:
        assert "plastic_strain_cell_avg" not in m.cell_data


_READ_XDMF = """
import sys, json, h5py
with h5py.File(sys.argv[1], "r") as f:
    steps = sorted(f["Function/cauchy_stress"].keys(), key=lambda t: float(t.replace("_", ".")))
    S = f["Function/cauchy_stress"][steps[-1]][...]
    X = f["Mesh/mesh/geometry"][...]
print(json.dumps({"S": S.tolist(), "steps": len(steps), "gdim": X.shape[1]}))
"""


def test_xdmf_of_a_homogeneous_deformation(tmp_path):
    """The XDMF writer on a 3D body: read back in a process of its own, a 3D geometry and, at the
    last increment, the closed form's stress in every cell."""
    import json
    import subprocess
    import sys
    res = _homogeneous_job(tmp_path, 2, False, [cm.XDMF(tmp_path / "results.xdmf")]).run()
    assert res.completed
    r = subprocess.run([sys.executable, "-c", _READ_XDMF, str(tmp_path / "results.h5")],
                       capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    data = json.loads(r.stdout)
    assert data["steps"] == 2 and data["gdim"] == 3
    S = np.array(data["S"]).reshape(-1, 9)
    sigma, _ = _closed_form(False)
    np.testing.assert_allclose(S, np.tile(sigma.ravel(), (len(S), 1)), rtol=0, atol=1e-8 * np.abs(sigma).max())


# -- checkpoint and restart -------------------------------------------------------------------------
def _bent_block(folder, checkpoint=None, stop_after=None, comm=MPI.COMM_WORLD, hexahedra=False, size=0.2,
                order=2, **body):
    """A J2 block held on its left face (P2 tetrahedra, or Q2 bricks with ``hexahedra``; ``body``:
    more of the Body's keywords), its right face moved down and along x at finite strain (sr_log),
    in 5 increments: plastic flow and a non-uniform state at every quadrature point."""
    from comove_dolfinx.io.checkpoint import Checkpoint
    from comove_dolfinx.io.writers import Writer
    md = geometry.box(1.0, 0.4, 0.4, size, order=order, comm=comm, cache_dir=str(folder), hexahedra=hexahedra)
    body = cm.Body(md, "solid", cm.J2(E, NU, cm.Hardening.linear(SIGMA0 * 10, H)), update="sr_log", **body)
    items = [cm.Fixed("left"), cm.Displacement("right", (0.02, -0.08, 0.03))]

    class Stop(Writer):
        def write(self, run, row, increment):
            if stop_after is not None and row["increment"] == stop_after:
                raise RuntimeError("stopped by the test")
    writers = ([Checkpoint(checkpoint, every=1, interval=0.0)] if checkpoint is not None else []) + [Stop()]
    probes = [cm.Reaction("left", "clamp", dim=3), cm.NodeDisplacement("tip", (1.0, 0.4, 0.4)),
              cm.MaxPlasticStrain()]
    return cm.Job(body, items, [cm.Step(5)], probes, writers=writers)


@pytest.mark.mpi
def test_a_3d_run_restarts_to_the_uninterrupted_history(mpi_tmp):
    """Stopped after increment 3 (a writer fails), then restarted from its checkpoint: the history
    (reactions, a corner's displacement, the plastic strain) and Newton's iterations are those of
    the run that was not stopped, to 1e-12, on however many ranks the test runs, and on one rank
    from the checkpoint of several."""
    full = _bent_block(mpi_tmp).run()
    assert full.completed and len(full) == 5 and full["max_plastic_strain"][-1] > 0.0
    folder = mpi_tmp / "checkpoint"
    with pytest.raises(RuntimeError, match="stopped by the test"):
        _bent_block(mpi_tmp, folder, stop_after=3).run()
    comm = MPI.COMM_WORLD
    kept = mpi_tmp / "checkpoint_3"          # (the restart below goes on saving into ``folder``)
    if comm.rank == 0:
        shutil.copytree(folder, kept)
    comm.barrier()
    again = _bent_block(mpi_tmp, folder).run(restart=folder)
    _same_history(again, full)
    if comm.size > 1:                        # the checkpoint of several ranks, restarted on one
        try:
            if comm.rank == 0:
                _same_history(_bent_block(mpi_tmp, comm=MPI.COMM_SELF).run(restart=kept), full)
        finally:
            comm.barrier()


def _same_history(res, ref):
    """``res`` has ``ref``'s Newton iterations and history, to 1e-12 of each column's largest value."""
    assert res.completed and res.newton_its == ref.newton_its
    for col in ("time", "load", "clamp_fx", "clamp_fy", "clamp_fz", "tip_ux", "tip_uy", "tip_uz",
                "max_plastic_strain"):
        r = np.asarray(ref[col], float)
        np.testing.assert_allclose(res[col], r, rtol=0, atol=1e-12 * max(np.abs(r).max(), 1e-300), err_msg=col)

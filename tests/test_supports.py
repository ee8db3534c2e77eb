"""Supports that leave a rigid-body motion free are found, named and warned about.

The truth is the geometry of the supports: a roller on a straight edge blocks the motion across the
edge and every rotation (which moves the edge's points along it by different amounts), a roller that
holds an edge along its own direction leaves free the translation across it and the rotations about
the points of its line, and in axisymmetry only the translation along the axis is rigid."""
import re

import pytest
from mpi4py import MPI

L, H = 2.0, 0.5


def _model(items, kind="plane_stress"):
    import comove_dolfinx as cm
    from comove_dolfinx.mechanics.model import Model
    body = cm.Body(cm.rectangle(L, H, 0.25, order=1), kind, cm.Elastic(100.0, 0.3), update="sr", degree=1)
    model = Model(body, items)
    model.finalize()
    return model


@pytest.mark.parametrize("supports, free", [
    ([("left", 0), ("bottom", 1)], []),                      # rollers on two edges hold it
    ([("left", None)], []),                                  # a clamped edge
    ([("left", 0)], ["translation in y"]),
    ([("bottom", 1)], ["translation in x"]),
    ([("left", 0), ("right", 0)], ["translation in y"]),
    ([], ["translation in x", "translation in y", "rotation"]),
])
def test_free_motions_in_the_plane(supports, free):
    import comove_dolfinx as cm
    model = _model([cm.Fixed(b, component=c) for b, c in supports])
    assert model.free_motions() == free


def test_a_roller_along_its_edge_leaves_the_rotations_about_its_line():
    """The bottom edge (y = 0) held in x only: two free motions, the translation in y and the
    rotations about the points of y = 0; whatever basis names them, a rotation's centre lies on
    that line (a translation in y added to a rotation about a point of it is a rotation about
    another point of it)."""
    import comove_dolfinx as cm
    free = _model([cm.Fixed("bottom", component=0)]).free_motions()
    assert len(free) == 2 and free.count("translation in y") <= 1      # two independent motions
    for motion in free:
        if motion.startswith("rotation about"):
            px, py = map(float, re.findall(r"[-+0-9.e]+", motion.split("about")[1]))
            assert abs(py) <= 1e-8 * L
        else:
            assert motion == "translation in y"


@pytest.mark.parametrize("supports, free", [
    ([("bottom", 1)], []),
    ([("left", 0)], ["translation along the axis"]),         # the axis r = 0 held radially
    ([], ["translation along the axis"]),
])
def test_free_motions_in_axisymmetry(supports, free):
    import comove_dolfinx as cm
    model = _model([cm.Fixed(b, component=c) for b, c in supports], kind="axisymmetric")
    assert model.free_motions() == free


@pytest.mark.mpi
def test_a_job_warns_once_of_a_free_motion(capsys):
    """A strip held in x at its left edge and pulled in x at its right: nothing holds it in y. The
    job warns once, at the start, on every rank alike, and its console says so; the strip with a
    roller under it too is not warned about."""
    import comove_dolfinx as cm
    from comove_dolfinx.io.writers import Console

    def job(items):
        body = cm.Body(cm.rectangle(L, H, 0.25, order=1), "plane_stress", cm.Elastic(100.0, 0.3), degree=1)
        return cm.Job(body, items, [cm.Step(2)], writers=[Console("strip")])
    res = job([cm.Fixed("left", component=0), cm.Displacement("right", 1e-4, component=0)]).run()
    said = [w for w in res.warnings if w.startswith("supports:")]
    assert len(said) == 1 and "translation in y" in said[0] and "add a support" in said[0]
    assert MPI.COMM_WORLD.allgather(said) == [said] * MPI.COMM_WORLD.size
    out = capsys.readouterr().out
    if MPI.COMM_WORLD.rank == 0:
        assert out.count("warning: supports:") == 1
    held = job([cm.Fixed("left", component=0), cm.Fixed("bottom", component=1),
                cm.Displacement("right", 1e-4, component=0)]).run()
    assert held.completed and not [w for w in held.warnings if w.startswith("supports:")]

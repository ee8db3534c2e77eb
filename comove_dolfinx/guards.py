"""A job's guards: warnings, each given once, of results that are computed but should be looked at.

* ``plastic strain``: a plastic strain beyond the hardening table's last point (the yield stress is
  extrapolated there);
* ``penetration``: a penetration that is a sizeable part of the smallest element;
* ``supports``: a step that starts with supports leaving a rigid-body motion free;
* ``linear solver``: MUMPS ran out of workspace and was given more (each time a new analysis and
  factorisation);
* ``locking``: plastic flow in a body of P1 displacements that must keep its volume (plane strain,
  axisymmetric, solid), which locks (docs/verification.md, the flat punch).

Each warning is a line "topic: what and the fix" appended to the run state's ``warnings``
(results.RunState); the topic, the words before the colon, says it was given.
"""
from __future__ import annotations

from mpi4py import MPI

#: a penetration beyond this fraction of the smallest cell is warned about
PENETRATION_WARNING = 0.02


def topics(run) -> set[str]:
    """What the run has warned of so far: each warning's topic, the words before its colon."""
    return {w.split(":")[0] for w in run.warnings}


def check_supports(run, step_index: int, step_count: int) -> None:
    """Warn (once) when the step ``step_index`` (from 0, of ``step_count``) starts with supports that
    leave a rigid-body motion free."""
    free = run.model.free_motions()
    if free and "supports" not in topics(run):
        when = f"from step {step_index + 1} " if step_count > 1 else ""
        run.warnings.append(
            f"supports: {when}the supports leave the body free to move rigidly ({', '.join(free)}); "
            "only contact can hold it there, and until it does the tangent is singular and that "
            "motion is left to round-off: add a support")


def check_workspace(run) -> None:
    """Warn (once) when MUMPS ran out of workspace and the solver gave it more (solver/linear.py,
    grow_workspace): each time costs a new analysis and factorisation."""
    grown = run.newton.workspace
    if grown is not None and "linear solver" not in topics(run):
        run.warnings.append(
            f"linear solver: MUMPS's workspace was too small for a tangent and was raised to {grown} % "
            "over its estimate, each time with a new analysis and factorisation: start with "
            f"-comove_mat_mumps_icntl_14 {grown} (the solver's PETSc options, docs/performance.md)")


def check_increment(run, row: dict, contacts, penetration_warning: float = PENETRATION_WARNING) -> None:
    """Warn (once each) of a plastic strain beyond the hardening table and of a penetration beyond
    ``penetration_warning`` times the smallest element, after the increment of the history row
    ``row``; and of a linear solver that had to be given more workspace. Collective."""
    check_workspace(run)
    said = topics(run)
    if "plastic strain" not in said:
        _check_plastic_strain(run, row)
    if "locking" not in said:
        _check_locking(run, row)
    if contacts and "penetration" not in said:
        _check_penetration(run, row, contacts, penetration_warning)


def _check_plastic_strain(run, row: dict) -> None:
    m = run.model
    if m.plastic is None:
        return
    last = m.plastic.hardening.strain[-1]
    p = m.comm.allreduce(float(m.p.x.array.max()) if m.p.x.array.size else 0.0, op=MPI.MAX)
    if len(m.plastic.hardening.strain) > 1 and p > last:
        run.warnings.append(
            f"plastic strain: {p:.3g} at increment {row['increment']} (time {row['time']:.4g}) is beyond the "
            f"hardening table's last point ({last:.3g}), where the yield stress is extrapolated "
            f"(slope {m.plastic.hardening.tail_slope:.3g}): extend the table")


def _check_locking(run, row: dict) -> None:
    m = run.model
    if m.plastic is None or m.degree != 1 or m.body.kind == "plane_stress" or m.volume is not None:
        return
    p = m.comm.allreduce(float(m.p.x.array.max()) if m.p.x.array.size else 0.0, op=MPI.MAX)
    if p > 0.0:
        from . import compat
        bricks = compat.cell_name(m.mesh) in ("quadrilateral", "hexahedron")
        run.warnings.append(
            f"locking: the body yields (increment {row['increment']}) with P1 displacements, which lock in "
            "plastic flow (it keeps the volume): a flat punch's limit load comes out 11 to 16 % high on a "
            "16 x 16 mesh (docs/verification.md): use degree=2" + (" or fbar=True" if bricks else ""))


def _check_penetration(run, row: dict, contacts, fraction: float) -> None:
    m = run.model
    h = m.comm.allreduce(min(float(c.h.x.array.min()) for c in contacts), op=MPI.MIN)
    pen = run.contact_stats["max_penetration"]
    if pen > fraction * h:
        run.warnings.append(
            f"penetration: {pen:.3g} at increment {row['increment']} is {100 * pen / h:.0f} % of the smallest "
            "element: raise gamma0, use nitsche, or refine the mesh")

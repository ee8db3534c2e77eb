"""The command line of the benchmarks: ``python -m comove_dolfinx.benchmarks STUDY [options]``.

STUDY is one of dolfinx, floor, parts, solvers, scale, slopes, krylov, solid, output (the modules of this package say
what each measures). Options: ``--out DIR`` (results/cost), ``--repeats N``, ``--increments N``, ``--sizes``
(comma-separated mesh sizes of the ring; solid: of the bent block), ``--solvers`` (comma-separated configurations of
:data:`~comove_dolfinx.benchmarks.linear_solvers.SOLVERS`; for krylov the names of
``NewtonSettings.linear_solver``, also for solid), ``--scenes`` (scale; krylov: one scene; output: scenes and
demos by name) and ``--set key=value`` (repeatable: a parameter of the ring scene for dolfinx, floor and
slopes). A bad option or scene parameter is a one-line usage error before any run.
"""
from __future__ import annotations

import argparse
import logging
import pathlib

from ..presets import SceneError, get_scene

PROG = "python -m comove_dolfinx.benchmarks"
STUDIES = ("dolfinx", "floor", "parts", "solvers", "scale", "slopes", "krylov", "solid", "output")


def _parser(prog: str) -> argparse.ArgumentParser:
    """The command's options."""
    p = argparse.ArgumentParser(prog=prog, description="What a Newton iteration costs, against plain "
                                "dolfinx and a linear-elastic floor; solvers; ranks (docs/performance.md).")
    p.add_argument("study", choices=STUDIES)
    p.add_argument("--out", default="results/cost")
    p.add_argument("--repeats", type=int, default=None,
                   help="runs per figure (dolfinx: 5 pairs; floor, solvers, scale: 3) or calls per timing (parts: 40)")
    p.add_argument("--increments", type=int, default=None, help="nominal increments of each short run")
    p.add_argument("--sizes", default=None, help="comma-separated mesh sizes (dolfinx, floor, solvers, slopes, krylov)")
    p.add_argument("--solvers", default=None, help="comma-separated configurations (solvers, scale)")
    p.add_argument("--scenes", default=None, help="comma-separated scenes (scale: ring,plate; "
                   "krylov: one scene, plate; output: scenes and demos by name)")
    p.add_argument("--set", action="append", default=[], metavar="KEY=VALUE", dest="overrides",
                   help="a parameter of the ring scene for its runs (dolfinx, floor, slopes), e.g. predictor=linear")
    return p


def _check(p: argparse.ArgumentParser, a: argparse.Namespace, ranks: int) -> None:
    """Usage errors (argparse's exit 2 with one line) for what the studies cannot take."""
    if a.overrides and a.study not in ("dolfinx", "floor", "slopes"):
        p.error("--set applies to the dolfinx, floor and slopes studies only")
    if a.study == "krylov" and a.scenes and "," in a.scenes:
        p.error("krylov takes one scene (--scenes plate)")
    if a.study == "output" and a.scenes:
        from .output_share import cases
        unknown = [n for n in a.scenes.split(",") if not cases([n])]
        if unknown:
            p.error(f"output: unknown case(s) {', '.join(unknown)}: choose among {', '.join(cases())}")
    if a.study in ("parts", "dolfinx", "output") and ranks > 1:
        p.error(f"{a.study} times one rank: run it without mpirun")
    try:
        get_scene("ring", a.overrides)
    except SceneError as err:
        p.error(str(err))


def _run(a: argparse.Namespace, out: pathlib.Path) -> None:
    """The study ``a.study`` with the options given (the others at the study's defaults)."""
    kw = {"repeats": a.repeats} if a.repeats else {}
    if a.increments:
        kw["increments"] = a.increments
    if a.sizes and a.study != "scale":
        kw["sizes"] = tuple(float(s) for s in a.sizes.split(","))
    if a.study == "dolfinx":
        from .iteration_dolfinx import against_dolfinx
        against_dolfinx(out, overrides=tuple(a.overrides), **kw)
    elif a.study == "floor":
        from .iteration_floor import floor
        floor(out, overrides=tuple(a.overrides), **kw)
    elif a.study == "parts":
        from .loop_parts import parts
        parts(out, **kw)
    elif a.study == "slopes":
        from .line_search import slopes
        kw.pop("repeats", None)
        slopes(out, overrides=tuple(a.overrides), **kw)
    elif a.study == "solvers":
        from .linear_solvers import solvers
        solvers(out, names=a.solvers.split(",") if a.solvers else None, **kw)
    elif a.study == "solid":
        from .solid3d import NAMES, solid
        solid(out, names=tuple(a.solvers.split(",")) if a.solvers else NAMES, **kw)
    elif a.study == "output":
        from .output_share import output
        output(out, repeats=a.repeats or 3, names=a.scenes.split(",") if a.scenes else None)
    elif a.study == "krylov":
        from .multigrid import NAMES, krylov
        names = tuple(a.solvers.split(",")) if a.solvers else NAMES
        krylov(out, scene=a.scenes or "plate", names=names, **kw)
    else:
        from .ranks import SCALE, scale
        names = tuple(a.solvers.split(",")) if a.solvers else ("mumps_auto", "gmres_gamg")
        scenes = (a.scenes or "ring,plate").split(",")
        scale(out, scenes={k: SCALE[k] for k in scenes}, solver_names=names, **kw)


def main(argv=None, prog: str = PROG) -> None:
    """Parse ``argv`` (default sys.argv), check it, and run the study into ``--out``."""
    from mpi4py import MPI
    comm = MPI.COMM_WORLD
    p = _parser(prog)
    a = p.parse_args(argv)
    _check(p, a, comm.size)
    logging.disable(logging.INFO)
    out = pathlib.Path(a.out)
    if comm.rank == 0:
        out.mkdir(parents=True, exist_ok=True)
    comm.barrier()
    _run(a, out)

"""The ``comove`` command.

    comove run SCENE --out DIR [--set key=value ...] [-v] [--no-progress]
    comove scenes
"""
from __future__ import annotations

import argparse
import logging
import sys


def _quiet_jit() -> None:
    # ffcx/cffi report every compilation through the root logger at INFO level
    logging.disable(logging.INFO)


def _scenes() -> int:
    from .scenes import SCENES
    for name, cls in SCENES.items():
        print(f"{name}: {cls.summary}")
        for key, default, doc in cls.parameters():
            print(f"    {key:<14} {default!s:<10} {doc}")
    return 0


def _run(args) -> int:
    from mpi4py import MPI

    from .contact import ContactError
    from .geometry import MeshError
    from .job import run_scene
    from .materials import MaterialError
    from .scenes import SceneError, get_scene

    try:
        scene = get_scene(args.scene, args.set)
    except (SceneError, MaterialError) as err:
        if MPI.COMM_WORLD.rank == 0:
            print(f"comove: {err}", file=sys.stderr)
        return 2
    if args.verbose:
        logging.disable(logging.NOTSET)
        logger = logging.getLogger("comove")
        logger.setLevel(logging.INFO)
        logger.propagate = False           # the JIT libraries give the root logger a handler
        if MPI.COMM_WORLD.rank == 0:
            logger.addHandler(logging.StreamHandler(sys.stdout))
        logging.getLogger().setLevel(logging.WARNING)
    try:
        result = run_scene(scene, args.out, progress=not args.no_progress)
    except (MeshError, SceneError, MaterialError, ContactError) as err:
        if MPI.COMM_WORLD.rank == 0:
            print(f"comove: {err}", file=sys.stderr)
        return 2
    return 0 if result.completed else 1


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(
        prog="comove", description="Large deformation of solids pressed against rigid obstacles "
        "by the co-moving S-R method (dolfinx 0.5.2).")
    sub = parser.add_subparsers(dest="command", required=True)
    run = sub.add_parser("run", help="run a scene")
    run.add_argument("scene", help="scene name (see 'comove scenes')")
    run.add_argument("--out", required=True, help="output folder")
    run.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                     help="override a scene parameter (repeatable)")
    run.add_argument("-v", "--verbose", action="store_true", help="log every Newton iteration")
    run.add_argument("--no-progress", action="store_true", help="no progress bar")
    sub.add_parser("scenes", help="list the scenes and their parameters with defaults")
    args = parser.parse_args(argv)
    _quiet_jit()
    from . import check_platform
    check_platform()
    return _scenes() if args.command == "scenes" else _run(args)


if __name__ == "__main__":
    sys.exit(main())

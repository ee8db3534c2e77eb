"""The ``comove`` command.

    comove run SCENE --out DIR [--set key=value ...] [-v] [--no-progress]
    comove run PROBLEM.toml --out DIR [-v] [--no-progress]
    comove run ... --restart [--allow-change KEY[,KEY...]]
    comove scenes
    comove verify NAME|all --out DIR [--small]

Exit codes: 0 the run completed; 1 it did not (an increment could not be solved, or the run failed:
a full disk, an error of PETSc); 2 bad input (one line naming the value and the fix, before dolfinx
is loaded where possible); 130 Ctrl-C and 143 SIGTERM, at any moment from the start of the command
(one line, no traceback; run.json, if the run wrote one, says ``interrupted``).
"""
from __future__ import annotations

import sys          # (a builtin module: loaded already; everything else is imported after main()
                    # has taken Ctrl-C and SIGTERM, command_signals.py)

#: seconds between checkpoints at least (the last increment is saved when a run ends): a restart
#: after a kill -9 repeats at most this much work, and a short run writes one checkpoint
CHECKPOINT_INTERVAL = 5.0


def _quiet_jit() -> None:
    # ffcx/cffi report every compilation through the root logger at INFO level
    import logging
    logging.disable(logging.INFO)


def _scenes() -> int:
    from .presets import SCENES
    for name, cls in SCENES.items():
        print(f"{name}: {cls.summary}")
        for key, default, doc in cls.parameters():
            print(f"    {key:<14} {default!s:<10} {doc}")
    return 0


def _verbose(comm) -> None:
    import logging
    logging.disable(logging.NOTSET)
    logger = logging.getLogger("comove")
    logger.setLevel(logging.INFO)
    logger.propagate = False           # the JIT libraries give the root logger a handler
    if comm.rank == 0:
        logger.addHandler(logging.StreamHandler(sys.stdout))
    logging.getLogger().setLevel(logging.WARNING)


def run_scene(scene, out_dir, comm=None, progress: bool = False, newton=None, overwrite: bool = False,
              restart: bool = False, checkpoint_every: int = 1, checkpoint_interval: float = CHECKPOINT_INTERVAL,
              allow=()):
    """Run a preset ``scene`` into the folder ``out_dir`` (history.csv, results.pvd with one .vtu per
    increment, run.json, the console's lines); returns the :class:`Results`. ``newton``: settings
    instead of the scene's; ``overwrite``: replace the results of an earlier run there; ``restart``:
    go on from its checkpoint, refused (RestartError) if the checkpoint is of another scene or of
    other parameters, unless ``allow`` names them and the scene can take the change (io/restart.py)."""
    import dataclasses
    import pathlib

    from mpi4py import MPI

    from . import command_signals, startup
    from .io import VTK, Console, HistoryCSV, RunInfo
    from .io import restart as restarts
    from .io.checkpoint import Checkpoint
    from .io.folder import RunFolder

    comm = comm or MPI.COMM_WORLD
    out = pathlib.Path(out_dir)
    identity = restarts.scene_identity(scene)
    point = restarts.restart_point(out, identity, allow, scene, comm) if restart else None
    with RunFolder(out, overwrite, comm, restart):
        with startup.part("mesh"):
            md = scene.mesh_data(comm)
        # the dataset before its history row: a kill between them leaves no row without dataset
        writers = [VTK(out, fibres=scene.fibres()), HistoryCSV(out / "history.csv"),
                   RunInfo(out / "run.json", {"scene": scene.name, **dataclasses.asdict(scene)},
                           identity=identity),
                   Console(scene.name, scene.columns),
                   Checkpoint(out / "checkpoint", checkpoint_every, checkpoint_interval, identity=identity),
                   command_signals.writer()]
        job = scene.job(md, writers)
        if newton is not None:
            job.newton = newton
        return job.run(progress=progress, restart=point)


def _errors():
    from .checks import SettingsError
    from .contact import ContactError
    from .geometry import MeshError
    from .io.checkpoint import CheckpointError
    from .io.folder import FolderError
    from .io.restart import RestartError
    from .job import JobError
    from .loads import ItemError
    from .mechanics.body import BodyError
    from .mechanics.material_data import MaterialError
    from .presets import SceneError
    from .probes import ProbeError
    from .solver.linear import SolverOptionError
    return (MeshError, SceneError, MaterialError, ContactError, BodyError, ItemError, JobError, ProbeError,
            FolderError, CheckpointError, RestartError, SettingsError)


def run_problem(path, out_dir, comm=None, progress: bool = False, overwrite: bool = False,
                restart: bool = False, checkpoint_every: int = 1, checkpoint_interval: float = CHECKPOINT_INTERVAL,
                allow=()):
    """Run a problem file (problem.py) into ``out_dir``, with the writers of the scenes; a restart is
    refused if the checkpoint is of another file or of other content, unless ``allow`` has
    ``problem``."""
    import pathlib

    from mpi4py import MPI

    from . import command_signals, problem
    from .io import VTK, Console, HistoryCSV, RunInfo
    from .io import restart as restarts
    from .io.checkpoint import Checkpoint
    from .io.folder import RunFolder

    comm = comm or MPI.COMM_WORLD
    data = problem.read(path)
    out = pathlib.Path(out_dir)
    identity = restarts.problem_identity(path, data)
    point = restarts.restart_point(out, identity, allow, None, comm) if restart else None
    with RunFolder(out, overwrite, comm, restart):
        writers = [VTK(out), HistoryCSV(out / "history.csv"),
                   RunInfo(out / "run.json", {"problem": str(path), **data}, identity=identity),
                   Console(pathlib.Path(path).stem),
                   Checkpoint(out / "checkpoint", checkpoint_every, checkpoint_interval, identity=identity),
                   command_signals.writer()]
        return problem.build(data, comm, writers).run(progress=progress, restart=point)


def _failures():
    """The exceptions of a run that fails for a reason outside the program (a full disk, an error
    that PETSc reports): one line, exit code 1."""
    from petsc4py import PETSc
    return (OSError, PETSc.Error)


def _run(args) -> int:
    from mpi4py import MPI

    from .io.folder import failure_line
    from .io.restart import allowed
    from .presets import get_scene
    from .problem import ProblemError

    comm = MPI.COMM_WORLD
    errors = _errors() + (ProblemError,)
    problem = args.scene.endswith(".toml")

    def fail(err, code=2) -> int:
        if comm.rank == 0:
            lines = str(err).strip().splitlines() or [""]      # (PETSc's messages: its stack between)
            print(f"comove: {lines[0]}" + (f" ... {lines[-1].strip()}" if len(lines) > 1 else ""),
                  file=sys.stderr)
        return code

    if problem and args.set:
        return fail("--set applies to scenes; edit the problem file instead")
    try:
        scene = None if problem else get_scene(args.scene, args.set)
    except errors as err:
        return fail(err)
    if args.verbose:
        _verbose(comm)
    kw = dict(progress=not args.no_progress, overwrite=args.overwrite, restart=args.restart,
              checkpoint_every=args.checkpoint_every, checkpoint_interval=args.checkpoint_interval,
              allow=allowed(args.allow_change))
    try:
        result = run_problem(args.scene, args.out, **kw) if problem else run_scene(scene, args.out, **kw)
    except errors as err:
        return fail(err)
    except _failures() as err:
        return fail(failure_line(err), 1)
    if not result.completed and comm.rank == 0:
        print(f"comove: {result.message}", file=sys.stderr)
    return 0 if result.completed else 1


def main(argv=None) -> int:
    """The command (``argv``: its arguments, else the process's). Ctrl-C and SIGTERM end it with
    one line at any moment, also while it imports or builds (exit codes 130 and 143,
    command_signals.py); without ``argv`` (the process's command) they are ignored once the command
    has returned, while the process shuts MPI and PETSc down."""
    from . import command_signals as cs
    previous, hook = cs.handle(), sys.unraisablehook
    from . import startup
    startup.begin()                      # (the CPU seconds so far: the interpreter's start)
    cs.SIGNALLED.clear()
    sys.unraisablehook = cs.quiet_after_signal
    parsed: list = []                    # the parsed arguments, once they are
    try:
        return _main(argv, parsed)
    except KeyboardInterrupt as err:
        return cs.end(err, parsed[0] if parsed else None, _rank(), _ranks())
    except Exception as err:
        if not cs.SIGNALLED:             # a bug: its traceback
            raise
        # an import that a signal cut short fails so (numpy's C extension: ImportError)
        return cs.end(err, parsed[0] if parsed else None, _rank(), _ranks())
    finally:
        cs.restore(previous, ignore=argv is None)
        if argv is not None:
            sys.unraisablehook = hook


def _parser():
    """The command's arguments."""
    import argparse
    parser = argparse.ArgumentParser(
        prog="comove", description="Large deformation of solids pressed against rigid obstacles "
        "by the co-moving S-R method.")
    from . import __version__
    parser.add_argument("--version", action="version", version=f"comove {__version__}")
    sub = parser.add_subparsers(dest="command", required=True)
    run = sub.add_parser("run", help="run a scene or a problem file")
    run.add_argument("scene", help="scene name (see 'comove scenes') or a problem file (.toml, docs/api.md)")
    run.add_argument("--out", required=True, help="output folder")
    run.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                     help="override a scene parameter (repeatable)")
    run.add_argument("-v", "--verbose", action="store_true", help="log every Newton iteration")
    run.add_argument("--no-progress", action="store_true", help="no progress bar")
    run.add_argument("--overwrite", action="store_true",
                     help="replace the results of an earlier run in the --out folder")
    run.add_argument("--restart", action="store_true",
                     help="go on from the last checkpoint in the --out folder (same scene and "
                          "parameters, any number of ranks)")
    run.add_argument("--allow-change", action="append", default=[], metavar="KEY[,KEY...]",
                     help="with --restart: parameters that may differ from the checkpoint's (e.g. "
                          "delta_max for a larger final load; 'problem' for a problem file's content)")
    run.add_argument("--checkpoint-every", type=int, default=1, metavar="K",
                     help="save the state every K converged increments (default 1)")
    run.add_argument("--checkpoint-interval", type=float, default=CHECKPOINT_INTERVAL, metavar="S",
                     help="and no sooner than S seconds after the last save; the last increment is "
                          f"always saved when the run ends (default {CHECKPOINT_INTERVAL:g}; 0: every K-th)")
    sub.add_parser("scenes", help="list the scenes and their parameters with defaults")
    st = sub.add_parser("study", help="speed against accuracy across methods (docs/study.md)")
    st.add_argument("scene", help="elastica, beam, plate, ring or all")
    st.add_argument("--out", default="results/study", help="output folder (default results/study)")
    st.add_argument("--repeat", type=int, default=3, help="runs of each case, for the CPU time's spread")
    st.add_argument("--jobs", type=int, default=2, help="runs at a time (default 2)")
    st.add_argument("--quick", action="store_true", help="the updates' sweeps only, fewer increments")
    st.add_argument("--replot", action="store_true", help="charts and summaries again from the saved runs")
    st.add_argument("--executor", default="auto", help="local (processes here), mpi (under "
                    "mpiexec -n N python -m mpi4py.futures) or auto (default: mpi when started so)")
    ve = sub.add_parser("verify", help="the verification cases against published results (docs/verification.md)")
    ve.add_argument("case", help="a case's name, or all")
    ve.add_argument("--out", default="results/verify", help="output folder (default results/verify)")
    ve.add_argument("--small", action="store_true", help="the coarse meshes of the test suite")
    return parser


def _main(argv, parsed: list) -> int:
    from . import startup
    with startup.part("arguments and checks"):
        parser = _parser()
        args = parser.parse_args(argv)
        parsed.append(args)
        if args.command == "study":
            return _study(args)
        if args.command == "verify":
            return _verify(args)
        err = _check_early(args) if args.command == "run" else None
    if err is not None:
        if _rank() == 0:
            print(f"comove: {err}", file=sys.stderr)
        return 2
    with startup.part("imports"):
        _import(args.command == "run")
    if args.command == "scenes":
        try:
            code = _scenes()
            sys.stdout.flush()           # here, not at exit, where the error could not be caught
            return code
        except BrokenPipeError:          # the listing piped into head and the like, which closed early
            import os
            os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
            return 0
    return _run(args)


def _import(run: bool) -> None:
    """dolfinx (with the signals held: its bindings cannot take one while they load), the platform
    checked, and for a run the package's modules it uses."""
    _quiet_jit()
    from . import check_platform, command_signals, startup
    command_signals.own_signals()
    with startup.versions_without_pkg_resources():
        command_signals.import_bindings()
    check_platform()
    if run:
        from . import geometry, job  # noqa: F401
        from .io import checkpoint, vtk, writers  # noqa: F401


def _study(args) -> int:
    """The study runs every case as its own ``comove run`` process: nothing heavy is loaded here."""
    import pathlib

    from .study import PLANS, executors
    from .study import main as study_main
    scenes = list(PLANS) if args.scene == "all" else [args.scene]
    err = None
    executor, why = executors.choose(args.executor)     # (local or mpi; a launcher without a pool)
    if why is not None:
        err = why
    elif any(s not in PLANS for s in scenes):
        err = f"study {args.scene!r}: choose one of {', '.join(PLANS)} or all"
    elif args.repeat < 1 or args.jobs < 1:
        err = f"--repeat {args.repeat} --jobs {args.jobs}: give whole numbers >= 1"
    elif not args.out.strip():
        err = "--out '': give the output folder"
    out = pathlib.Path(args.out)
    if err is None:
        try:
            out.mkdir(parents=True, exist_ok=True)
        except OSError as e:
            err = f"--out {args.out}: cannot make the folder ({e.strerror}); choose another place"
    if err is not None:
        print(f"comove: {err}", file=sys.stderr)
        return 2
    return study_main(scenes, out, args.repeat, args.jobs, args.quick, args.replot, executor)


def _verify(args) -> int:
    """Each case runs as a process of its own (verify/runner.py): nothing heavy is loaded here."""
    import pathlib

    from .verify import runner
    names, err = [], None
    if _ranks() > 1:
        err = "verify: it runs each case as a process of its own: start it without mpirun"
    else:
        names, err = runner.check_args(args.case, args.out)
    if err is not None:
        print(f"comove: {err}", file=sys.stderr)
        return 2
    return runner.main(names, pathlib.Path(args.out), args.small)


def _ranks() -> int:
    """The number of MPI ranks from the launcher's environment (before MPI is loaded)."""
    import os
    for var in ("OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_SIZE"):
        if var in os.environ:
            return int(os.environ[var])
    return 1


def _rank() -> int:
    """This process's MPI rank from the launcher's environment (before MPI is loaded)."""
    import os
    for var in ("OMPI_COMM_WORLD_RANK", "PMI_RANK", "PMIX_RANK"):
        if var in os.environ:
            return int(os.environ[var])
    return 0


def _check_early(args):
    """The run's arguments checked before dolfinx is loaded: the scene and its parameters, or the
    problem file, and the output folder (the run checks it again when it takes it). The message,
    or None."""
    from .mechanics.material_data import MaterialError
    from .presets import SceneError, get_scene
    from .problem import ProblemError, read
    if not args.out.strip():
        return "--out '': give the output folder"
    if args.checkpoint_every < 1:
        return f"--checkpoint-every {args.checkpoint_every}: give a whole number >= 1"
    if not 0.0 <= args.checkpoint_interval < float("inf"):
        return f"--checkpoint-interval {args.checkpoint_interval}: give a number of seconds >= 0"
    if args.restart and args.overwrite:
        return "--restart and --overwrite: choose one (go on from the checkpoint, or start afresh)"
    if args.allow_change and not args.restart:
        return "--allow-change applies to --restart: drop it, or add --restart"
    try:
        if args.scene.endswith(".toml"):
            scene, data = None, read(args.scene)
        else:
            scene, data = get_scene(args.scene, args.set), None
    except (SceneError, MaterialError, ProblemError) as err:
        return err
    from .io.folder import check
    why = check(args.out, args.overwrite, args.restart, lock=_rank() == 0)
    if why is None and args.restart:
        from .io import restart
        why = restart.early_error(args.out, args.scene, scene, data, restart.allowed(args.allow_change))
    return why


if __name__ == "__main__":
    sys.exit(main())

"""The ``forming`` command: ``forming run SCENE``, ``forming study``, ``forming bench`` and
``forming mesh SCENE -o FILE``.

Arguments after a lone ``--`` are PETSc options (``-- -ksp_type preonly -pc_type lu``) and take
precedence over the scene's ``solver.petsc_options``.
"""
from __future__ import annotations

import argparse
import logging
import signal
import sys
from pathlib import Path

from forming_fenicsx.core.errors import SceneError
from forming_fenicsx.core.jit_cache import exact_lookup
from forming_fenicsx.core.numbers import fraction, is_number

log = logging.getLogger("forming_fenicsx")


def petsc_options_from_args(args: list[str]) -> dict[str, str]:
    """``-key value`` / ``-flag`` pairs to a dict without the leading dash."""
    options: dict[str, str] = {}
    i = 0
    while i < len(args):
        key = args[i]
        if not key.startswith("-") or len(key) < 2:
            raise SceneError(key, "PETSc options after '--' must look like -name [value]")
        value = ""
        if i + 1 < len(args) and not (args[i + 1].startswith("-") and not is_number(args[i + 1])):
            value = args[i + 1]
            i += 1
        options[key.lstrip("-")] = value
        i += 1
    return options


def accuracy_override(text: str) -> str:
    """``--accuracy 1%`` or ``--accuracy 0.01`` as the override accuracy.target=0.01."""
    try:
        value = fraction(text)
    except ValueError:
        raise SceneError("--accuracy",
                         f"must be a relative error such as 1% or 0.01; got {text!r}") from None
    return f"accuracy.target={value!r}"


def _is_study(path: str) -> bool:
    """A study file has a [study] table (scene files have none)."""
    import tomllib

    try:
        return "study" in tomllib.loads(Path(path).read_text())
    except (OSError, ValueError):
        return False


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="forming",
                                     description="Steady-state metal forming (Angelov 2014).")
    sub = parser.add_subparsers(dest="command", required=True)
    run = sub.add_parser("run", help="solve a scene and write its results")
    run.add_argument("scene", help="scene TOML file")
    run.add_argument("--out", help="output folder (default: results/<scene name>)")
    run.add_argument("--set", action="append", default=[], metavar="SECTION.KEY=VALUE",
                     help="override a scene value (repeatable)")
    run.add_argument("--quiet", action="store_true", help="log warnings only")
    run.add_argument("--force", action="store_true", help="replace an existing output folder")
    run.add_argument("--restart", metavar="DIR",
                     help="start from the velocity of a previous run of the same mesh")
    run.add_argument("--accuracy", metavar="TARGET",
                     help="refine the mesh until the estimated relative error of the main quantity "
                     "is below TARGET (1%%, 0.3%% or 0.01): accuracy.target")
    study = sub.add_parser("study", help="run a grid of variations of a scene: a design sweep "
                           "(quantities against a parameter, optimum) or errors against costs")
    study.add_argument("scene", help="scene TOML file, or a study file "
                       "(a [study] table: scene, vary, set, quantity)")
    study.add_argument("--vary", action="append", default=[], metavar="SECTION.KEY=V1,V2,...",
                       help="a key and its values (repeatable; the grid is every combination)")
    study.add_argument("--out", help="output folder (default: results/<scene name>_study)")
    study.add_argument("--quantity", action="append", default=[], metavar="KEY[,KEY...]",
                       help="summary keys to measure (repeatable or comma-separated; default: "
                       "ram_pressure or mean_die_pressure)")
    study.add_argument("--keep-runs", action="store_true",
                       help="keep each run's output folder (summary, fields, figures) in "
                       "OUT/runs/")
    study.add_argument("--set", action="append", default=[], metavar="SECTION.KEY=VALUE")
    study.add_argument("--quiet", action="store_true", help="log warnings only")
    sub.add_parser("bench", help="the nonlinear solvers side by side on both examples: solves, "
                   "times, memory (forming bench --help)", add_help=False)
    mesh = sub.add_parser("mesh", help="write the scene's mesh as a Gmsh .msh file")
    mesh.add_argument("scene", help="scene TOML file")
    mesh.add_argument("-o", "--output", required=True, help="the .msh file to write")
    mesh.add_argument("--set", action="append", default=[], metavar="SECTION.KEY=VALUE")
    return parser


def _not_a_compiler_line(record: logging.LogRecord) -> bool:
    """False for the C compiler's build lines: when FFCx compiles a form, setuptools logs every
    compile and link command through the root logger, whose handler FFCx installed (about 30 lines
    a run); and for FFCx's advice on a form's many integration points (its UserWarning, logged
    through py.warnings when a 3D form of the forms' own degree compiles: "Number of integration
    points per cell is: 121. Consider using 'quadrature_degree'")."""
    if record.name == "py.warnings" and "Number of integration points" in record.getMessage():
        return False
    return not ("distutils" in record.pathname or "setuptools" in record.pathname)


def configure_logging(quiet: bool, rank: int) -> None:
    """The application's own handler, on rank 0 only; the root logger's level is left alone, and
    its handlers drop the compiler's build lines (_not_a_compiler_line)."""
    for handler in logging.getLogger().handlers:
        if _not_a_compiler_line not in handler.filters:
            handler.addFilter(_not_a_compiler_line)
    log.propagate = False
    handler = logging.StreamHandler(sys.stdout) if rank == 0 else logging.NullHandler()
    handler.setFormatter(logging.Formatter("%(message)s"))
    log.addHandler(handler)
    log.setLevel(logging.WARNING if quiet else logging.INFO)
    # every iterate's line, unless the command quiets them again (a study: one line per run)
    logging.getLogger("forming_fenicsx.solvers").setLevel(logging.NOTSET)


LOGGERS = ("forming_fenicsx", "forming_fenicsx.solvers")  # the ones configure_logging sets


def main(argv: list[str] | None = None) -> int:
    """The `forming` command; the loggers it configures are as before when it returns (a command
    run within a process, as the tests do, leaves no logging state behind), and so is FFCx's
    lookup of compiled forms (core/jit_cache.py while it runs)."""
    loggers = [logging.getLogger(name) for name in LOGGERS]
    saved = [(logger.level, logger.propagate, list(logger.handlers)) for logger in loggers]
    try:
        with exact_lookup():
            return _main(argv)
    finally:
        for logger, (level, propagate, handlers) in zip(loggers, saved, strict=True):
            logger.setLevel(level)
            logger.propagate = propagate
            logger.handlers[:] = handlers


def _main(argv: list[str] | None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    if argv[:1] == ["bench"]:  # its own parser: every case runs in a child process
        from forming_fenicsx.app.bench import main as bench

        return bench(argv[1:])
    petsc_args: list[str] = []
    if "--" in argv:
        split = argv.index("--")
        argv, petsc_args = argv[:split], argv[split + 1:]
    args = _parser().parse_args(argv)

    from mpi4py import MPI

    from forming_fenicsx.config.loader import load_scene, read_scene_data

    comm = MPI.COMM_WORLD
    try:
        if args.command == "study":
            from forming_fenicsx.app.study import load_study, parse_quantities, run_study

            configure_logging(args.quiet, comm.rank)
            # one progress line per run
            logging.getLogger("forming_fenicsx.solvers").setLevel(logging.WARNING)
            study_file = _is_study(args.scene)
            data, vary, quantities = load_study(args.scene, args.set) if study_file else \
                (read_scene_data(args.scene, args.set), [], [])
            if not vary + args.vary:
                raise SceneError("--vary", "a study needs at least one --vary (or a study file)")
            stem = Path(args.scene).name.split(".")[0]
            out = (Path(args.out) if args.out
                   else Path("results") / (stem if study_file else f"{stem}_study"))
            quantities = parse_quantities(args.quantity) or quantities
            rows = run_study(data, vary + args.vary, out, quantities, comm,
                             keep_runs=args.keep_runs)
            if comm.rank == 0:
                print((out / "study.md").read_text())
                figures = ", ".join(sorted(p.name for p in out.glob("*.png")))
                warned = sum(bool(r.get("warnings")) for r in rows)
                print(f"{len(rows)} runs, {sum(r['converged'] for r in rows)} converged, "
                      f"{warned} with warnings (study.md lists them); "
                      f"{out}/study.json, study.csv, study.md{', ' + figures if figures else ''}")
            return 0
        accuracy = [accuracy_override(args.accuracy)] if getattr(args, "accuracy", None) else []
        scene = load_scene(args.scene, [*args.set, *accuracy])
        petsc_options = petsc_options_from_args(petsc_args)
    except SceneError as error:
        if comm.rank == 0:
            print(f"forming: invalid scene {args.scene}: {error}", file=sys.stderr)
        return 2

    if args.command == "mesh":
        if comm.rank == 0:
            from forming_fenicsx.mesh.geometry import write_msh

            print(write_msh(scene, args.output))
        return 0

    from forming_fenicsx.app.run import run_scene

    configure_logging(args.quiet, comm.rank)
    out = Path(args.out) if args.out else Path("results") / Path(args.scene).stem
    received: list[int] = []

    def on_signal(signum, frame):
        received.append(signum)

    def stop() -> str | None:
        return f"interrupted by {signal.Signals(received[0]).name}" if received else None

    previous = {sig: signal.signal(sig, on_signal) for sig in (signal.SIGINT, signal.SIGTERM)}
    try:
        summary = run_scene(scene, out, petsc_options, comm, title=Path(args.scene).stem,
                            overwrite=args.force, stop=stop,
                            restart=Path(args.restart) if args.restart else None)
    except (FileExistsError, FileNotFoundError, ValueError) as error:
        if comm.rank == 0:
            print(f"forming: {error}", file=sys.stderr)
        return 2
    except Exception as error:  # one rank's failure must end every rank, not leave them waiting
        print(f"forming: error on rank {comm.rank} of {comm.size}: {type(error).__name__}: {error}",
              file=sys.stderr, flush=True)
        if comm.size > 1:
            comm.Abort(1)
        return 1
    finally:
        for sig, handler in previous.items():
            signal.signal(sig, handler)
    if not summary["converged"]:
        if comm.rank == 0:
            print(f"forming: not converged: {summary['reason']}; the last iterate's results are "
                  f"in {out}", file=sys.stderr)
        return 3
    if not summary.get("accuracy", {"reached": True})["reached"]:
        accuracy = summary["accuracy"]
        if comm.rank == 0:
            print(f"forming: accuracy not reached: {accuracy['reason']}; the finest mesh's "
                  f"results are in {out} ({accuracy['quantity']} = {accuracy['answer_value']:.6g}"
                  f" ({accuracy['answer']}), estimated error "
                  f"{100 * accuracy['answer_estimate']:.3g} %)", file=sys.stderr)
        return 3
    return 0


if __name__ == "__main__":
    sys.exit(main())

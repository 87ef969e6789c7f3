"""One run, in the order data flows: scene -> mesh -> forms -> solver -> results -> files."""
from __future__ import annotations

import logging
import math
import shutil
import tempfile
import time
from pathlib import Path
from typing import Any, Callable

import dolfinx
from mpi4py import MPI

from .forms import FlowProblem
from .geometry import build_mesh
from .newton import NewtonSolver
from .output import load_velocity, save_velocity, write_die_profile, write_fields, write_history, write_summary
from .plotting import write_die_plot, write_figures
from .postprocess import die_profile, force_balance, output_fields, scalars
from .scene import Scene
from .solvers import ILL_CONDITIONED, SecantSolver, SolveResult

log = logging.getLogger(__name__)


def solve_scene(scene: Scene, petsc_options: dict[str, Any] | None = None, comm: MPI.Comm = MPI.COMM_WORLD,
                stop: Callable[[], str | None] | None = None,
                restart: Path | None = None) -> tuple[FlowProblem, SolveResult, dict[str, Any]]:
    """Mesh, solve and post-process a scene; returns the problem, the iteration and the summary.

    ``stop`` is polled after every linear solve (see SecantSolver); ``restart`` is a previous run's
    folder whose velocity.npz (same mesh) starts the iteration. Timed from when every rank has entered (a
    rank still starting its interpreter is not the run's time)."""
    comm.barrier()
    start = time.perf_counter()
    problem = FlowProblem(scene, build_mesh(scene, comm))
    initial = None
    if restart is not None:
        initial = problem.u.copy()
        load_velocity(Path(restart) / "velocity.npz", initial)
    method = NewtonSolver if scene.solver.method == "newton" else SecantSolver
    solver = method(problem, petsc_options, balance=lambda: force_balance(problem)[0], stop=stop)
    setup = time.perf_counter() - start
    result = solver.solve(initial)
    solver.destroy()
    problem.update_state(problem.u, friction_too=True)
    summary = {
        "scene": scene.to_dict(),
        "dolfinx_version": dolfinx.__version__,
        "mpi_ranks": comm.size,
        "dofs": problem.unknowns,
        "converged": result.converged,
        "reason": result.reason,
        "linear_solves": result.linear_solves,
        "outer_iterations": result.outer_iterations,
        "solve_error_estimate": result.solve_error,
        "restarted_from": str(restart) if restart is not None else None,
        **scalars(problem),
        "wall_time_s": comm.allreduce(time.perf_counter() - start, op=MPI.MAX),
        "time_split_s": time_split(comm, setup, result),
    }
    summary["warnings"] = warnings(summary, scene)
    if comm.rank == 0:
        for text in summary["warnings"]:
            log.warning(text)
    return problem, result, summary


def time_split(comm: MPI.Comm, setup: float, result: SolveResult) -> dict[str, float]:
    """Seconds (the slowest rank's) in setup (mesh, spaces, compiled forms), and within the iteration in
    assembly, factorisation, solves and the rest (state updates, projections, checks)."""
    timings = result.timings
    rest = result.iteration_time - timings.assembly - timings.factorisation - timings.solve
    return {key: comm.allreduce(value, op=MPI.MAX) for key, value in
            (("setup", setup), ("assembly", timings.assembly), ("factorisation", timings.factorisation),
             ("solve", timings.solve), ("rest", rest))}


COMPRESSIBLE = 0.1  # ||div u|| / ||e(u)|| above which the penalty solution is reported as compressible


def warnings(summary: dict[str, Any], scene: Scene) -> list[str]:
    """What a converged-looking run must still tell its user: a penalty too weak for incompressibility,
    linear solves whose estimated error approaches the tolerance, a drawing stress the drawn strip
    cannot carry."""
    found = []
    if scene.discretisation.formulation == "penalty" and summary["relative_divergence"] > COMPRESSIBLE:
        found.append(f"penalty.d = {scene.penalty.d:g} lets the material compress: ||div u||/||e(u)|| = "
                     f"{summary['relative_divergence']:.2g} (above {COMPRESSIBLE:g}); the results are those of a "
                     "compressible material: use a smaller penalty.d (Theorem 3.1: the error falls like O(d))")
    if summary["solve_error_estimate"] > ILL_CONDITIONED * scene.solver.tolerance:
        found.append(f"ill-conditioned linear systems: estimated relative error of a solve "
                     f"{summary['solve_error_estimate']:.1e}, above {ILL_CONDITIONED:.0%} of solver.tolerance; "
                     "use larger penalty parameters (penalty.d, penalty.d_N, friction.d_T)")
    if scene.process.kind == "drawing":
        strength = 2 / math.sqrt(3) * scene.reference_flow_stress
        if summary["drawing_stress"] > strength:
            found.append(f"the drawing stress {summary['drawing_stress']:.4g} exceeds the plane-strain yield stress "
                         f"2k = {strength:.4g} of the drawn strip: it yields after the die, so no steady drawing "
                         "exists at this reduction and friction (the limit of drawability)")
    return found


def run_scene(scene: Scene, out: str | Path, petsc_options: dict[str, Any] | None = None,
              comm: MPI.Comm = MPI.COMM_WORLD, title: str = "", overwrite: bool = False,
              stop: Callable[[], str | None] | None = None, restart: Path | None = None) -> dict[str, Any]:
    """Solve a scene and write summary.json, history.csv, die.csv, fields.xdmf and the figures into ``out``.

    The files are written into a hidden staging folder beside ``out`` and moved into place only when
    all are complete, so ``out`` never holds a half-written run. An existing ``out`` is replaced only
    with ``overwrite`` (FileExistsError otherwise, before any work).
    """
    out = Path(out)
    exists = comm.bcast(out.exists() if comm.rank == 0 else None, root=0)
    if exists and not overwrite:
        raise FileExistsError(f"output folder {out} exists (use --force to replace it)")
    staging = None
    if comm.rank == 0:
        out.parent.mkdir(parents=True, exist_ok=True)
        staging = Path(tempfile.mkdtemp(prefix=f".{out.name}.partial-", dir=out.parent))
    staging = Path(comm.bcast(str(staging) if staging else None, root=0))
    try:
        summary = _solve_and_write(scene, staging, petsc_options, comm, title, stop, restart)
    except BaseException:
        if comm.rank == 0:
            shutil.rmtree(staging, ignore_errors=True)
        raise
    comm.barrier()
    if comm.rank == 0:
        if out.exists():
            shutil.rmtree(out)
        staging.rename(out)
    comm.barrier()
    return summary


def _solve_and_write(scene: Scene, out: Path, petsc_options: dict[str, Any] | None, comm: MPI.Comm,
                     title: str, stop: Callable[[], str | None] | None, restart: Path | None) -> dict[str, Any]:
    problem, result, summary = solve_scene(scene, petsc_options, comm, stop, restart)
    save_velocity(out / "velocity.npz", problem.u)
    if scene.output.fields:
        write_fields(out / "fields.xdmf", problem.mesh, output_fields(problem))
    if scene.output.figures:
        write_figures(problem, out, title or scene.process.kind)
    profile = die_profile(problem)
    if comm.rank == 0:
        write_die_profile(out / "die.csv", profile)
        if scene.output.figures:
            write_die_plot(profile, out / "die.png", title or scene.process.kind)
        write_history(out / "history.csv", result.history)
        write_summary(out / "summary.json", summary)
        key = "ram_pressure" if scene.process.kind == "extrusion" else "drawing_stress"
        log.info("%s %.5g, force balance residual %.2e, %d linear solves, %.1f s", key.replace("_", " "),
                 summary[key], summary["force_balance_residual"], summary["linear_solves"], summary["wall_time_s"])
    return summary

"""One run, in the order data flows: scene -> mesh -> forms -> solver -> results -> files."""
from __future__ import annotations

import dataclasses
import logging
import os
import shutil
import tempfile
import time
from pathlib import Path
from typing import Any, Callable

import dolfinx
from mpi4py import MPI

from forming_fenicsx.app.free_surface import solve_free_surface, surface_lines
from forming_fenicsx.config.scene import Scene
from forming_fenicsx.core.units import DIMENSIONS
from forming_fenicsx.coupled.coupling import coupled_problem
from forming_fenicsx.fem.forms import FlowProblem
from forming_fenicsx.io.die_faces import write_die_faces
from forming_fenicsx.io.die_plot import write_die_plot
from forming_fenicsx.io.figure import Heading
from forming_fenicsx.io.maps import write_figures
from forming_fenicsx.io.maps3d import write_maps_3d
from forming_fenicsx.io.output import (load_velocity, save_velocity, write_die_profile,
                                       write_exit_profile, write_fields, write_free_surface,
                                       write_history, write_summary)
from forming_fenicsx.io.profile_plot import write_exit_profile_plot
from forming_fenicsx.io.roll_plot import write_roll_plot
from forming_fenicsx.io.section_plot import write_section_plot
from forming_fenicsx.mesh.free_shape import FreeShape
from forming_fenicsx.mesh.geometry import build_mesh
from forming_fenicsx.mesh.transfer import transfer
from forming_fenicsx.post.die import die_profile, die_stresses
from forming_fenicsx.post.exit_profiles import exit_profile, exit_strain_profile
from forming_fenicsx.post.forces import force_balance
from forming_fenicsx.post.output_fields import output_fields
from forming_fenicsx.post.sanity import check_run
from forming_fenicsx.post.summary import scalars, update_scalars
from forming_fenicsx.post.views3d import (die_faces, exit_section_values, strain_undershoot,
                                          symmetry_planes)
from forming_fenicsx.solvers.accuracy import solve_to_accuracy
from forming_fenicsx.solvers.choice import solver_for
from forming_fenicsx.solvers.records import SolveResult

log = logging.getLogger(__name__)
LITE = "lite_summary"  # a lite summary's mark (solve_scene(lite=True)), gone once completed


def solve_scene(scene: Scene, petsc_options: dict[str, Any] | None = None,
                comm: MPI.Comm = MPI.COMM_WORLD, stop: Callable[[], str | None] | None = None,
                restart: Path | None = None,
                previous: dolfinx.fem.Function | FlowProblem | None = None,
                generate: Callable[[], None] | None = None, quiet: bool = False,
                lite: bool = False) -> tuple[FlowProblem, SolveResult, dict[str, Any]]:
    """Mesh, solve and post-process a scene; returns the problem, the iteration and the summary.

    ``stop`` is polled after every linear solve (see SecantSolver); ``restart`` is a previous run's
    folder whose velocity.npz (same mesh) starts the iteration, ``previous`` a velocity on another
    mesh of the workpiece that starts it interpolated (transfer.py), or a problem solved on one,
    whose contact multiplier starts it too (FlowProblem.carry_from); ``generate`` meshes the
    workpiece instead of the scene's blocks (an adapted mesh, mesh/adapted.py); ``quiet``: the
    summary's warnings are not logged (the free surface's intermediate flows: it logs its last
    one's); ``lite``: the summary has only the numbers the free surface's update reads
    (summary.update_scalars) and no checks, until completed_summary. Timed from when every rank
    has entered (a rank still starting its interpreter is not the run's time)."""
    comm.barrier()
    start = time.perf_counter()
    problem = coupled_problem(scene, build_mesh(scene, comm, generate))
    initial = None
    if restart is not None:
        initial = problem.u.copy()
        load_velocity(Path(restart) / "velocity.npz", initial)
    elif isinstance(previous, FlowProblem):
        initial = problem.u.copy()
        problem.carry_from(previous, initial)
    elif previous is not None:
        initial = problem.u.copy()
        transfer(previous, initial)
    solver = solver_for(problem, petsc_options, balance=lambda: force_balance(problem)[0],
                        stop=stop)
    setup = time.perf_counter() - start
    result = solver.solve(initial)
    solver.destroy()
    post = time.perf_counter()
    problem.update_state(problem.u, frozen_too=True)
    numbers = update_scalars(problem) if lite else scalars(problem)
    post = time.perf_counter() - post
    body = {
        "scene": scene.to_dict(),
        "scales": dataclasses.asdict(scene.scales),
        "dolfinx_version": dolfinx.__version__,
        "mpi_ranks": comm.size,
        "dofs": problem.unknowns,
        "linear_solves": result.linear_solves,
        "outer_iterations": result.outer_iterations,
        "solver_fallback": result.fallback,
        "solve_error_estimate": result.solve_error,
        "linear_solver": "iterative" if solver.linear.saddle_point is not None else "direct",
        "krylov_iterations": sum(record.krylov_iterations for record in result.history),
        "velocity_iterations": sum(record.velocity_iterations for record in result.history),
        "restarted_from": str(restart) if restart is not None else None,
        **numbers,
        "wall_time_s": comm.allreduce(time.perf_counter() - start, op=MPI.MAX),
        "time_split_s": time_split(comm, setup, result, post),
    }
    if lite:
        return problem, result, {LITE: True, "warnings": [], "failed_checks": [],
                                 "converged": result.converged, "reason": result.reason,
                                 "iteration_converged": result.converged, **body}
    return problem, result, summarise(body, result, scene, comm, quiet)


def completed_summary(problem: FlowProblem, result: SolveResult, summary: dict[str, Any],
                      scene: Scene, comm: MPI.Comm) -> dict[str, Any]:
    """A lite summary (solve_scene(lite=True)) made whole: every number of scalars and the
    sanity checks against ``scene``, for the problem's flow (the free surface's last); the time
    it takes is the post-processing's and the run's. Warnings are not logged. Collective."""
    if not summary.get(LITE):
        return summary
    start = time.perf_counter()
    numbers = scalars(problem)
    spent = comm.allreduce(time.perf_counter() - start, op=MPI.MAX)
    keys = list(summary)
    lite_numbers = keys.index("restarted_from") + 1
    head = {key: summary[key] for key in keys[keys.index("scene"):lite_numbers]}
    split = summary["time_split_s"]
    body = {**head, **numbers, "wall_time_s": summary["wall_time_s"] + spent,
            "time_split_s": {**split, "postprocess": split["postprocess"] + spent}}
    return summarise(body, result, scene, comm, quiet=True)


def solve_updated(scene: Scene, petsc_options: dict[str, Any] | None = None,
                  comm: MPI.Comm = MPI.COMM_WORLD, stop: Callable[[], str | None] | None = None
                  ) -> tuple[FlowProblem, SolveResult, dict[str, Any], FreeShape]:
    """The scene with its free surfaces updated (app/free_surface.solve_free_surface): the flows
    of shapes that move on with lite summaries, their warnings not logged, the last one's
    completed (completed_summary)."""
    return solve_free_surface(
        scene, lambda variant, previous, generate: solve_scene(
            variant, petsc_options, comm, stop, previous=previous, generate=generate,
            quiet=True, lite=True), comm,
        lambda *solved: completed_summary(*solved, scene, comm))


def summarise(body: dict[str, Any], result: SolveResult, scene: Scene, comm: MPI.Comm,
              quiet: bool = False) -> dict[str, Any]:
    """The summary: the sanity checks' warnings and failures first (sanity.py), then whether the run
    converged (a failed check means it did not, whatever the iteration did) and why, the units, then
    the run's numbers. The reason leads with what the run measured: a failed check of a converged
    iteration, or a cause (the law's rate window, drawability) found at the last iterate of one that
    stopped, before the iteration's own reason. Warnings are logged on rank 0 unless ``quiet`` (a
    failure is the reason the command prints)."""
    findings = check_run(body, scene, result.converged)
    failures = [f.message for f in findings if f.failure]
    converged = result.converged and not failures
    cause = next((f.message for f in findings if f.cause), None)
    if result.converged and failures:
        reason = (f"the iteration converged ({result.reason}), but the answer cannot be right: "
                  f"{failures[0]}")
    elif not result.converged and cause is not None:
        reason = f"{cause} (the iteration stopped: {result.reason})"
    else:
        reason = result.reason
    summary = {"warnings": [f.message for f in findings if not f.failure],
               "failed_checks": failures, "converged": converged, "reason": reason,
               "iteration_converged": result.converged,
               "units": scene.units.summary(list(body), scene.geometry.whole_forces), **body}
    if comm.rank == 0 and not quiet:
        log_warnings(summary["warnings"])
    return summary


def log_warnings(warnings: list[str]) -> None:
    for text in warnings:
        log.warning("warning: %s", text)


def time_split(comm: MPI.Comm, setup: float, result: SolveResult, post: float) -> dict[str, float]:
    """Seconds (the slowest rank's) in setup (mesh, spaces, compiled forms), within the iteration in
    assembly, factorisation, solves and the rest (state updates, projections, checks), and in the
    post-processing of the summary's numbers."""
    timings = result.timings
    rest = result.iteration_time - timings.assembly - timings.factorisation - timings.solve
    return {key: comm.allreduce(value, op=MPI.MAX) for key, value in
            (("setup", setup), ("assembly", timings.assembly),
             ("factorisation", timings.factorisation), ("solve", timings.solve), ("rest", rest),
             ("postprocess", post))}


def run_scene(scene: Scene, out: str | Path, petsc_options: dict[str, Any] | None = None,
              comm: MPI.Comm = MPI.COMM_WORLD, title: str = "", overwrite: bool = False,
              stop: Callable[[], str | None] | None = None, restart: Path | None = None
              ) -> dict[str, Any]:
    """Solve a scene and write summary.json, history.csv, die.csv, fields.xdmf and the figures into
    ``out``.

    The files are written into a hidden staging folder beside ``out`` and moved into place only
    when all are complete, so ``out`` never holds a half-written run. An existing ``out`` is
    replaced only with ``overwrite`` (FileExistsError otherwise, before any work).
    """
    out = Path(out)
    exists = comm.bcast(out.exists() if comm.rank == 0 else None, root=0)
    if exists and not overwrite:
        raise FileExistsError(f"output folder {out} exists (use --force to replace it)")
    staging = None
    if comm.rank == 0:
        out.parent.mkdir(parents=True, exist_ok=True)
        staging = Path(tempfile.mkdtemp(prefix=f".{out.name}.partial-", dir=out.parent))
        umask = os.umask(0)
        os.umask(umask)
        staging.chmod(0o777 & ~umask)  # mkdtemp's 0700, made the user's normal permissions
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
                     title: str, stop: Callable[[], str | None] | None, restart: Path | None
                     ) -> dict[str, Any]:
    """Solve the scene (once, or on finer meshes to accuracy.target) and write every file of the
    run into ``out``; returns the summary."""
    shape = None
    if scene.free_surface.update:
        if restart is not None:
            raise ValueError("--restart starts one run on the same mesh; free_surface.update "
                             "re-meshes the workpiece at each update: give one or the other")
        problem, result, summary, shape = solve_updated(scene, petsc_options, comm, stop)
        if comm.rank == 0:
            log_warnings(summary["warnings"])
    elif scene.accuracy.target is None:
        problem, result, summary = solve_scene(scene, petsc_options, comm, stop, restart)
    else:
        if restart is not None:
            raise ValueError("--restart starts one run on the same mesh; accuracy.target runs a "
                             "sequence of meshes, each started from the previous one: give one or "
                             "the other")
        problem, result, summary = solve_to_accuracy(
            scene, lambda level, previous, generate: solve_scene(
                level, petsc_options, comm, stop, previous=previous, generate=generate), comm)
    save_velocity(out / "velocity.npz", problem.u)
    if scene.output.fields:
        write_fields(out / "fields.xdmf", problem.mesh, output_fields(problem))
    three_d = problem.coordinates.three_dimensional
    stresses = die_stresses(problem)
    profile = die_profile(problem, stresses)
    heading = Heading.of_run(title or scene.process.kind, problem.scene, summary)  # finest mesh
    if scene.output.figures and three_d:
        faces, planes = die_faces(problem, stresses), symmetry_planes(problem)
        if comm.rank == 0:
            write_die_faces(faces, list(stresses), out / "die.png", heading, scene)
            write_maps_3d(planes, profile, out, heading, scene.units)
    elif scene.output.figures and shape is not None:  # the whole die wall (the square die's
        # face is all in Gamma3)
        wall = None if shape.wall is None else scene.geometry.profile().polyline()
        write_figures(problem, out, heading, profile, wall, surface_lines(shape))
    elif scene.output.figures:
        write_figures(problem, out, heading, profile)
    profiles = []  # (file stem, summary/units key, profile, label, reference level)
    # a hardening law: the product's strain (hardness) profile; not of an iteration that stopped,
    # whose strain may be NaN and whose streamlines are no flow's (an annealed steel wire's ran
    # back and forth for 25 minutes before this, docs/outputs.md)
    if problem.strain is not None and result.converged:
        ideal = summary["mean_entry_strain"] + summary["ideal_strain"]
        across = (exit_section_values(problem, problem.strain) if three_d
                  else exit_strain_profile(problem))
        note = strain_undershoot(across, scene.inflow_strain, comm) if three_d else ""
        if note:
            summary["warnings"].append(note)
            if comm.rank == 0:
                log_warnings([note])
        profiles.append(("exit_strain", "equivalent_strain", across, "equivalent strain",
                         ("entry strain + ideal ln(A0/A1)", ideal)))
    temperature = problem.field("temperature")
    if temperature is not None:  # [thermal]: the product's temperature profile
        profiles.append(("exit_temperature", "temperature",
                         exit_profile(problem, temperature.T), "temperature",
                         ("inflow temperature", scene.thermal.inflow_temperature)))
    mirrored = tuple(role in problem.roles for role in ("gamma6_symmetry", "gamma7_symmetry"))
    for stem, key, across, label, reference in profiles:
        if comm.rank != 0:
            continue
        write_exit_profile(out / f"{stem}.csv", across, key, scene.units)
        if scene.output.figures and three_d:
            write_section_plot(across["samples"], out / f"{stem}.png", heading, label,
                               DIMENSIONS.get(key, ""), scene.units, mirrored, reference)
        elif scene.output.figures:
            write_exit_profile_plot(across, out / f"{stem}.png", heading, label,
                                    DIMENSIONS.get(key, ""), scene.units, reference)
    if comm.rank == 0:
        write_die_profile(out / "die.csv", profile, scene.units)
        if shape is not None:
            write_free_surface(out / "free_surface.csv", surface_lines(shape), scene.units)
        if scene.output.figures and scene.process.kind == "rolling":
            write_roll_plot(profile, out / "rolls.png", heading, scene, summary["neutral_x"])
        elif scene.output.figures and not three_d:
            write_die_plot(profile, out / "die.png", heading, scene)
        write_history(out / "history.csv", result.history)
        write_summary(out / "summary.json", summary)

        def labelled(key: str) -> str:
            """A summary number with its unit, as the log shows it."""
            unit = scene.units.label(scene.units.dimension(key, scene.geometry.whole_forces))
            return f"{summary[key]:.5g}" + (f" {unit}" if unit else "")

        key = {"extrusion": "ram_pressure", "drawing": "drawing_stress",
               "rolling": "roll_force"}[scene.process.kind]
        log.info("%s %s, force balance residual %.2e, %d linear solves, %.1f s",
                 key.replace("_", " "), labelled(key), summary["force_balance_residual"],
                 summary["linear_solves"], summary["wall_time_s"])
        if scene.process.kind == "rolling":
            log.info("rolls: torque %s, neutral point %.3g deg (x = %s), forward slip %.3g %%, "
                     "entry speed %s", labelled("roll_torque"), summary["neutral_angle"],
                     labelled("neutral_x"), 100 * summary["forward_slip"],
                     labelled("entry_speed"))
            if scene.friction.law == "factor" and scene.friction.sticks:
                log.info("friction: m = 1 solved as sticking, the factor law's d_T -> 0 limit "
                         "on a strongly rate-sensitive metal (friction.sticks; docs/rolling.md)")
        if "free_surface" in summary:
            surface = summary["free_surface"]
            size = f"exit_{scene.geometry.thickness_name}"  # free_surface.shape_scalars' key
            contact = (f"the die corner at x = {surface['contact_end_x']:.5g}"
                       if surface["contact_start_x"] == surface["contact_end_x"] else
                       f"contact from x = {surface['contact_start_x']:.5g} to "
                       f"{surface['contact_end_x']:.5g}")
            stock = (f", stock {100 * summary['free_surface_crossing_stock']:.3g} %"
                     if scene.process.kind == "drawing" else "")
            log.info("free surface: %s after %d updates, the product's %s %.6g (%+.3g %% from the "
                     "die's), %s, crossing %.3g %% (product %.3g %%%s), %d linear solves, %.1f s",
                     "settled" if surface["converged"] else "not settled",
                     surface["updates"], size.replace("_", " "), surface[size],
                     100 * surface[f"{size}_change"], contact,
                     100 * summary["free_surface_crossing"],
                     100 * summary["free_surface_crossing_product"], stock,
                     surface["linear_solves"], surface["wall_time_s"])
        if "accuracy" in summary:
            accuracy = summary["accuracy"]
            which = ("finest mesh" if accuracy["answer"] != "extrapolated" else
                     f"extrapolated; finest mesh {accuracy['value']:.6g}, estimated error "
                     f"{100 * accuracy['estimate']:.3g} %")
            log.info("accuracy: %s = %.6g (%s), estimated error %.3g %% (target %g %%) on %d %s "
                     "meshes, %.1f s: %s", accuracy["quantity"], accuracy["answer_value"], which,
                     100 * accuracy["answer_estimate"], 100 * accuracy["target"],
                     len(accuracy["meshes"]), accuracy["mesh_kind"], accuracy["wall_time_s"],
                     accuracy["reason"])
    return summary

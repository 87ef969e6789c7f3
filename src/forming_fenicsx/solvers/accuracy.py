"""Accuracy on demand: a scene solved on a sequence of finer meshes, each started from the previous
solution interpolated onto it (transfer.py), until the estimated error of its main quantity is below
a target. The estimate is Richardson's with its guards (core/richardson.py); docs/accuracy.md
measures how it compares with the true error.
"""
from __future__ import annotations

import copy
import logging
import math
import time
from typing import Any, Callable

import dolfinx.fem
from mpi4py import MPI

from forming_fenicsx.config.scene import Scene
from forming_fenicsx.core.richardson import Estimate, estimate, relative
from forming_fenicsx.fem.forms import FlowProblem
from forming_fenicsx.solvers.records import SolveResult

log = logging.getLogger(__name__)
SAFETY = 0.8       # a predicted mesh size aims at this fraction of the target
MIN_RATIO, MAX_RATIO = 1.5, 3.0  # the refinement a prediction may choose


def next_mesh_size(size: float, found: Estimate | None, relative_error: float, target: float,
                   ratio: float) -> float:
    """The next level's mesh size: size/ratio until an asymptotic estimate exists, then the size
    that the observed order predicts for SAFETY times the target, refined by a factor within
    [MIN_RATIO, MAX_RATIO]."""
    if found is None or found.kind != "richardson":
        return size / ratio
    wanted = (relative_error / (SAFETY * target)) ** (1.0 / found.order)
    return size / min(max(wanted, MIN_RATIO), MAX_RATIO)


def level_scene(scene: Scene, size: float) -> Scene:
    """The scene on a mesh of size ``size``; a friction mollification length equal to the scene's
    mesh size (its default: one element) follows the mesh."""
    level = copy.deepcopy(scene)
    level.discretisation.mesh_size = size
    level.discretisation.mesh_size_relative = size / scene.geometry.thinnest
    if math.isclose(scene.friction.mollification_length, scene.discretisation.mesh_size):
        level.friction.mollification_length = size
    level.check()
    return level


def first_mesh_size(scene: Scene) -> float:
    """The coarsest level: two refinements above the scene's own mesh size, within the thinnest
    half-thickness (at least one element across it)."""
    return min(scene.discretisation.mesh_size * scene.accuracy.ratio**2, scene.geometry.thinnest)


Solve = Callable[[Scene, "dolfinx.fem.Function | None"],
                 tuple[FlowProblem, SolveResult, dict[str, Any]]]


def solve_to_accuracy(scene: Scene, solve: Solve, comm: MPI.Comm = MPI.COMM_WORLD
                      ) -> tuple[FlowProblem, SolveResult, dict[str, Any]]:
    """Solve on finer meshes, each started from the previous velocity (``solve(level, previous)``:
    run.solve_scene), until the estimated relative error of the scene's accuracy.quantity is below
    accuracy.target, a level does not converge, or accuracy.max_levels are used. Returns the last
    level's problem, iteration and summary, the summary with an ``accuracy`` table (whose value and
    estimate are the last converged level's)."""
    settings = scene.accuracy
    quantity, target = settings.quantity, settings.target
    start = time.perf_counter()
    sizes: list[float] = []
    values: list[float] = []
    levels: list[dict[str, Any]] = []
    size, previous, found, error = first_mesh_size(scene), None, None, math.inf
    while True:
        problem, result, summary = solve(level_scene(scene, size), previous)
        if sizes:  # the run says where it started
            summary["restarted_from"] = f"the velocity on mesh size {sizes[-1]:.6g}, interpolated"
        previous = problem.u
        level = {key: summary[key] for key in ("dofs", "linear_solves", "wall_time_s", quantity)}
        levels.append({"mesh_size": size, **level, "converged": summary["converged"],
                       "started_from": summary["restarted_from"]})
        if not summary["converged"]:  # the value and estimate stay the previous mesh's
            reason = (f"the run on mesh size {size:.4g} did not converge: {summary['reason']}; the "
                      "value and estimate are those of the previous mesh")
            break
        sizes.append(size)
        values.append(float(summary[quantity]))
        if len(values) >= 3:
            found = estimate(sizes, values, scene.discretisation.degree)
            error = float(relative(found, values[-1]))
        if comm.rank == 0:
            note = f", estimated error {100 * error:.3g} % ({found.kind.split(':')[0]})" if found \
                else ""
            log.info("accuracy level %d: h = %.4g, %d dofs, %s = %.6g, %d solves, %.1f s%s",
                     len(sizes), size, summary["dofs"], quantity, values[-1],
                     summary["linear_solves"], summary["wall_time_s"], note)
        if error <= target:
            reason = f"estimated error {100 * error:.3g} % <= target {100 * target:g} %"
            break
        if len(levels) == settings.max_levels:
            reason = (f"target {100 * target:g} % not reached in accuracy.max_levels = "
                      f"{settings.max_levels} meshes (estimated error {100 * error:.3g} %)")
            break
        size = next_mesh_size(size, found, error, target, settings.ratio)
    reached = bool(summary["converged"] and error <= target)
    summary["accuracy"] = {
        "target": target, "quantity": quantity, "reached": reached, "reason": reason,
        "value": values[-1] if values else math.nan,
        "extrapolated": found.extrapolated if found else math.nan,
        "estimate": error, "estimate_absolute": found.error if found else math.nan,
        "observed_order": found.order if found else math.nan,
        "estimate_kind": found.kind if found else "none: fewer than three meshes",
        "meshes": levels,
        "wall_time_s": comm.allreduce(time.perf_counter() - start, op=MPI.MAX),
    }
    return problem, result, summary

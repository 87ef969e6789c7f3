"""Accuracy on demand: a scene solved on a sequence of finer meshes (adapted to a recovered
strain-rate indicator, fem/error_indicator.py and mesh/adapted.py, or the scene's blocks refined),
each started from the previous solution interpolated onto it (transfer.py), until the estimated
error of its answer is below a target. The answer is the finest mesh's value with Richardson's
estimate (with its guards), or, from four meshes in the asymptotic range, the extrapolated value
with the change of the extrapolation as its estimate, whichever estimate is smaller
(core/richardson.py); docs/accuracy.md measures how both compare with the true error.
"""
from __future__ import annotations

import copy
import logging
import math
import time
from dataclasses import dataclass
from typing import Any, Callable

import dolfinx.fem
import numpy as np
import ufl
from mpi4py import MPI

from forming_fenicsx.config.scene import Scene
from forming_fenicsx.fem.error_indicator import strain_rate_indicator
from forming_fenicsx.mesh.adapted import adapted_sizes, size_field_mesh
from forming_fenicsx.core.richardson import Estimate, estimate, extrapolation_error, relative
from forming_fenicsx.fem.forms import FlowProblem
from forming_fenicsx.solvers.records import SolveResult

log = logging.getLogger(__name__)
SAFETY = 0.8       # a predicted mesh size aims at this fraction of the target
MIN_RATIO, MAX_RATIO = 1.5, 3.0  # the refinement a prediction may choose


def next_mesh_size(size: float, found: Estimate | None, relative_error: float, target: float,
                   ratio: float, meshes: int = 0) -> float:
    """The next level's mesh size: size/ratio until an asymptotic estimate exists, then the size
    that the observed order predicts for SAFETY times the target, refined by a factor within
    [MIN_RATIO, MAX_RATIO]; after the third of ``meshes`` at most by ``ratio``: the fourth gives
    the extrapolated value its own estimate, which may reach the target first (choose_answer)."""
    if found is None or found.kind != "richardson":
        return size / ratio
    wanted = (relative_error / (SAFETY * target)) ** (1.0 / found.order)
    refine = min(max(wanted, MIN_RATIO), MAX_RATIO)
    return size / (min(refine, max(ratio, MIN_RATIO)) if meshes == 3 else refine)


@dataclass
class Answer:
    """The sequence's answer: which value ("finest" or "extrapolated"), the value, its estimated
    relative error and why it was chosen."""

    kind: str
    value: float
    estimate: float
    reason: str


def choose_answer(sizes: list[float], values: list[float], found: Estimate) -> Answer:
    """The extrapolated value when its estimate (the change of the extrapolation when the finest
    mesh was added, relative to it) is smaller than the finest value's, else the finest value."""
    finest = float(relative(found, values[-1]))
    change = extrapolation_error(sizes, values)
    if math.isfinite(change):
        own = change / abs(found.extrapolated) if found.extrapolated != 0 else math.inf
        if own < finest:
            return Answer("extrapolated", found.extrapolated, own,
                          f"the extrapolated value: it changed by {100 * own:.3g} % when the "
                          f"finest mesh was added, less than the finest value's estimated error "
                          f"{100 * finest:.3g} %")
        why = (f"the extrapolated value changed by {100 * own:.3g} % when the finest mesh was "
               f"added, more than the finest value's estimated error {100 * finest:.3g} %")
    else:
        why = ("the extrapolated value has no estimate of its own (fewer than four meshes, or "
               "a limit not from an asymptotic sequence)")
    return Answer("finest", values[-1], finest, f"the finest mesh's value: {why}")


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


Solve = Callable[[Scene, "dolfinx.fem.Function | None", "Callable[[], None] | None"],
                 tuple[FlowProblem, SolveResult, dict[str, Any]]]


def mesh_kind(scene: Scene) -> str:
    """accuracy.meshes, "refined" where a mesh cannot be adapted: a 3D scene (hexahedra by a size
    field are not gmsh's) or a user's mesh file (no geometry to re-mesh)."""
    g = scene.geometry
    return "refined" if g.three_dimensional or g.mesh_file else scene.accuracy.meshes


def effective_size(problem: FlowProblem) -> float:
    """The mesh size of an adapted mesh for Richardson's estimate: sqrt(area/cells), the size of
    a uniform mesh with as many cells (the transfinite blocks' nominal size, too: their edges
    take length/size elements)."""
    mesh, comm = problem.mesh, problem.comm
    area = dolfinx.fem.assemble_scalar(dolfinx.fem.form(1.0 * ufl.dx(domain=mesh)))
    cells = mesh.topology.index_map(mesh.topology.dim).size_global
    return math.sqrt(comm.allreduce(area, op=MPI.SUM) / cells)


def adapted_mesh(problem: FlowProblem, growth: float, add: Callable[[], None] | None = None
                 ) -> Callable[[], None] | None:
    """The generator of the next level's mesh (mesh/adapted.py), adapted to the strain-rate
    indicator of ``problem``'s solution, on rank 0, ``growth`` times the cells of its mesh (None on
    the other ranks, which build_mesh does not ask); the scene's blocks, or the unmeshed model that
    ``add`` makes. The cells go to gmsh in the order this mesh was made from, whatever the
    partition: the same mesh on any number of ranks."""
    comm, scene = problem.comm, problem.scene
    parts = comm.gather(strain_rate_indicator(problem), root=0)
    if comm.rank != 0:
        return None
    eta, area, corners, index = (np.concatenate(p) for p in zip(*parts, strict=True))
    order = np.argsort(index)
    eta, area, corners = eta[order], area[order], corners[order]
    sizes = adapted_sizes(eta, np.sqrt(area), growth * len(area), scene.discretisation.degree)
    return size_field_mesh(scene, corners, sizes, add)


def solve_to_accuracy(scene: Scene, solve: Solve, comm: MPI.Comm = MPI.COMM_WORLD
                      ) -> tuple[FlowProblem, SolveResult, dict[str, Any]]:
    """Solve on finer meshes (adapted, mesh_kind), each started from the previous velocity
    (``solve(level, previous, generate)``: run.solve_scene, ``generate`` the adapted mesh's
    generator or None for the scene's blocks), until the estimated relative error of the answer for
    the scene's accuracy.quantity (choose_answer) is below accuracy.target, a level does not
    converge, or accuracy.max_levels are used. Returns the last level's problem, iteration and
    summary, the summary with an ``accuracy`` table (whose value and estimates are the last
    converged level's)."""
    settings = scene.accuracy
    quantity, target = settings.quantity, settings.target
    start = time.perf_counter()
    sizes: list[float] = []
    values: list[float] = []
    levels: list[dict[str, Any]] = []
    size, previous, found, error = first_mesh_size(scene), None, None, math.inf
    answer = Answer("none", math.nan, math.inf, "fewer than three meshes: no estimate")
    meshes, generate = mesh_kind(scene), None
    while True:
        problem, result, summary = solve(level_scene(scene, size), previous, generate)
        if sizes:  # the run says where it started
            summary["restarted_from"] = f"the velocity on mesh size {sizes[-1]:.6g}, interpolated"
        previous = problem.u
        if meshes == "adapted":  # the level's size is the adapted mesh's, as it came out
            size = effective_size(problem)
            disc = problem.scene.discretisation
            disc.mesh_size, disc.mesh_size_relative = size, size / scene.geometry.thinnest
            summary["scene"]["discretisation"].update(
                mesh_size=size, mesh_size_relative=disc.mesh_size_relative)
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
            found = estimate(sizes, values)
            error = float(relative(found, values[-1]))
            answer = choose_answer(sizes, values, found)
        if comm.rank == 0:
            note = f", estimated error {100 * error:.3g} % ({found.kind.split(':')[0]})" if found \
                else ""
            if answer.kind == "extrapolated":
                note += (f"; extrapolated {answer.value:.6g}, its estimated error "
                         f"{100 * answer.estimate:.3g} %")
            log.info("accuracy level %d: h = %.4g, %d dofs, %s = %.6g, %d solves, %.1f s%s",
                     len(sizes), size, summary["dofs"], quantity, values[-1],
                     summary["linear_solves"], summary["wall_time_s"], note)
        if answer.estimate <= target:
            reason = (f"estimated error of the {answer.kind} value {100 * answer.estimate:.3g} % "
                      f"<= target {100 * target:g} %")
            break
        if len(levels) == settings.max_levels:
            reason = (f"target {100 * target:g} % not reached in accuracy.max_levels = "
                      f"{settings.max_levels} meshes (estimated error {100 * answer.estimate:.3g} "
                      "%)")
            break
        finer = next_mesh_size(size, found, error, target, settings.ratio, len(sizes))
        if meshes == "adapted":
            generate = adapted_mesh(problem, (size / finer) ** 2)
        size = finer
    reached = bool(summary["converged"] and answer.estimate <= target)
    summary["accuracy"] = {
        "target": target, "quantity": quantity, "reached": reached, "reason": reason,
        "answer": answer.kind, "answer_value": answer.value, "answer_estimate": answer.estimate,
        "answer_reason": answer.reason,
        "value": values[-1] if values else math.nan,
        "extrapolated": found.extrapolated if found else math.nan,
        "estimate": error, "estimate_absolute": found.error if found else math.nan,
        "observed_order": found.order if found else math.nan,
        "estimate_kind": found.kind if found else "none: fewer than three meshes",
        "extrapolated_estimate": (extrapolation_error(sizes, values)
                                  / abs(found.extrapolated) if found else math.nan),
        "mesh_kind": meshes, "meshes": levels,
        "wall_time_s": comm.allreduce(time.perf_counter() - start, op=MPI.MAX),
    }
    return problem, result, summary

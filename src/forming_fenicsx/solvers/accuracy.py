"""Accuracy on demand: a scene solved on a sequence of finer meshes, each started from the previous
solution interpolated onto it (transfer.py), until the estimated error of its main quantity is below
a target (docs/accuracy.md measures how the estimate compares with the true error).

The estimate is Richardson's from the last three meshes h1 > h2 > h3 with values f1, f2, f3: with
f(h) = F + C h^p, the observed order p solves (f1 - f2)/(f2 - f3) = (h1^p - h2^p)/(h2^p - h3^p), the
extrapolated value is F = f3 - (f2 - f3) h3^p/(h2^p - h3^p) and the error of the finest value is
estimated as FACTOR |f3 - F|. A sequence outside its asymptotic range is guarded against: when the
differences change sign (an oscillation) the estimate is FACTOR |f3 - f2| and nothing is
extrapolated; when the observed order lies outside [MIN_ORDER, 2(k + 1)] (k the element degree) it
is clipped to that range and the estimate is FACTOR times the larger of the clipped Richardson error
and |f3 - f2|. ``kind`` says which was used. FACTOR = 1.25 is Roache's factor of safety of the grid
convergence index for three meshes: Richardson's |f3 - F| alone lay between 0.60 and 1.06 times the
true error on Example 1 and the exact drawing field (docs/accuracy.md), below it in five of six.
"""
from __future__ import annotations

import copy
import logging
import math
import time
from dataclasses import dataclass
from typing import Any, Callable

import dolfinx.fem
from mpi4py import MPI

from forming_fenicsx.fem.forms import FlowProblem
from forming_fenicsx.config.scene import Scene
from forming_fenicsx.solvers.records import SolveResult

log = logging.getLogger(__name__)
FACTOR = 1.25      # the estimate over Richardson's error (Roache's grid convergence index)
MIN_ORDER = 0.5    # below this the sequence is taken as not yet asymptotic
SAFETY = 0.8       # a predicted mesh size aims at this fraction of the target
MIN_RATIO, MAX_RATIO = 1.5, 3.0  # the refinement a prediction may choose


@dataclass
class Estimate:
    """The error estimate of the finest value of a sequence: the extrapolated limit (NaN when none),
    the estimated absolute error of the finest value (FACTOR times the rule's), the observed order
    (NaN when none) and which rule gave the estimate."""

    extrapolated: float
    error: float
    order: float
    kind: str


def observed_order(sizes: list[float], values: list[float]) -> float:
    """p with (f1 - f2)/(f2 - f3) = (h1^p - h2^p)/(h2^p - h3^p) for the last three meshes, by
    bisection (the right side grows with p from ln(h1/h2)/ln(h2/h3) at p = 0); 0 when the ratio lies
    below that (the differences do not shrink: no convergence seen), NaN when the differences change
    sign."""
    (h1, h2, h3), (f1, f2, f3) = sizes[-3:], values[-3:]
    if (f1 - f2) * (f2 - f3) <= 0:
        return math.nan
    ratio = (f1 - f2) / (f2 - f3)

    def model(p: float) -> float:
        return (h1**p - h2**p) / (h2**p - h3**p)

    if ratio <= math.log(h1 / h2) / math.log(h2 / h3):
        return 0.0
    low, high = 1e-9, 1.0
    while model(high) < ratio:
        low, high = high, 2 * high
        if high > 64:
            return high
    for _ in range(100):
        middle = 0.5 * (low + high)
        low, high = (middle, high) if model(middle) < ratio else (low, middle)
    return 0.5 * (low + high)


def richardson_error(sizes: list[float], values: list[float], order: float) -> tuple[float, float]:
    """The extrapolated value and the finest value's error for an order p (last three meshes)."""
    (h2, h3), (f2, f3) = sizes[-2:], values[-2:]
    correction = (f2 - f3) * h3**order / (h2**order - h3**order)
    return f3 - correction, abs(correction)


def estimate(sizes: list[float], values: list[float], degree: int) -> Estimate:
    """The error estimate of the finest of at least three values on meshes of decreasing sizes
    (module docstring): Richardson's when the observed order lies in [MIN_ORDER, 2(degree + 1)],
    else the guarded, less optimistic one."""
    if len(values) < 3:
        raise ValueError("an observed order needs three meshes")
    last = abs(values[-1] - values[-2])
    if last == 0:
        return Estimate(values[-1], 0.0, math.nan, "the last two values agree")
    order = observed_order(sizes, values)
    if math.isnan(order):
        return Estimate(math.nan, FACTOR * last, math.nan,
                        "oscillating: the last two values' difference, no extrapolation")
    highest = 2.0 * (degree + 1)
    if MIN_ORDER <= order <= highest:
        limit, error = richardson_error(sizes, values, order)
        return Estimate(limit, FACTOR * error, order, "richardson")
    clipped = min(max(order, MIN_ORDER), highest)
    limit, error = richardson_error(sizes, values, clipped)
    return Estimate(limit, FACTOR * max(error, last), order,
                    f"observed order {order:.3g} outside [{MIN_ORDER:g}, {highest:g}] (not "
                    f"asymptotic): the larger of Richardson's with order {clipped:g} and the last "
                    "two values' difference")


def relative(found: Estimate, value: float) -> float:
    """The estimated error relative to the extrapolated value (to the finest when none)."""
    reference = found.extrapolated if math.isfinite(found.extrapolated) else value
    return found.error / abs(reference) if reference != 0 else math.inf


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

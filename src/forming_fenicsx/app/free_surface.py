"""The free surfaces the flow decides: the flow solved on the scene's domain, then alternately the
surface made of streamlines of the last flow (post/free_surface.py) and the flow solved again on
the workpiece re-meshed under it (mesh/geometry.shaped_mesh), started from the last velocity
interpolated onto the new mesh (mesh/transfer.py), until the surfaces move by less than
free_surface.tolerance times the exit half-size and the stock's streamline meets the die wall
within that (docs/free_surface.md).

A shape that still moves needs its flow's velocity, not its forces: those flows are drafts, solved
without the force-balance criterion (solver.force_tolerance), and Newton's started from the last
flow without its secant start. The last shape's draft is solved on to the scene's own rules on the
same mesh, and the shape judged again on that flow (Example 2 at mu = 0.4: 83 linear solves
instead of 102, docs/free_surface.md).
"""
from __future__ import annotations

import dataclasses
import logging
import time
from typing import Any, Callable

import numpy as np
from mpi4py import MPI

from forming_fenicsx.config.scene import Scene
from forming_fenicsx.fem.forms import FlowProblem
from forming_fenicsx.mesh.free_shape import FreeShape, fixed_shape, wall_area
from forming_fenicsx.mesh.geometry import shaped_mesh
from forming_fenicsx.mesh.quality import folded_cells
from forming_fenicsx.post.free_surface import SurfaceNotFound, shape_change, updated_shape
from forming_fenicsx.solvers.records import SolveResult

log = logging.getLogger(__name__)

Solve = Callable[[Scene, "FlowProblem | None", "Callable[[], None] | None"],
                 tuple[FlowProblem, SolveResult, dict[str, Any]]]
Complete = Callable[[FlowProblem, SolveResult, dict[str, Any]], dict[str, Any]]


def solve_free_surface(scene: Scene, solve: Solve, comm: MPI.Comm = MPI.COMM_WORLD,
                       complete: Complete | None = None
                       ) -> tuple[FlowProblem, SolveResult, dict[str, Any], FreeShape]:
    """Alternate ``solve(variant, previous, generate)`` (run.solve_scene of the scene ``variant``
    on the mesh ``generate`` makes, started from the solved problem ``previous``: its velocity and
    contact multiplier) with the surface update (module
    docstring). A shape that still moves is updated from a draft flow (_draft); the flow the run
    reports, on the last shape, meets the scene's own rules. Returns the last solve's problem,
    iteration and summary, the summary with a ``free_surface`` table, and the shape the last solve
    had. ``complete(problem, result, summary)``: the last solve's summary made whole, where
    ``solve`` gives only what the update reads (run.solve_scene's lite summaries: the flows of
    shapes that move on are not post-processed in full)."""
    settings = scene.free_surface
    h1 = 0.5 * scene.geometry.exit_thickness
    start = time.perf_counter()
    shape = fixed_shape(scene)
    draft = _draft(scene)
    solves, moved, converged = 0, 0, False

    def solved(variant: Scene, previous: FlowProblem | None,
               generate: Callable[[], None] | None
               ) -> tuple[FlowProblem, SolveResult, dict[str, Any]]:
        """``solve``, its linear solves counted into the run's."""
        nonlocal solves
        outcome = solve(variant, previous, generate)
        solves += outcome[2]["linear_solves"]
        return outcome

    problem, result, summary = solved(draft, None, None)

    def drafted() -> bool:  # the flow does not meet the scene's own rules
        return draft is not scene and not summary["force_balance_residual"] \
            < scene.solver.force_tolerance

    def finished() -> tuple[FlowProblem, SolveResult, dict[str, Any]]:
        """The draft flow solved on to the scene's own rules, on its shape's mesh."""
        return solved(_warm(scene), problem, None if moved == 0 else
                      _mesher(scene, shape, comm))

    updates: list[dict[str, Any]] = []
    stopped = ""  # why the update stopped before the surface settled, if it did
    while summary["iteration_converged"]:
        try:
            new = updated_shape(problem, shape, summary.get("contact_end_x"))  # none: square
        except SurfaceNotFound as error:  # this shape stands
            if drafted():
                problem, result, summary = finished()
            stopped = (f"the free surface's update {moved + 1} could not be made: {error} "
                       f"({error.cause}); the update stopped, and the shape and the forces are "
                       f"those of update {moved}")
            break
        move = max(shape_change(shape, new, scene.geometry.length), new.stock_miss) / h1
        updates.append({"linear_solves": summary["linear_solves"],
                        "wall_time_s": summary["wall_time_s"],
                        "free_surface_crossing": summary["free_surface_crossing"],
                        **shape_scalars(scene, shape), "surface_move": move,
                        "stock_miss": new.stock_miss / h1, "draft": drafted()})
        if comm.rank == 0:
            log.info("free surface after %d updates: crossing %.3g %%, the next update moves it "
                     "%.3g of the exit half-size", moved, 100 * summary["free_surface_crossing"],
                     move)
        converged = bool(move < settings.tolerance)
        if (converged or moved == settings.max_updates) and drafted():  # the last shape: its
            # flow finished, and the shape judged again on it
            problem, result, summary = finished()
            continue
        if converged or moved == settings.max_updates:
            break
        last = problem, result, summary, shape
        shape, moved = new, moved + 1
        problem, result, summary = solved(_warm(draft), problem, _mesher(scene, shape, comm))
        folded = folded_cells(problem.mesh)
        failed = "" if summary["iteration_converged"] else summary["reason"]
        if folded or failed:  # the last shape's solve stands: this mesh's cannot be trusted
            # (quality.py), or its flow was not found
            problem, result, summary, shape = last
            moved -= 1
            if drafted():
                problem, result, summary = finished()
            why = (f"re-meshed the workpiece with {folded} folded cells (not convex)" if folded
                   else f"gave a flow that did not converge ({failed})")
            stopped = (f"the free surface's update {moved + 1} {why}: the update stopped, and "
                       f"the shape and the forces are those of update {moved}")
            break
    if complete is not None:
        summary = complete(problem, result, summary)
    summary["scene"] = scene.to_dict()  # the scene's, not a draft's or a warm start's
    summary["free_surface"] = {
        "converged": converged, "updates": moved, "tolerance": settings.tolerance,
        **shape_scalars(scene, shape), "history": updates, "linear_solves": solves,
        "wall_time_s": comm.allreduce(time.perf_counter() - start, op=MPI.MAX)}
    if stopped:
        summary["warnings"].append(stopped)
    elif not converged and summary["converged"]:
        summary["warnings"].append(
            f"the free surface did not settle in free_surface.max_updates = "
            f"{settings.max_updates} updates (the last moved it {updates[-1]['surface_move']:.3g} "
            f"of the exit half-size, tolerance {settings.tolerance:g}): the shape and the "
            "forces are those of the last update")
    if shape.wall is not None:  # the square die's face stays whole
        summary["die_contact_fraction"] *= (wall_area(shape.wall, scene.geometry.axisymmetric)
                                            / wall_area(scene.geometry.profile(),
                                                        scene.geometry.axisymmetric))
    return problem, result, summary, shape


def shape_scalars(scene: Scene, shape: FreeShape) -> dict[str, float]:
    """The product's exit size (full thickness or diameter) and its change from the die's exit
    size, and where the contact with the die starts and ends."""
    g = scene.geometry
    size = f"exit_{g.thickness_name}"
    # the square die: its face at x = die_position, the product leaving it at the corner
    start, end = ((g.die_position, g.die_position) if shape.wall is None
                  else (shape.wall.start[0], shape.wall.end[0]))
    return {size: 2 * shape.exit_height,
            f"{size}_change": shape.exit_height / (0.5 * g.exit_thickness) - 1,
            "contact_start_x": start, "contact_end_x": end}


def surface_lines(shape: FreeShape) -> dict[str, np.ndarray]:
    """The free surfaces found, by name: "stock", before a drawing die (when it was updated), and
    "product", after the die."""
    stock = {} if shape.upstream is None else {"stock": shape.upstream}
    return {**stock, "product": shape.downstream}


def _draft(scene: Scene) -> Scene:
    """The scene whose flow a shape that still moves is updated from: without the force-balance
    criterion (solver.force_tolerance), which only the forces of the last shape need."""
    if scene.solver.force_tolerance == 0:
        return scene
    return dataclasses.replace(scene, solver=dataclasses.replace(scene.solver,
                                                                 force_tolerance=0.0))


def _warm(scene: Scene) -> Scene:
    """The scene for a solve started from the last flow: Newton without its secant start (from a
    converged flow those secant iterates moved the copper wire's velocity by 6 % and back)."""
    return dataclasses.replace(scene, solver=dataclasses.replace(scene.solver, secant_start=0))


def _mesher(scene: Scene, shape: FreeShape, comm: MPI.Comm) -> Callable[[], None] | None:
    return shaped_mesh(scene, shape) if comm.rank == 0 else None

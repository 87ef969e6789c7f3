"""Error against unknowns on uniform, graded and adapted meshes (docs/accuracy.md).

Each case is an accuracy sequence (accuracy.solve_to_accuracy, as `forming run --accuracy` runs it)
with an unreachable target, for a fixed number of meshes: uniform (the scene's blocks with
corner_grading = 1, refined), graded (corner_grading as given, refined) and adapted (the recovered
strain-rate indicator, mesh/adapted.py). Printed per mesh: the unknowns, the value, its error
against the exact value, the observed order in the unknowns N (error ~ N^-q from the previous mesh;
2q is the order in a mesh size) and the level's wall time. "graded 8" and "graded 64" grade toward
the die's corners only (wall_grading 1), "graded" is the defaults' grading (corner_grading 64,
wall_grading 16 along the die segments and toward the die wall; the square die has no wall
grading, so for Example 1 it is "graded 64").

The exact cone flow (verification.radial_flow, Norton n = 0.2) has its own sector mesh: uniform,
graded toward the exit cap (CONE_GRADING) and adapted (the same indicator and size field on the
sector); the exit stress's error and the velocity's H1 error against the exact field.
Run: .venv/bin/python demos/mesh_convergence.py (one rank, about 4 minutes)
"""
from __future__ import annotations

import argparse
import math
from pathlib import Path

from mpi4py import MPI

from forming_fenicsx.app.run import solve_scene
from forming_fenicsx.app.study import exact_value
from forming_fenicsx.config.loader import load_scene
from forming_fenicsx.core.report import markdown_table
from forming_fenicsx.solvers.accuracy import adapted_mesh, solve_to_accuracy
from forming_fenicsx.verification.verification import (add_sector, radial_errors, radial_problem,
                                                       sector_mesh, solve_radial)

DEMOS = Path(__file__).parent
NEWTON = ["solver.method=newton", "discretisation.averaging=quadrature", "output.fields=false",
          "output.figures=false", "accuracy.target=1e-6"]
EXACT_FIELD = ["material.rate2=1e9", "material.alpha=1e-4"]  # as in accuracy_honesty.py
# (case, scene, overrides, meshes)
CASES = {
    "example1": ("example1_extrusion.toml", [], 4),
    "exact_drawing": ("example2_exact_field.toml", EXACT_FIELD, 4),
}
UNIFORM = ["discretisation.corner_grading=1", "discretisation.wall_grading=1"]
KINDS = {"uniform": [*UNIFORM, "accuracy.meshes=refined"],
         "graded 8": [*UNIFORM[1:], "discretisation.corner_grading=8", "accuracy.meshes=refined"],
         "graded 64": [*UNIFORM[1:], "discretisation.corner_grading=64",
                       "accuracy.meshes=refined"],
         "graded": ["discretisation.corner_grading=64", "discretisation.wall_grading=16",
                    "accuracy.meshes=refined"],
         "adapted": ["accuracy.meshes=adapted"]}
CONE_CELLS, CONE_N, CONE_GRADING = (4, 8, 16, 32), 0.2, 4.0
# Newton's tolerance on the cone (docs/accuracy.md's table): chosen while the line search still cut
# the last steps on the adapted meshes at radial_problem's 1e-8; since it takes the full steps Phi
# cannot judge (newton.ENERGY_ROUNDING) 1e-8 converges too (tests/test_adapted_meshes.py)
CONE_TOLERANCE = 1e-7


def order_in_n(error: float, dofs: int, error_before: float, dofs_before: int) -> float:
    """q of error ~ N^-q between two meshes of N = dofs_before and dofs unknowns."""
    return -math.log(error / error_before) / math.log(dofs / dofs_before)


def rows_of(name: str, kind: str, comm, extra: tuple[str, ...] = (),
            levels: int | None = None) -> list[list]:
    """The case's sequence of ``kind`` (``extra`` overrides, ``levels`` meshes instead of its
    own): a row per mesh."""
    path, overrides, own = CASES[name]
    scene = load_scene(DEMOS / path, [*NEWTON, *overrides, *KINDS[kind], *extra,
                                      f"accuracy.max_levels={levels or own}"])
    accuracy = solve_to_accuracy(scene, lambda level, previous, generate: solve_scene(
        level, comm=comm, previous=previous, generate=generate), comm)[2]["accuracy"]
    exact = exact_value(scene, accuracy["quantity"])
    rows, before = [], None
    for mesh in accuracy["meshes"]:
        error = abs(mesh[accuracy["quantity"]] / exact - 1)
        order = order_in_n(error, mesh["dofs"], before[1], before[0]) if before else math.nan
        rows.append([name, kind, f"{mesh['mesh_size']:.4g}", mesh["dofs"],
                     f"{mesh[accuracy['quantity']]:.6g}", f"{100 * error:.3g} %",
                     f"{order:.2f}" if before else "", f"{2 * order:.2f}" if before else "",
                     f"{mesh['wall_time_s']:.2f}"])
        before = (mesh["dofs"], error)
    return rows


def cone_rows(kind: str, comm, cells: tuple[int, ...] = CONE_CELLS) -> list[list]:
    """The exact cone flow on ``kind`` meshes (uniform, graded or adapted: its first mesh the
    uniform one of cells[0], each next with four times the cells): a row per mesh."""
    rows, before, generate = [], None, None
    for level, count in enumerate(cells):
        forming_mesh = sector_mesh(count, 2, comm, CONE_GRADING if kind == "graded" else 1.0,
                                   generate if level else None)
        problem = radial_problem("axisymmetric", CONE_N, "Q2", count, comm=comm,
                                 tolerance=CONE_TOLERANCE, forming_mesh=forming_mesh)
        start = MPI.Wtime()
        found = radial_errors(problem, solve_radial(problem), CONE_N)
        seconds = MPI.Wtime() - start
        if kind == "adapted":
            generate = adapted_mesh(problem, 4.0,
                                    lambda: add_sector(0, structured=False))
        dofs = problem.unknowns
        errors = (abs(found["exit_stress"] / found["exact_exit_stress"] - 1), found["h1"])
        orders = [order_in_n(e, dofs, b, before[0])
                  for e, b in zip(errors, before[1], strict=True)] if before else []
        rows.append(["cone n = 0.2", kind, dofs, f"{100 * errors[0]:.3g} %",
                     f"{orders[0]:.2f}" if before else "", f"{errors[1]:.3g}",
                     f"{orders[1]:.2f}" if before else "", f"{seconds:.2f}"])
        before = (dofs, errors)
    return rows


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--cases", nargs="*", default=list(CASES), choices=list(CASES))
    parser.add_argument("--kinds", nargs="*", default=list(KINDS), choices=list(KINDS))
    parser.add_argument("--no-cone", dest="cone", action="store_false",
                        help="leave out the exact cone flow")
    args = parser.parse_args()
    comm = MPI.COMM_WORLD
    rows = [row for name in args.cases for kind in args.kinds for row in rows_of(name, kind, comm)]
    header = ["case", "meshes", "h", "dofs", "value", "error", "order in N", "order in h",
              "wall s"]
    cone = ([row for kind in ("uniform", "graded", "adapted") for row in cone_rows(kind, comm)]
            if args.cone else [])
    if comm.rank == 0:
        print(markdown_table(None, header, rows))
        if cone:
            print("\n" + markdown_table(None, ["case", "meshes", "dofs", "exit stress error",
                                               "order in N", "H1 error", "order in N",
                                               "wall s"], cone))


if __name__ == "__main__":
    main()

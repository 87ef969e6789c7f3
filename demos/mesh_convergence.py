"""Error against unknowns on uniform, graded and adapted meshes (docs/accuracy.md).

Each case is an accuracy sequence (accuracy.solve_to_accuracy, as `forming run --accuracy` runs it)
with an unreachable target, for a fixed number of meshes: uniform (the scene's blocks with
corner_grading = 1, refined), graded (corner_grading as given, refined) and adapted (the recovered
strain-rate indicator, mesh/adapted.py). Printed per mesh: the unknowns, the value, its error
against the exact value, the observed order in the unknowns N (error ~ N^-q from the previous mesh;
2q is the order in a mesh size) and the level's wall time.
Run: .venv/bin/python demos/mesh_convergence.py (one rank, about 3 minutes)
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
from forming_fenicsx.solvers.accuracy import solve_to_accuracy

DEMOS = Path(__file__).parent
NEWTON = ["solver.method=newton", "discretisation.averaging=quadrature", "output.fields=false",
          "output.figures=false", "accuracy.target=1e-6"]
EXACT_FIELD = ["material.rate2=1e9", "material.alpha=1e-4"]  # as in accuracy_honesty.py
# (case, scene, overrides, meshes)
CASES = {
    "example1": ("example1_extrusion.toml", [], 4),
    "exact_drawing": ("example2_exact_field.toml", EXACT_FIELD, 4),
}
KINDS = {"uniform": ["discretisation.corner_grading=1", "accuracy.meshes=refined"],
         "graded 8": ["discretisation.corner_grading=8", "accuracy.meshes=refined"],
         "graded 64": ["discretisation.corner_grading=64", "accuracy.meshes=refined"],
         "adapted": ["accuracy.meshes=adapted"]}


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
        order = (-math.log(error / before[1]) / math.log(mesh["dofs"] / before[0])
                 if before else math.nan)
        rows.append([name, kind, f"{mesh['mesh_size']:.4g}", mesh["dofs"],
                     f"{mesh[accuracy['quantity']]:.6g}", f"{100 * error:.3g} %",
                     f"{order:.2f}" if before else "", f"{2 * order:.2f}" if before else "",
                     f"{mesh['wall_time_s']:.2f}"])
        before = (mesh["dofs"], error)
    return rows


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--cases", nargs="*", default=list(CASES), choices=list(CASES))
    parser.add_argument("--kinds", nargs="*", default=list(KINDS), choices=list(KINDS))
    args = parser.parse_args()
    comm = MPI.COMM_WORLD
    rows = [row for name in args.cases for kind in args.kinds for row in rows_of(name, kind, comm)]
    header = ["case", "meshes", "h", "dofs", "value", "error", "order in N", "order in h",
              "wall s"]
    if comm.rank == 0:
        print(markdown_table(None, header, rows))


if __name__ == "__main__":
    main()

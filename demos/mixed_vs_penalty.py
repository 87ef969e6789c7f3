# # The mixed formulation against the penalty one as d -> 0 (Theorem 3.1)
#
#     mpirun -n 2 python demos/mixed_vs_penalty.py [--out results/mixed_vs_penalty]
#
# Example 1 (mu = 0, h = 0.25 and 0.125) and Example 2 (mu = 0.2, Q2 reduced, h = 0.05): the penalty
# problem for d from the paper's value down by four decades, and the mixed formulation (Q2 velocity,
# discontinuous P1 pressure). For each run: the process quantity, ||div u||, the mean hydrostatic
# pressure on the ram face (extrusion), and the L2 distance of its pressure field (element means of
# -sigma_H) from the mixed one, relative to the mixed one. docs/solvers.md shows a run.

import argparse
import json
from pathlib import Path

import numpy as np
import ufl
from mpi4py import MPI

import dolfinx.fem
import dolfinx.fem.petsc

from forming_fenicsx import load_scene
from forming_fenicsx.fem.projection import cell_means
from forming_fenicsx.core.report import markdown_table
from forming_fenicsx.core.richardson import richardson
from forming_fenicsx.app.run import solve_scene

DEMOS = Path(__file__).parent
CASES = [("Example 1, h = 0.25", DEMOS / "example1_extrusion.toml",
          ["discretisation.mesh_size=0.25"], 1e-3),
         ("Example 1, h = 0.125", DEMOS / "example1_extrusion.toml",
          ["discretisation.mesh_size=0.125"], 1e-3),
         ("Example 2, mu = 0.2, h = 0.05", DEMOS / "example2_drawing_mu02.toml",
          ["discretisation.mesh_size=0.05", "discretisation.element=Q2",
           "discretisation.volumetric_integration=reduced"],
          5e-3)]
COMMON = ["solver.method=direct", "solver.force_tolerance=1e-3", "solver.max_iterations=1000",
          "output.fields=false", "output.figures=false"]


def pressure_means(problem) -> np.ndarray:
    """Element means of -sigma_H, gathered on every rank in cell order of the original mesh
    input."""
    means = cell_means(problem.mesh, -problem.hydrostatic_stress(), "pressure", problem.full_degree)
    cells = problem.mesh.topology.index_map(problem.mesh.topology.dim).size_local
    original = problem.mesh.topology.original_cell_index[:cells]
    order = np.concatenate(problem.comm.allgather(original))
    values = np.concatenate(problem.comm.allgather(means.x.array[:cells]))
    volume = dolfinx.fem.form(ufl.TestFunction(means.function_space) * ufl.dx)
    sizes = dolfinx.fem.petsc.assemble_vector(volume)
    areas = np.concatenate(problem.comm.allgather(sizes.array[:cells]))
    result = np.empty((order.size, 2))
    result[order] = np.column_stack([values, areas])
    return result


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--out", default="results/mixed_vs_penalty")
    args = parser.parse_args()
    rank0 = MPI.COMM_WORLD.rank == 0
    rows = []
    for title, scene_file, settings, d0 in CASES:
        problem, _, mixed = solve_scene(load_scene(
            scene_file, [*settings, *COMMON, "discretisation.formulation=mixed"]))
        reference = pressure_means(problem)
        quantity = "ram_pressure" if "ram_pressure" in mixed else "mean_die_pressure"
        case_rows = []
        for d in (d0, d0 / 10, d0 / 100, d0 / 1000, d0 / 10000):
            problem, _, summary = solve_scene(load_scene(scene_file,
                                                         [*settings, *COMMON, f"penalty.d={d}"]))
            field = pressure_means(problem)
            difference = np.sqrt(np.sum(reference[:, 1] * (field[:, 0] - reference[:, 0]) ** 2)
                                 / np.sum(reference[:, 1] * reference[:, 0] ** 2))
            case_rows.append({"case": title, "formulation": "penalty", "d": d, **summary,
                              "field_difference": difference})
        # O(d): the limit from the three smallest d (the extrapolation needs no particular ratio),
        # or the smallest d's value where rounding makes the differences non-monotone
        limit = richardson([r["d"] for r in case_rows], [r[quantity] for r in case_rows])[0]
        limit = limit if np.isfinite(limit) else case_rows[-1][quantity]
        mixed.update(case=title, formulation="mixed", d=0.0, field_difference=0.0)
        for row in [*case_rows, mixed]:
            row["quantity"], row["value"] = quantity, row[quantity]
            row["vs_penalty_limit"] = row[quantity] / limit - 1
        rows += [*case_rows, mixed]
    for row in rows:
        row.pop("scene", None)
    if rank0:
        print(markdown_table(
            "Mixed against penalty "
            "(the penalty limit d -> 0 extrapolated from the three smallest d)",
            ["case", "formulation", "d", "quantity", "value", "vs penalty limit",
             "L2 norm of div u", "p_av", "pressure field vs mixed", "linear solves", "dofs"],
            [[r["case"], r["formulation"], r["d"], r["quantity"], r["value"],
              f"{100 * r['vs_penalty_limit']:+.3f}%", f"{r['divergence_l2']:.2e}",
              r.get("mean_hydrostatic_pressure", ""), f"{r['field_difference']:.2e}",
              r["linear_solves"], r["dofs"]] for r in rows]))
        out = Path(args.out)
        out.mkdir(parents=True, exist_ok=True)
        (out / "mixed_vs_penalty.json").write_text(json.dumps(rows, indent=1, default=str))


if __name__ == "__main__":
    main()

# # Example 1 measured: mesh convergence, the penalty's effect on p_av, and the two secant methods
#
#     mpirun -n 2 python demos/example1_study.py [--sizes 0.5 0.25 0.125 0.0625]
#                                                [--out results/example1_study]
#
# Prints three tables (markdown) and writes them as JSON. docs/example1.md shows one run of it.

import argparse
import json
import math
from pathlib import Path

from mpi4py import MPI

from forming_fenicsx import load_scene
from forming_fenicsx.post.ram_face import ram_face_pressure_model
from forming_fenicsx.core.report import markdown_table
from forming_fenicsx.core.richardson import richardson
from forming_fenicsx.app.run import solve_scene

HILL = 1 + math.pi / 2
parser = argparse.ArgumentParser()
parser.add_argument("--scene", default=str(Path(__file__).with_name("example1_extrusion.toml")))
parser.add_argument("--sizes", type=float, nargs="+", default=[0.5, 0.25, 0.125, 0.0625])
parser.add_argument("--grading", type=float, default=8.0)
parser.add_argument("--penalties", type=float, nargs="+", default=[1e-2, 1e-3, 1e-4, 1e-5, 1e-6])
PARTS = ["mesh", "penalty", "methods", "tolerance", "elements", "regularisation"]
parser.add_argument("--parts", nargs="+", default=PARTS, choices=PARTS)
parser.add_argument("--out", default="results/example1_study")
args = parser.parse_args()
rank0 = MPI.COMM_WORLD.rank == 0


def run(*overrides: str) -> dict:
    summary = solve_scene(load_scene(args.scene, list(overrides)))[2]
    summary.pop("scene")
    return summary


def table(title: str, header: list[str], rows: list[list]) -> None:
    if rank0 and rows:
        print(markdown_table(title, header, rows))


results: dict = {part: [] for part in PARTS}
grading = f"discretisation.corner_grading={args.grading}"

# ## 1. Ram pressure under mesh refinement (mu = 0, direct method)
for size in args.sizes if "mesh" in args.parts else []:
    s = run(f"discretisation.mesh_size={size}", grading, "solver.method=direct")
    results["mesh"].append({"mesh_size": size, **s})
if len(results["mesh"]) >= 3:
    pressures = [r["ram_pressure"] for r in results["mesh"]]
    limit, order = richardson([r["mesh_size"] for r in results["mesh"]], pressures)
    results["extrapolated_ram_pressure"] = {"value": limit, "order": order, "hill": HILL,
                                            "relative_error": limit / HILL - 1}
    table(f"Ram pressure, mu = 0, Q2 reduced, grading {args.grading} (Hill {HILL:.4f})",
          ["h", "dofs", "ram pressure", "error vs Hill", "p_av", "force balance", "linear solves",
           "wall s"],
          [[r["mesh_size"], r["dofs"], r["ram_pressure"],
            f"{100 * (r['ram_pressure'] / HILL - 1):+.2f}%", r["mean_hydrostatic_pressure"],
            f"{r['force_balance_residual']:.1e}", r["linear_solves"],
            round(r["wall_time_s"], 1)] for r in results["mesh"]]
          + [["extrapolated", "", limit, f"{100 * (limit / HILL - 1):+.2f}%", f"order {order:.2f}",
              "", "", ""]])

# ## 2. p_av against the penalty d (mu = 0, h = 0.25)
scene = load_scene(args.scene)
law = scene.material
for d in args.penalties if "penalty" in args.parts else []:
    s = run("discretisation.mesh_size=0.25", grading, "solver.method=direct", f"penalty.d={d}")
    model = ram_face_pressure_model(law, d, s["ram_pressure"])
    results["penalty"].append({"d": d, "rigid_zone_model": model, **s})
table("p_av on the ram face against d (h = 0.25)",
      ["d", "ram pressure", "p_av", "rigid-zone model of p_av", "L2 norm of div u",
       "linear solves"],
      [[r["d"], r["ram_pressure"], r["mean_hydrostatic_pressure"], r["rigid_zone_model"],
        r["divergence_l2"], r["linear_solves"]] for r in results["penalty"]])

# ## 3. Direct (3.13) and modified (3.33) methods at delta = 1e-4, demo mesh
for mu in (0.0, 0.1) if "methods" in args.parts else []:
    for method in ("direct", "modified"):
        s = run(f"friction.mu={mu}", f"solver.method={method}")
        results["methods"].append({"mu": mu, "method": method, **s})
table("Secant-modulus methods, delta = 1e-4, demo scene mesh",
      ["mu", "method", "linear solves", "outer iterations", "wall s", "ram pressure",
       "force balance"],
      [[r["mu"], r["method"], r["linear_solves"], r["outer_iterations"], round(r["wall_time_s"], 1),
        r["ram_pressure"], f"{r['force_balance_residual']:.1e}"] for r in results["methods"]])

# ## 4. The stopping tolerance delta and the force balance (mu = 0.1, h = 0.25)
for tolerance in (1e-4, 1e-5, 1e-6) if "tolerance" in args.parts else []:
    for method in ("direct", "modified"):
        s = run("discretisation.mesh_size=0.25", grading, "friction.mu=0.1",
                f"solver.method={method}", f"solver.tolerance={tolerance}",
                "solver.max_iterations=5000")
        results["tolerance"].append({"tolerance": tolerance, "method": method, **s})
table("Stopping tolerance against force balance (mu = 0.1, h = 0.25)",
      ["delta", "method", "linear solves", "outer iterations", "ram pressure",
       "die friction force x", "force balance"],
      [[r["tolerance"], r["method"], r["linear_solves"], r["outer_iterations"], r["ram_pressure"],
        r["die_friction_force_x"], f"{r['force_balance_residual']:.1e}"]
       for r in results["tolerance"]])

# ## 5. Elements and volumetric quadrature (mu = 0, h = 0.25, direct method)
variants = [("Q2", "reduced", "nodes"), ("Q2", "reduced", "centres"), ("Q2", "complete", "nodes"),
            ("Q1", "reduced", "nodes"), ("Q1", "complete", "nodes")]
for element, quadrature, averaging in variants if "elements" in args.parts else []:
    s = run("discretisation.mesh_size=0.25", grading, "solver.method=direct",
            f"discretisation.element={element}",
            f"discretisation.volumetric_integration={quadrature}",
            f"discretisation.averaging={averaging}")
    results["elements"].append({"element": element, "volumetric_integration": quadrature,
                                "averaging": averaging, **s})
table("Elements, volumetric quadrature and averaging (mu = 0, h = 0.25, grading 8)",
      ["element", "volumetric", "averaging", "dofs", "ram pressure", "error vs Hill",
       "linear solves"],
      [[r["element"], r["volumetric_integration"], r["averaging"], r["dofs"], r["ram_pressure"],
        f"{100 * (r['ram_pressure'] / HILL - 1):+.2f}%", r["linear_solves"]]
       for r in results["elements"]])

# ## 6. The friction regularisation d_T -> 0 (mu = 0.1, h = 0.5, direct method)
for d_T in (1e-1, 1e-2, 1e-3, 1e-4, 1e-6) if "regularisation" in args.parts else []:
    s = run("discretisation.mesh_size=0.5", grading, "friction.mu=0.1", "solver.method=direct",
            f"friction.d_T={d_T}")
    results["regularisation"].append({"d_T": d_T, **s})
table("Friction regularisation (mu = 0.1, h = 0.5)",
      ["d_T", "ram pressure", "die friction force x", "linear solves"],
      [[r["d_T"], r["ram_pressure"], r["die_friction_force_x"], r["linear_solves"]]
       for r in results["regularisation"]])

if rank0:
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "example1_study.json").write_text(json.dumps(results, indent=2))
    print(f"\nwritten {out / 'example1_study.json'}")

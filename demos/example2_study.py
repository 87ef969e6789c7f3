# # Example 2 measured: drawing through a 6 degree die against the paper and the slip-line solution
#
#     mpirun -n 2 python demos/example2_study.py [--sizes 0.1 0.05 0.025]
#                                                [--out results/example2_study]
#
# Prints markdown tables and writes them as JSON; docs/example2.md shows one run.

import argparse
import json
import math
from pathlib import Path

from mpi4py import MPI

from forming_fenicsx import load_scene
from forming_fenicsx.core.report import markdown_table
from forming_fenicsx.core.richardson import richardson
from forming_fenicsx.app.run import solve_scene

PAPER_Q = {0.0: 243.0, 0.2: 255.0, 0.4: 273.0}
SLIP_LINE_Q = 250.0
PARTS = ["table", "measures", "drive", "penalty", "rate", "exact", "secant", "methods"]
parser = argparse.ArgumentParser()
parser.add_argument("--scene", default=str(Path(__file__).with_name("example2_drawing.toml")))
parser.add_argument("--sizes", type=float, nargs="+", default=[0.1, 0.05, 0.025])
parser.add_argument("--parts", nargs="+", default=PARTS, choices=PARTS)
parser.add_argument("--mu", type=float, nargs="+", default=[0.0, 0.2, 0.4], choices=[0.0, 0.2, 0.4],
                    help="friction coefficients of the reproduction table")
parser.add_argument("--elements", nargs="+", default=["Q1 complete", "Q2 reduced"],
                    choices=["Q1 complete", "Q2 reduced"],
                    help="elements of the reproduction table")
parser.add_argument("--out", default="results/example2_study")
args = parser.parse_args()
rank0 = MPI.COMM_WORLD.rank == 0
geometry = load_scene(args.scene).geometry
h0, h1 = geometry.entry_thickness, geometry.exit_thickness
cot = 1 / math.tan(math.radians(geometry.die_angle))
ELEMENTS = {"Q1 complete": ["discretisation.element=Q1",
                            "discretisation.volumetric_integration=complete"],
            "Q2 reduced": ["discretisation.element=Q2",
                           "discretisation.volumetric_integration=reduced"]}
CONVERGED = ["solver.method=direct", "solver.force_tolerance=1e-3", "solver.max_iterations=2000",
             "output.fields=false", "output.figures=false"]


def run(*overrides: str) -> dict:
    summary = solve_scene(load_scene(args.scene, list(overrides)))[2]
    summary.pop("scene")
    summary["projected_die_pressure"] = summary["die_normal_force_x"] / (h0 - h1)  # both halves
    return summary


def table(title: str, header: list[str], rows: list[list]) -> None:
    if rank0 and rows:
        print(markdown_table(title, header, rows))


results: dict = {part: [] for part in PARTS}
results["extrapolated"] = []

# ## 1. The reproduction table: q_av and drawing stress for each mu, element and mesh
for mu in args.mu if "table" in args.parts else []:
    for element in args.elements:
        settings = ELEMENTS[element]
        rows = []
        for size in args.sizes:
            s = run(f"friction.mu={mu}", f"discretisation.mesh_size={size}", *settings, *CONVERGED)
            rows.append({"mu": mu, "element": element, "mesh_size": size, **s})
        results["table"].extend(rows)
        if len(rows) >= 3:
            for key in ("mean_die_pressure", "drawing_stress", "projected_die_pressure"):
                limit, order = richardson(args.sizes, [r[key] for r in rows])
                results["extrapolated"].append({"mu": mu, "element": element, "quantity": key,
                                                "value": limit, "order": order})
table("q_av and drawing stress (direct method to delta = 1e-4 and force balance < 1e-3)",
      ["mu", "element", "h", "dofs", "q_av", "paper q_av", "q projected", "drawing stress",
       "sigma_d from paper q", "contact end x", "force balance", "linear solves"],
      [[r["mu"], r["element"], r["mesh_size"], r["dofs"], r["mean_die_pressure"], PAPER_Q[r["mu"]],
        r["projected_die_pressure"], r["drawing_stress"],
        PAPER_Q[r["mu"]] * (h0 - h1) * (1 + r["mu"] * cot) / h1,
        r["contact_end_x"], f"{r['force_balance_residual']:.1e}", r["linear_solves"]]
       for r in results["table"]])
table("Extrapolated (Richardson on the three finest meshes)",
      ["mu", "element", "quantity", "value", "order"],
      [[e["mu"], e["element"], e["quantity"], e["value"], e["order"]]
       for e in results["extrapolated"]])

# ## 2. How q_av is measured (mu = 0, h = 0.05): penalty or stress, with or without the die-entry
# spike
size = args.sizes[len(args.sizes) // 2]
for element, settings in ELEMENTS.items() if "measures" in args.parts else []:
    for pressure in ("penalty", "stress"):
        for trim in (0.0, size, 2 * size):
            s = run(f"discretisation.mesh_size={size}", *settings, *CONVERGED,
                    f"output.die_pressure={pressure}", f"output.die_entry_trim={trim}")
            results["measures"].append({"element": element, "die_pressure": pressure,
                                        "trim": trim, **s})
table(f"q_av by measure (mu = 0, h = {size})",
      ["element", "pressure from", "entry length left out", "q_av", "q projected",
       "drawing stress"],
      [[r["element"], r["die_pressure"], r["trim"], r["mean_die_pressure"],
        r["projected_die_pressure"], r["drawing_stress"]] for r in results["measures"]])

# ## 3. Where the velocity is prescribed: pulled at the exit (1000) or pushed at the entry
# (1000 h1/h0) for each friction coefficient of the reproduction table (friction adds to a push
# and lowers q under a pull)
for mu in args.mu if "drive" in args.parts else []:
    for element in args.elements:
        for drive, velocity in (("pull", 1000.0), ("push", 1000.0 * h1 / h0)):
            s = run(f"friction.mu={mu}", f"discretisation.mesh_size={size}", *ELEMENTS[element],
                    *CONVERGED, f"process.drive={drive}", f"process.velocity={velocity}")
            results["drive"].append({"mu": mu, "element": element, "drive": drive, **s})
table(f"Pulling at the exit or pushing at the entry (h = {size})",
      ["mu", "element", "drive", "q_av", "paper q_av", "q projected", "process force / h1",
       "force balance", "linear solves"],
      [[r["mu"], r["element"], r["drive"], r["mean_die_pressure"], PAPER_Q[r["mu"]],
        r["projected_die_pressure"], r["drawing_stress"], f"{r['force_balance_residual']:.1e}",
        r["linear_solves"]] for r in results["drive"]])

# ## 4. The penalties d and d_N (mu = 0, Q2 reduced), one varied from the paper's values at a time
penalties = [("d", d) for d in (5e-3, 5e-4, 5e-5, 5e-6)] + [("d_N", d) for d in (1e-3, 1e-4, 1e-5)]
for key, value in penalties if "penalty" in args.parts else []:
    s = run(f"discretisation.mesh_size={size}", *ELEMENTS["Q2 reduced"], *CONVERGED,
            f"penalty.{key}={value}")
    results["penalty"].append({"penalty": key, "value": value, **s})
table(f"The penalties (mu = 0, Q2 reduced, h = {size})",
      ["penalty", "value", "q_av", "drawing stress", "L2 norm of div u"],
      [[r["penalty"], r["value"], r["mean_die_pressure"], r["drawing_stress"], r["divergence_l2"]]
       for r in results["penalty"]])

# ## 5. Rate sensitivity and the flux through the free strip surfaces (mu = 0, Q2 reduced)
for alpha in (1e-3, 1e-5) if "rate" in args.parts else []:
    for size_r in args.sizes[1:]:
        s = run(f"discretisation.mesh_size={size_r}", *ELEMENTS["Q2 reduced"], *CONVERGED,
                f"material.alpha={alpha}")
        results["rate"].append({"alpha": alpha, "mesh_size": size_r, **s})
table("Rate sensitivity alpha, and volume crossing the free strip surfaces over the throughput "
      "(mu = 0, Q2)",
      ["alpha", "h", "q_av", "drawing stress", "free surface crossing"],
      [[r["alpha"], r["mesh_size"], r["mean_die_pressure"], r["drawing_stress"],
        r["free_surface_crossing"]] for r in results["rate"]])

# ## 6. Verification against an exact slip-line field (Hill): frictionless drawing through a wedge
# at the reduction r = 2 sin(a)/(1 + 2 sin(a)), where a triangle and a centred fan of angle a make
# the whole field; equilibrium along it gives q = 2k(1 + a)(1 - r) and the drawing stress
# t = 2k(1 + a) r.
angle = math.radians(geometry.die_angle)
r_exact = 2 * math.sin(angle) / (1 + 2 * math.sin(angle))
k = load_scene(args.scene).material.flow_stress(__import__("numpy").array([1.0]))[0] / math.sqrt(3)
exact_q, exact_t = 2 * k * (1 + angle) * (1 - r_exact), 2 * k * (1 + angle) * r_exact
for size_e in args.sizes if "exact" in args.parts else []:
    s = run(f"geometry.exit_thickness={h0 * (1 - r_exact)}", f"discretisation.mesh_size={size_e}",
            *ELEMENTS["Q2 reduced"], *CONVERGED)
    results["exact"].append({"mesh_size": size_e, "exact_q": exact_q, "exact_t": exact_t, **s})
if len(results["exact"]) >= 3:
    limits = {}
    for key in ("mean_die_pressure", "drawing_stress"):
        limits[key], order = richardson(args.sizes, [r[key] for r in results["exact"]])
        results["extrapolated"].append({"mu": 0.0, "element": "Q2 reduced",
                                        "quantity": f"exact-field {key}", "value": limits[key],
                                        "order": order})
    results["exact"].append({"mesh_size": "extrapolated", **limits})
table(f"Exact slip-line field, r = {r_exact:.4f} "
      f"(k = {k:.3f}: q = {exact_q:.2f}, t = {exact_t:.3f}), Q2 reduced",
      ["h", "q_av", "error", "drawing stress", "error"],
      [[r["mesh_size"], r.get("mean_die_pressure", math.nan),
        f"{100 * (r.get('mean_die_pressure', math.nan) / exact_q - 1):+.2f}%",
        r.get("drawing_stress", math.nan),
        f"{100 * (r.get('drawing_stress', math.nan) / exact_t - 1):+.2f}%"]
       for r in results["exact"]])

# ## 7. Where the secant G is evaluated, and the linear branch of (4.5) above rate2 = 1e3: the
# exact-field case and the paper's case (mu = 0, Q2 reduced), G averaged at the nodes as in the
# paper or taken at the Gauss points, with the paper's rate2 or with rate2 = 1e9 (no linear branch
# at these rates)
VARIANTS = [("nodes", 1e3), ("quadrature", 1e3), ("quadrature", 1e9)]
for case, exit_thickness, reference in (("exact field", h0 * (1 - r_exact), exact_q),
                                        ("paper", h1, SLIP_LINE_Q)):
    for averaging, rate2 in VARIANTS if "secant" in args.parts else []:
        rows = []
        for size_s in args.sizes:
            s = run(f"geometry.exit_thickness={exit_thickness}",
                    f"discretisation.mesh_size={size_s}", f"discretisation.averaging={averaging}",
                    f"material.rate2={rate2}", *ELEMENTS["Q2 reduced"], *CONVERGED)
            rows.append({"case": case, "averaging": averaging, "rate2": rate2, "mesh_size": size_s,
                         "reference": reference, **s})
        if len(rows) >= 3:
            limit, order = richardson(args.sizes, [r["mean_die_pressure"] for r in rows])
            rows.append({"case": case, "averaging": averaging, "rate2": rate2,
                         "mesh_size": "extrapolated", "reference": reference,
                         "mean_die_pressure": limit, "order": order})
        results["secant"].extend(rows)
table("Secant at the nodes or at the Gauss points, and rate2 "
      "(mu = 0, Q2 reduced; reference: exact q or slip-line 250)",
      ["case", "G at", "rate2", "h", "q_av", "against reference", "linear solves"],
      [[r["case"], r["averaging"], r["rate2"], r["mesh_size"], r["mean_die_pressure"],
        f"{100 * (r['mean_die_pressure'] / r['reference'] - 1):+.2f}%", r.get("linear_solves", "")]
       for r in results["secant"]])

# ## 8. Direct and modified methods at delta = 1e-4 (the paper's rule alone), Q1 complete, h = 0.05
for mu in (0.0, 0.2, 0.4) if "methods" in args.parts else []:
    for method in ("direct", "modified"):
        s = run(f"friction.mu={mu}", f"discretisation.mesh_size={size}", f"solver.method={method}",
                "solver.force_tolerance=0", "solver.max_iterations=2000", "output.fields=false",
                "output.figures=false")
        results["methods"].append({"mu": mu, "method": method, **s})
table(f"Secant-modulus methods at delta = 1e-4, no force criterion (Q1 complete, h = {size})",
      ["mu", "method", "linear solves", "outer iterations", "wall s", "q_av", "drawing stress",
       "force balance"],
      [[r["mu"], r["method"], r["linear_solves"], r["outer_iterations"], round(r["wall_time_s"], 1),
        r["mean_die_pressure"], r["drawing_stress"], f"{r['force_balance_residual']:.1e}"]
       for r in results["methods"]])

if rank0:
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "example2_study.json").write_text(json.dumps(results, indent=2))
    print(f"\nwritten {out / 'example2_study.json'}")

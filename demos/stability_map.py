# # Stability map: every parameter pushed to its extremes, on coarse meshes
#
#     mpirun -n 2 python demos/stability_map.py [--groups d alpha ...] [--out results/stability_map]
#
# Each row is one run of Example 1 (h = 0.5, Q2 reduced, direct method) or Example 2 (h = 0.1, Q2
# reduced, direct method, force balance to 1e-3) with one parameter changed. A run must either
# converge to a finite result whose change from the base run is bounded (and explained by the
# parameter), or stop with a specific message. "solve error" is the largest estimated relative error
# of a linear solve (one step of iterative refinement), the sign of ill-conditioned systems.
# docs/stability.md shows a run.

import argparse
import json
import math
from pathlib import Path

from mpi4py import MPI

from forming_fenicsx import load_scene
from forming_fenicsx.core.errors import SceneError
from forming_fenicsx.core.report import markdown_table
from forming_fenicsx.app.run import solve_scene

DEMOS = Path(__file__).parent
EX1 = (DEMOS / "example1_extrusion.toml", ["discretisation.mesh_size=0.5", "solver.method=direct"])
EX2 = (DEMOS / "example2_drawing_mu02.toml",
       ["discretisation.mesh_size=0.1", "discretisation.element=Q2",
        "discretisation.volumetric_integration=reduced", "solver.method=direct"])
QUANTITY = {"extrusion": "ram_pressure", "drawing": "mean_die_pressure"}
COMMON = ["output.fields=false", "output.figures=false", "solver.max_iterations=400"]
ALPHA = 1e-3  # the examples' rate sensitivity


def powers(low: int, high: int, step: int = 1) -> list[float]:
    return [10.0 ** e for e in range(low, high + 1, step)]


def velocity_cases(example, velocity: float) -> list[tuple[str, list[str]]]:
    """Velocity scaled by lam: alone, and with the rate window and penalties scaled so that the
    problem is exactly the base one with stresses times lam**alpha (u' = lam u, sigma' = lam**alpha
    sigma)."""
    cases = []
    for lam in (1e-3, 1e-1, 1e2, 1e4, 1e6):
        penalty = lam ** (1 - ALPHA)
        scene = load_scene(example[0])
        cases.append((f"{lam:g} alone", [f"process.velocity={velocity * lam}"]))
        cases.append((f"{lam:g} consistent", [
            f"process.velocity={velocity * lam}", f"material.rate1={scene.material.rate1 * lam}",
            f"material.rate2={scene.material.rate2 * lam}",
            f"penalty.d={scene.penalty.d * penalty}",
            f"penalty.d_N={scene.penalty.d_N * penalty}",
            f"friction.d_T={scene.friction.d_T * penalty}"]))
    return cases


GROUPS = {
    "d": (EX1, [(f"{d:g}", [f"penalty.d={d}"]) for d in powers(-12, -1)]),
    "d_N": (EX2, [(f"{d:g}", [f"penalty.d_N={d}"]) for d in powers(-12, -2, 2)]),
    "d_T": (EX2, [(f"{d:g}", [f"friction.d_T={d}"]) for d in powers(-12, -2, 2)]),
    "alpha": (EX1, [(f"{a:g}", [f"material.alpha={a}"]) for a in (1e-4, 1e-3, 0.1, 1.0)]),
    "rate1": (EX1, [(f"{r:g}", [f"material.rate1={r}"]) for r in powers(-6, -1)]),
    "velocity ex1": (EX1, velocity_cases(EX1, 1.0)),
    "velocity ex2": (EX2, velocity_cases(EX2, 1000.0)),
    "two elements ex1": (EX1, [("h = 1.25", ["discretisation.mesh_size=1.25"])]),
    "two elements ex2": (EX2, [("h = 0.375", ["discretisation.mesh_size=0.375"])]),
    "mu ex1": (EX1, [(f"{m:g}", [f"friction.mu={m}"]) for m in (0.1, 0.3, 0.5, 1.0, 2.0)]),
    "mu ex2 direct": (EX2, [(f"{m:g}", [f"friction.mu={m}"])
                            for m in (0.4, 0.5, 0.6, 0.8, 1.0, 2.0)]),
    "mu ex2 modified": (EX2, [(f"{m:g}", [f"friction.mu={m}", "solver.method=modified"])
                              for m in (0.4, 0.5, 0.6, 0.8, 1.0, 2.0)]),
    "reduction ex1": (EX1, [(f"{r:g}", [f"geometry.exit_thickness={10 * (1 - r)}"])
                            for r in (0.05, 0.2, 0.5, 0.65, 0.8)]),
    "reduction ex2": (EX2, [(f"{r:g}", [f"geometry.exit_thickness={1.625 * (1 - r)}"])
                            for r in (0.05, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6)]),
}


def run(scene_file: str | Path, overrides: list[str]) -> dict:
    """One run's summary, or the SceneError it was refused with."""
    try:
        scene = load_scene(scene_file, [*overrides, *COMMON])
    except SceneError as error:
        return {"converged": False, "reason": f"refused: {error}"}
    summary = solve_scene(scene)[2]
    summary["quantity"] = summary[QUANTITY[scene.process.kind]]
    summary.pop("scene")
    return summary


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--groups", nargs="+", default=list(GROUPS), choices=list(GROUPS))
    parser.add_argument("--out", default="results/stability_map")
    args = parser.parse_args()
    rank0 = MPI.COMM_WORLD.rank == 0
    results = {}
    for group in args.groups:
        example, cases = GROUPS[group]
        base = run(*example)
        rows = []
        for label, overrides in cases:
            s = run(example[0], [*example[1], *overrides])
            reference = base["quantity"] * (float(label.split()[0]) ** ALPHA
                                            if label.endswith("consistent") else 1)
            change = s["quantity"] / reference - 1 if "quantity" in s else math.nan
            rows.append({"value": label, "change": change, **s})
        results[group] = {"base": base, "rows": rows}
        if rank0:
            print(markdown_table(
                f"{group} (base {base['quantity']:.5g})",
                ["value", "converged", "linear solves", "quantity", "change", "solve error",
                 "force balance", "div u / e(u)", "stop or warning"],
                [[r["value"], r["converged"], r.get("linear_solves", 0),
                  r.get("quantity", math.nan), f"{100 * r['change']:+.3g}%",
                  f"{r.get('solve_error_estimate', math.nan):.1e}",
                  f"{r.get('force_balance_residual', math.nan):.1e}",
                  f"{r.get('relative_divergence', math.nan):.1e}",
                  "; ".join(([] if r["converged"] else [r["reason"].split(":")[0]])
                            + [w.split(":")[0] for w in r.get("warnings", [])])]
                 for r in rows]), flush=True)
    if rank0:
        out = Path(args.out)
        out.mkdir(parents=True, exist_ok=True)
        (out / "stability_map.json").write_text(json.dumps(results, indent=1, default=str))
        print(f"\nwritten {out / 'stability_map.json'}")


if __name__ == "__main__":
    main()

"""`forming bench`: the nonlinear solvers side by side on Example 1 and Example 2, with their costs.

Each case (example, mesh size, method, MPI ranks) runs in a process of its own (``mpirun -n R
python -m forming_fenicsx.app.bench --case JSON``), so that its peak memory and time are its own;
the parent collects one JSON line per case and prints and writes the table. All methods use the
secant at the Gauss points (Newton needs it), so that every method solves the same discrete
problem and their results can be compared: "vs direct" is the relative difference from the direct
method on the same mesh and ranks.
"""
from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
from pathlib import Path
from typing import Any

from forming_fenicsx.app.bench_free_surface import (free_surface_bench, free_surface_table,
                                                    run_free_surface_case)
from forming_fenicsx.app.bench_pairs import median_run, pair_rows, timed_pair
from forming_fenicsx.app.bench_scale import (DEFAULT_SCALE_SIZES, growth_exponents,
                                             peak_memory_mb, run_scale_case, scale_bench,
                                             scale_table)
from forming_fenicsx.core.jit_cache import exact_lookup
from forming_fenicsx.core.report import markdown_table

DEMOS = Path(__file__).resolve().parents[3] / "demos"
EXAMPLES = {
    1: ("example1_extrusion.toml", "ram_pressure", []),
    2: ("example2_drawing_mu02.toml", "mean_die_pressure",
        ["discretisation.element=Q2", "discretisation.volumetric_integration=reduced"]),
}
DEFAULT_SIZES = {1: [0.25, 0.11], 2: [0.05, 0.025]}
# --hardening: scenes with a hardening law, each run coupled and with the flow stress frozen at the
# coupled run's mean (a rate-independent law of that flow stress): the cost of the transported
# strain. Each row: scene, quantity, overrides, and its mesh size over the --sizes value (the wire's
# h 0.06 mm is the rod's 1.2 mm: 15 and 5 elements per exit radius)
HARDENING = {
    "copper, annealed": ("copper_wire_pass.toml", "drawing_stress", [], 1.0),
    "copper, drawn before (eps 0.276)": ("copper_wire_pass.toml", "drawing_stress",
                                         ["material.initial_strain=0.276"], 1.0),
    "aluminium 1100-O, rate factor 0.05": ("copper_wire_pass.toml", "drawing_stress", [
        "material.name=aluminium_1100_O", "material.rate_factor=power", "material.m=0.05"], 1.0),
    "6061-O rod, cold extrusion": ("aluminium_rod_cold.toml", "ram_pressure", [], 20.0),
}
METHODS = ("direct", "modified", "newton")


def run_case(case: dict[str, Any]) -> dict[str, Any]:
    """Solve one case in this process (all ranks) and return its row (on every rank)."""
    if case.get("scale"):
        return run_scale_case(case)
    if case.get("free_surface"):
        return run_free_surface_case(case)
    from mpi4py import MPI

    from forming_fenicsx.app.run import solve_scene
    from forming_fenicsx.config.loader import read_scene_data, scene_from_dict
    from forming_fenicsx.app.study import exact_value

    if "hardening" in case:
        scene_file, quantity, settings, _ = HARDENING[case["hardening"]]
    else:
        scene_file, quantity, settings = EXAMPLES[case["example"]]
    data = read_scene_data(DEMOS / scene_file, [
        *settings, f"discretisation.mesh_size={case['mesh_size']}",
        "discretisation.averaging=quadrature", f"solver.method={case['method']}",
        f"discretisation.formulation={case.get('formulation', 'penalty')}",
        "solver.max_iterations=1000", "output.fields=false",
        "output.figures=false", *case.get("set", [])])
    # the same mesh, as a round bar: thicknesses are diameters
    if case.get("symmetry") == "axisymmetric":
        geometry = data["geometry"]
        geometry["symmetry"] = "axisymmetric"
        for end in ("entry", "exit"):
            geometry[f"{end}_diameter"] = geometry.pop(f"{end}_thickness")
    if case.get("material"):  # the flow stress frozen: another law in place of the scene's
        data["material"] = case["material"]
    scene = scene_from_dict(data)
    summary = solve_scene(scene)[2]
    comm = MPI.COMM_WORLD
    split = summary["time_split_s"]
    solves = max(summary["linear_solves"], 1)
    return {**case, "ranks": comm.size, "dofs": summary["dofs"], "converged": summary["converged"],
            "linear_solves": summary["linear_solves"], "wall_time_s": summary["wall_time_s"], **{
                f"{key}_s": value for key, value in split.items()},
            "outside_per_solve_s": (split["assembly"] + split["rest"]) / solves,
            "factor_solve_per_solve_s": (split["factorisation"] + split["solve"]) / solves,
            "peak_memory_mb": peak_memory_mb(comm), "quantity": quantity,
            "value": summary[quantity], "exact": exact_value(scene, quantity),
            "force_balance_residual": summary["force_balance_residual"],
            "solve_error_estimate": summary["solve_error_estimate"],
            "mean_flow_stress": summary.get("mean_flow_stress")}


def hardening_bench(ranks: int, mesh_size: float, repeat: int) -> list[dict[str, Any]]:
    """Each HARDENING scene coupled, then with the flow stress frozen at the coupled run's mean
    flow stress (law rate_power, exponent 1e-3: the rate factor "none" of the hardening laws);
    the rows carry the coupled run's solves and time over the frozen run's. A first run of each,
    not counted, compiles the forms, so that no counted run pays for it (the frozen stress is a
    constant of the frozen run's forms; docs/hardening.md). The counted runs alternate, coupled
    then frozen, so that a load on the machine that comes or goes between them weighs on both."""
    rows = []
    for name, (*_, scale) in HARDENING.items():
        case = {"hardening": name, "mesh_size": round(mesh_size * scale, 9), "method": "newton"}
        first = _launch(case, ranks)
        frozen_case = {**case, "material": {"law": "rate_power", "A": first["mean_flow_stress"],
                                            "n": 1e-3}}
        coupled, frozen, ratios = timed_pair(case, frozen_case, ranks, repeat, _launch,
                                             first_warm=True)
        rows += [{**row, "flow_stress": kind} for row, kind in zip(
            pair_rows(name, coupled, frozen, ratios, ("coupled", "frozen"), "frozen"),
            ("strain transported", "frozen at the mean"))]
    return rows


def hardening_table(rows: list[dict[str, Any]]) -> str:
    return markdown_table("forming bench --hardening", [
        "scene", "h", "ranks", "flow stress", "converged", "dofs", "linear solves", "wall s",
        "wall s range", "drawing stress or ram pressure", "mean flow stress", "solves / frozen",
        "time / frozen"],
        [[r["hardening"], r["mesh_size"], r["ranks"], r["flow_stress"], r["converged"], r["dofs"],
          r["linear_solves"], f"{r['wall_time_s']:.2f}", _spread(r["wall_time_runs_s"]),
          f"{r['value']:.5g}", f"{r['mean_flow_stress'] or float('nan'):.5g}",
          f"{r['solves_vs_frozen']:.2f}", f"{r['time_vs_frozen']:.2f}"] for r in rows])


def _launch(case: dict[str, Any], ranks: int) -> dict[str, Any]:
    """Run one case under ``mpirun -n ranks`` and read its JSON row."""
    command = [sys.executable, "-m", "forming_fenicsx.app.bench", "--case", json.dumps(case)]
    launcher = shutil.which("mpirun") or shutil.which("mpiexec")
    if launcher:
        command = [launcher, "-n", str(ranks), *command]
    elif ranks != 1:
        raise RuntimeError("no mpirun or mpiexec on PATH for a run on more than one rank")
    done = subprocess.run(command, capture_output=True, text=True, check=False)
    rows = [line for line in done.stdout.splitlines() if line.startswith("{")]
    if done.returncode != 0 or not rows:
        raise RuntimeError(f"bench case {case} on {ranks} ranks failed:\n{done.stderr[-2000:]}")
    return json.loads(rows[-1])


def _counterpart(rows: list[dict[str, Any]], row: dict[str, Any], **changed: Any
                 ) -> dict[str, Any] | None:
    """The row of the same case as ``row`` but for the ``changed`` keys (e.g. method="direct")."""
    keys = ("example", "mesh_size", "ranks", "method", "formulation", "symmetry")
    wanted = {key: row.get(key) for key in keys} | changed
    return next((r for r in rows if all(r.get(key) == value for key, value in wanted.items())),
                None)


def compare(rows: list[dict[str, Any]]) -> None:
    """Add the error against the exact value and the difference from the direct method (in
    place)."""
    for row in rows:
        row["error"] = abs(row["value"] / row["exact"] - 1) if row.get("exact") else None
        direct = _counterpart(rows, row, method="direct")
        row["vs_direct"] = abs(row["value"] / direct["value"] - 1) if direct else None
        row["speedup_vs_direct"] = direct["wall_time_s"] / row["wall_time_s"] if direct else None
        serial = _counterpart(rows, row, ranks=1)
        row["speedup_vs_1_rank"] = serial["wall_time_s"] / row["wall_time_s"] if serial else None
        plane = _counterpart(rows, row, symmetry="plane_strain")
        row["time_vs_plane_strain"] = (row["wall_time_s"] / plane["wall_time_s"]
                                       if plane and row.get("symmetry") == "axisymmetric" else None)


def _spread(times: list[float]) -> str:
    return f"{min(times):.2f}-{max(times):.2f} ({len(times)})"


def table(rows: list[dict[str, Any]]) -> str:
    def number(value, fmt):
        return format(value, fmt) if value is not None else ""

    return markdown_table("forming bench", [
        "example", "h", "ranks", "symmetry", "formulation", "method", "converged", "dofs",
        "linear solves", "wall s", "wall s range", "setup s", "assembly s", "factorisation s",
        "solve s", "rest s", "post s", "outside/inside per solve", "peak MB", "solve error",
        "quantity", "error", "vs direct", "speed-up vs direct", "speed-up vs 1 rank",
        "time vs plane strain"],
        [[r["example"], r["mesh_size"], r["ranks"], r.get("symmetry", "plane_strain"),
          r.get("formulation", "penalty"), r["method"], r["converged"],
          r["dofs"], r["linear_solves"], f"{r['wall_time_s']:.2f}",
          _spread(r.get("wall_time_runs_s", [r["wall_time_s"]])), f"{r['setup_s']:.2f}",
          f"{r['assembly_s']:.2f}", f"{r['factorisation_s']:.2f}", f"{r['solve_s']:.2f}",
          f"{r['rest_s']:.2f}", f"{r.get('postprocess_s', 0.0):.2f}",
          f"{r['outside_per_solve_s'] / r['factor_solve_per_solve_s']:.2f}",
          f"{r['peak_memory_mb']:.0f}", number(r.get("solve_error_estimate"), ".1e"),
          f"{r['value']:.6g}", number(r["error"], ".2e"), number(r["vs_direct"], ".1e"),
          number(r["speedup_vs_direct"], ".2f"), number(r["speedup_vs_1_rank"], ".2f"),
          number(r.get("time_vs_plane_strain"), ".2f")] for r in rows])


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="forming bench", description=__doc__.splitlines()[0])
    parser.add_argument("--case", help=argparse.SUPPRESS)  # one case, in a child process
    parser.add_argument("--examples", type=int, nargs="+", default=[1, 2],
                        choices=sorted(EXAMPLES))
    parser.add_argument("--sizes", type=float, nargs="+",
                        help="mesh sizes (default: two per example)")
    parser.add_argument("--methods", nargs="+", default=list(METHODS), choices=METHODS)
    parser.add_argument("--formulations", nargs="+", default=["penalty"],
                        choices=["penalty", "mixed"],
                        help="incompressibility by penalty and/or the mixed formulation")
    parser.add_argument("--symmetries", nargs="+", default=["plane_strain"],
                        choices=["plane_strain", "axisymmetric"],
                        help="the examples as strips and/or round bars "
                             "(thicknesses read as diameters)")
    parser.add_argument("--ranks", type=int, nargs="+", default=[1],
                        help="MPI ranks of each case (e.g. 1 2)")
    parser.add_argument("--set", action="append", default=[], metavar="SECTION.KEY=VALUE",
                        help="override a scene value in every case")
    parser.add_argument("--repeat", type=int, default=1,
                        help="run every case once per round, so many rounds, and keep each "
                             "case's run of median wall time")
    parser.add_argument("--hardening", action="store_true",
                        help="the hardening scenes instead of the examples: each coupled and "
                             "with the flow stress frozen at its mean (the first --ranks and "
                             "--sizes; h 0.06 mm)")
    parser.add_argument("--free-surface", action="store_true",
                        help="scenes on their own domain and with the free-surface update: the "
                             "update's cost (the first --ranks)")
    parser.add_argument("--scale", action="store_true",
                        help="a 3D bar on --sizes (default 1.0 0.7 0.5 mm) and --ranks, solved "
                             "by each --linear solver: time, memory and Krylov iterations "
                             "against the unknowns")
    parser.add_argument("--linear", nargs="+", default=["direct", "iterative"],
                        choices=["direct", "iterative"], help="the linear solvers of --scale")
    parser.add_argument("--out", default="results/bench.json")
    args = parser.parse_args(argv)
    if args.repeat < 1:
        parser.error(f"--repeat must be at least 1; got {args.repeat}")
    if args.case:  # with FFCx's lookup as `forming` has it: the time of a listing of the whole
        # form cache at every form (0.01 s at the 20k files of a developer's cache) is not a run's
        with exact_lookup():
            row = run_case(json.loads(args.case))
        from mpi4py import MPI

        if MPI.COMM_WORLD.rank == 0:
            print(json.dumps(row), flush=True)
        return 0
    if "OMPI_COMM_WORLD_SIZE" in os.environ or "PMI_RANK" in os.environ:
        print("forming bench: run it without mpirun; --ranks sets the ranks of each case",
              file=sys.stderr)
        return 2
    if args.scale:
        rows = scale_bench(args.sizes or DEFAULT_SCALE_SIZES, args.ranks, args.linear, _launch)
        print(scale_table(rows))
        return _write(Path(args.out), rows + [{"growth": growth_exponents(rows)}])
    if args.free_surface:
        rows = free_surface_bench(args.ranks[0], args.repeat, _launch)
        print(free_surface_table(rows))
        return _write(Path(args.out), rows)
    if args.hardening:
        rows = hardening_bench(args.ranks[0], (args.sizes or [0.06])[0], args.repeat)
        print(hardening_table(rows))
        return _write(Path(args.out), rows)
    cases = [({"example": example, "mesh_size": size, "method": method, "formulation": formulation,
               "symmetry": symmetry, "set": args.set}, ranks)
             for example in args.examples for size in args.sizes or DEFAULT_SIZES[example]
             for ranks in args.ranks for formulation in args.formulations for method in args.methods
             for symmetry in args.symmetries]
    runs: list[list[dict[str, Any]]] = [[] for _ in cases]
    # every case once per round: a slow spell of the machine falls on all cases alike
    for round_ in range(1, args.repeat + 1):
        for (case, ranks), case_runs in zip(cases, runs, strict=True):
            case_runs.append(_launch(case, ranks))
            print(f"run {round_}/{args.repeat}: example {case['example']}, {case['symmetry']}, "
                  f"h = {case['mesh_size']}, {ranks} rank(s), "
                  f"{case['formulation']}, {case['method']}: "
                  f"{case_runs[-1]['linear_solves']} solves, "
                  f"{case_runs[-1]['wall_time_s']:.2f} s", flush=True)
    rows = [median_run(case_runs) for case_runs in runs]
    compare(rows)
    print(table(rows))
    return _write(Path(args.out), rows)


def _write(out: Path, rows: list[dict[str, Any]]) -> int:
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(rows, indent=1))
    print(f"\nwritten {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

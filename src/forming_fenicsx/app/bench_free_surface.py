"""`forming bench --free-surface`: the cost of the free-surface update (app/free_surface.py).

Each scene runs on its own domain and with `[free_surface] update = true`, each run in a process of
its own (bench.py launches them); the rows carry the free run's linear solves and wall time (every
solve, re-mesh and trace: free_surface.wall_time_s) over the fixed run's, and what the update
changed (docs/free_surface.md)."""
from __future__ import annotations

from pathlib import Path
from typing import Any, Callable

from forming_fenicsx.app.bench_pairs import Row, pair_rows, timed_pair
from forming_fenicsx.core.report import markdown_table

DEMOS = Path(__file__).resolve().parents[3] / "demos"
# Q2 on the default gradings (the demos of Example 2 keep the paper's uniform mesh)
Q2_GRADED = ["discretisation.element=Q2", "discretisation.corner_grading=64",
             "discretisation.wall_grading=16"]
# name: scene, the quantity reported, overrides
SCENES = {
    "Example 2, mu = 0": ("example2_drawing.toml", "drawing_stress", []),
    "Example 2, mu = 0.4": ("example2_drawing_mu04.toml", "drawing_stress", []),
    "copper wire 2 -> 1.8 mm, 6 deg": ("copper_wire.toml", "drawing_stress", []),
    "6061-O rod 20 -> 12 mm, no bearing": ("aluminium_rod_cold.toml", "ram_pressure",
                                           ["geometry.land_length=0.0",
                                            "discretisation.mesh_size=0.6"]),
    # the must-show cases on Q2 and the default graded mesh, where the default tolerance takes
    # Example 2's crossing below 0.1 % (docs/free_surface.md)
    **{f"Example 2, mu = {mu}, Q2 graded": (scene, "drawing_stress", Q2_GRADED)
       for mu, scene in (("0", "example2_drawing.toml"), ("0.2", "example2_drawing_mu02.toml"),
                         ("0.4", "example2_drawing_mu04.toml"))},
    "wire 2 -> 1.789 mm, 15 deg, mu = 0, Q2 graded, tolerance 1e-4": (
        "copper_wire.toml", "drawing_stress",
        ["geometry.exit_diameter=1.789", "geometry.die_angle=15", "friction.mu=0", *Q2_GRADED,
         "free_surface.tolerance=1e-4"]),
}


def run_free_surface_case(case: dict[str, Any]) -> dict[str, Any]:
    """Solve one scene of SCENES in this process (all ranks), on its own domain or with the
    free-surface update (``case["update"]``); its row (on every rank)."""
    from mpi4py import MPI

    from forming_fenicsx.app.bench_scale import peak_memory_mb
    from forming_fenicsx.app.run import solve_scene, solve_updated
    from forming_fenicsx.config.loader import load_scene

    scene_file, quantity, settings = SCENES[case["free_surface"]]
    scene = load_scene(DEMOS / scene_file, [
        *settings, "output.fields=false", "output.figures=false",
        f"free_surface.update={'true' if case['update'] else 'false'}"])
    if case["update"]:
        summary = solve_updated(scene)[2]
        table = summary["free_surface"]
        solves, wall = table["linear_solves"], table["wall_time_s"]
        extra = {"updates": table["updates"], "settled": table["converged"],
                 "size_change": table[f"exit_{scene.geometry.thickness_name}_change"]}
    else:
        summary = solve_scene(scene)[2]
        solves, wall, extra = summary["linear_solves"], summary["wall_time_s"], {}
    return {**case, "ranks": MPI.COMM_WORLD.size, "dofs": summary["dofs"],
            "converged": summary["converged"], "linear_solves": solves, "wall_time_s": wall,
            "peak_memory_mb": peak_memory_mb(MPI.COMM_WORLD), "quantity": quantity,
            "value": summary[quantity], "crossing": summary["free_surface_crossing"], **extra}


def free_surface_bench(ranks: int, repeat: int, launch: Callable[[Row, int], Row],
                       names: tuple[str, ...] = tuple(SCENES)) -> list[Row]:
    """Each scene named fixed and free, timed against each other (bench_pairs.timed_pair); the
    rows of median wall time with the median of the pairs' time ratios."""
    rows = []
    for name in names:
        fixed_case, free_case = ({"free_surface": name, "update": update}
                                 for update in (False, True))
        free, fixed, ratios = timed_pair(free_case, fixed_case, ranks, repeat, launch)
        rows += reversed(pair_rows(name, free, fixed, ratios, ("free", "fixed"), "fixed"))
    return rows


def free_surface_table(rows: list[dict[str, Any]]) -> str:
    return markdown_table("forming bench --free-surface", [
        "scene", "ranks", "domain", "converged", "dofs", "updates", "linear solves", "wall s",
        "wall s range", "quantity", "crossing", "product size change", "solves / fixed",
        "time / fixed"],
        [[r["free_surface"], r["ranks"], "free surface" if r["update"] else "the scene's",
          r["converged"], r["dofs"], r.get("updates", ""), r["linear_solves"],
          f"{r['wall_time_s']:.2f}", f"{min(r['wall_time_runs_s']):.2f}-"
          f"{max(r['wall_time_runs_s']):.2f}", f"{r['quantity']} {r['value']:.5g}",
          f"{100 * r['crossing']:.3g} %",
          f"{100 * r['size_change']:.3g} %" if "size_change" in r else "",
          f"{r['solves_vs_fixed']:.2f}", f"{r['time_vs_fixed']:.2f}"] for r in rows])

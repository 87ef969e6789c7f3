"""`forming bench --scale`: the direct (MUMPS) and the iterative linear solver (fem/saddle_point.py)
on a 3D bar of growing meshes and ranks: wall time, peak memory, Krylov iterations per linear solve
and per Newton step, the answer's difference between the two, and the growth exponents of time and
memory with the unknowns (least squares of log t = a + p log N over each solver and rank count).
"""
from __future__ import annotations

import math
import resource
from collections.abc import Callable
from typing import Any

import numpy as np

from forming_fenicsx.core.report import markdown_table

# the bar of tests/test_iterative_solver.py: 4 x 6 -> 3.2 x 5 mm through an 8 degree die, mu 0.05,
# law (4.5), the mixed formulation, Newton's method, on the uniform blocks docs/iterative_solver.md
# was measured on (on the default gradings the iterative solver took 188 s against 61 s at 92k
# unknowns, two ranks, with GMRES inside the velocity block)
SCALE_BAR: dict[str, dict[str, Any]] = {
    "process": {"kind": "drawing", "velocity": 1.0},
    "geometry": {"symmetry": "3d", "entry_height": 4.0, "exit_height": 3.2, "entry_width": 6.0,
                 "exit_width": 5.0, "die_angle": 8.0},
    "material": {"law": "piecewise_power", "A": 300.0}, "friction": {"mu": 0.05},
    "discretisation": {"averaging": "quadrature", "formulation": "mixed", "corner_grading": 1.0,
                       "wall_grading": 1.0},
    "solver": {"method": "newton"}, "output": {"fields": False, "figures": False}}
DEFAULT_SCALE_SIZES = [1.0, 0.7, 0.5]


def peak_memory_mb(comm) -> float:
    """The peak resident memory of this process summed over the ranks, in MB."""
    from mpi4py import MPI

    return comm.allreduce(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss, op=MPI.SUM) / 1024.0


def run_scale_case(case: dict[str, Any]) -> dict[str, Any]:
    """Solve the bar at case["mesh_size"] with case["linear"] in this process (all ranks)."""
    from mpi4py import MPI

    from forming_fenicsx.app.run import solve_scene
    from forming_fenicsx.config.loader import scene_from_dict

    data = {key: dict(value) for key, value in SCALE_BAR.items()}
    data["discretisation"]["mesh_size"] = case["mesh_size"]
    data["solver"]["linear"] = case["linear"]
    _, result, summary = solve_scene(scene_from_dict(data))
    comm = MPI.COMM_WORLD
    newton = [record for record in result.history if not math.isnan(record.residual)]
    split = summary["time_split_s"]
    return {**case, "ranks": comm.size, "dofs": summary["dofs"],
            "converged": summary["converged"], "linear_solves": summary["linear_solves"],
            "wall_time_s": summary["wall_time_s"],
            "solve_time_s": split["factorisation"] + split["solve"],
            "peak_memory_mb": peak_memory_mb(comm), "drawing_stress": summary["drawing_stress"],
            "time_split_s": split,
            "krylov_per_newton_step": [record.krylov_iterations for record in newton],
            "velocity_per_newton_step": [record.velocity_iterations for record in newton]}


def scale_bench(sizes: list[float], ranks: list[int], linears: list[str],
                launch: Callable[[dict[str, Any], int], dict[str, Any]]) -> list[dict[str, Any]]:
    """Every size x ranks x linear solver once, coarsest first (``launch`` runs a case under
    mpirun and returns its row); each row gets its difference from the direct solver's answer."""
    rows = []
    for size in sorted(sizes, reverse=True):
        for count in ranks:
            for linear in linears:
                row = launch({"scale": True, "mesh_size": size, "linear": linear}, count)
                rows.append(row)
                print(f"h = {size}, {count} rank(s), {linear}: {row['dofs']} unknowns, "
                      f"{row['linear_solves']} solves, {row['wall_time_s']:.1f} s, "
                      f"{row['peak_memory_mb']:.0f} MB", flush=True)
    for row in rows:
        direct = next((r for r in rows if r["linear"] == "direct" and r["ranks"] == row["ranks"]
                       and r["mesh_size"] == row["mesh_size"]), None)
        row["vs_direct"] = (abs(row["drawing_stress"] / direct["drawing_stress"] - 1)
                            if direct else None)
    return rows


def growth_exponents(rows: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """The fitted exponent p of wall time and peak memory ~ N^p, per solver and rank count (two
    sizes at least)."""
    fits = []
    for linear in sorted({row["linear"] for row in rows}):
        for count in sorted({row["ranks"] for row in rows}):
            group = [r for r in rows if r["linear"] == linear and r["ranks"] == count]
            if len(group) < 2:
                continue
            unknowns = np.log([r["dofs"] for r in group])
            fits.append({"linear": linear, "ranks": count, "sizes": len(group), **{
                f"{key}_exponent": float(np.polyfit(unknowns, np.log([r[key] for r in group]),
                                                    1)[0])
                for key in ("wall_time_s", "solve_time_s", "peak_memory_mb")}})
    return fits


def scale_table(rows: list[dict[str, Any]]) -> str:
    def steps(values: list[int]) -> str:
        return f"{min(values)}-{max(values)}" if values else ""

    table = markdown_table("forming bench --scale", [
        "h", "ranks", "linear solver", "unknowns", "converged", "linear solves", "wall s",
        "solve s", "peak MB", "Krylov per Newton step", "velocity-block iterations per Newton step",
        "drawing stress", "vs direct"],
        [[r["mesh_size"], r["ranks"], r["linear"], r["dofs"], r["converged"], r["linear_solves"],
          f"{r['wall_time_s']:.1f}", f"{r['solve_time_s']:.1f}", f"{r['peak_memory_mb']:.0f}",
          steps(r["krylov_per_newton_step"]) if r["linear"] == "iterative" else "",
          steps(r["velocity_per_newton_step"]) if r["linear"] == "iterative" else "",
          f"{r['drawing_stress']:.6g}",
          "" if r["vs_direct"] is None else f"{r['vs_direct']:.1e}"] for r in rows])
    fits = markdown_table("growth with the unknowns N (fitted exponent p of N^p)", [
        "linear solver", "ranks", "sizes", "wall time", "solve time", "peak memory"],
        [[f["linear"], f["ranks"], f["sizes"], f"{f['wall_time_s_exponent']:.2f}",
          f"{f['solve_time_s_exponent']:.2f}", f"{f['peak_memory_mb_exponent']:.2f}"]
         for f in growth_exponents(rows)])
    return f"{table}\n\n{fits}"

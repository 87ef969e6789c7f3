"""The grading sweeps behind the default gradings (docs/accuracy.md, "Graded meshes: the defaults").

One run per mesh (Newton, quadrature averaging, Q2), the error of the drawing stress for
corner_grading / wall_grading pairs:
- the exact drawing field (demos/example2_exact_field.toml with rate2 = 1e9, alpha = 1e-4) against
  the slip-line value;
- a frictionless wire, 2 -> 1.6 mm through a 15 degree die (copper_wire.toml's law), against its
  own --accuracy 0.05 % answer on adapted meshes;
- the 3D quarter of verification.three_d's wire (6 degrees, mu = 0.05) against the axisymmetric
  pass on h = 0.0125 with the defaults' gradings;
and, with the paper's method, Example 1 with mu = 0.1 on h = 1 (three elements on the graded
edges) for gradings 4 to 64: whether the friction loop converges.
Run: .venv/bin/python demos/grading_sweep.py (one rank, about 4 minutes)
"""
from __future__ import annotations

from pathlib import Path

from mpi4py import MPI

from forming_fenicsx.app.run import solve_scene
from forming_fenicsx.app.study import exact_value
from forming_fenicsx.config.loader import load_scene, scene_from_dict
from forming_fenicsx.core.report import markdown_table
from forming_fenicsx.mesh.geometry import build_mesh
from forming_fenicsx.solvers.accuracy import solve_to_accuracy
from forming_fenicsx.verification.three_d import coupled_problem, solved, wire_scene

DEMOS = Path(__file__).parent
QUIET = ["output.fields=false", "output.figures=false"]
NEWTON = ["solver.method=newton", "discretisation.averaging=quadrature", *QUIET]
PAIRS = ((1, 1), (64, 1), (64, 4), (64, 8), (64, 16), (64, 32))
WIRE = {"process": {"kind": "drawing", "velocity": 1000.0},
        "geometry": {"symmetry": "axisymmetric", "entry_diameter": 2.0, "exit_diameter": 1.6,
                     "die_angle": 15.0, "land_length": 0.3},
        "material": {"law": "rate_power", "A": 236.0, "n": 0.01}, "friction": {"mu": 0.0},
        "solver": {"method": "newton"}, "discretisation": {"averaging": "quadrature"},
        "output": {"fields": False, "figures": False},
        "units": {"length": "mm", "time": "s", "stress": "MPa", "force": "N"}}


def graded(scene, pair: tuple[float, float]):
    """The scene with corner_grading and wall_grading set."""
    scene.discretisation.corner_grading, scene.discretisation.wall_grading = map(float, pair)
    return scene


def wire(size: float | None = None):
    data = {**WIRE, "discretisation": {**WIRE["discretisation"],
                                       **({"mesh_size": size} if size else {})}}
    return scene_from_dict(data)


def row(case: str, size: float, runs: list[tuple[int, float]], reference: float) -> list:
    """A table row: the unknowns (their range) and each pair's error in %."""
    dofs = sorted({dofs for dofs, _ in runs})
    return [case, size, f"{dofs[0]}-{dofs[-1]}" if len(dofs) > 1 else dofs[0],
            *(f"{100 * abs(value / reference - 1):.3f} %" for _, value in runs)]


def main() -> None:
    comm = MPI.COMM_WORLD
    rows = []
    exact_path = DEMOS / "example2_exact_field.toml"
    field = [*NEWTON, "material.rate2=1e9", "material.alpha=1e-4"]
    exact = exact_value(load_scene(exact_path, field), "drawing_stress")
    for size in (0.05, 0.025):
        runs = []
        for pair in PAIRS:
            summary = solve_scene(graded(load_scene(exact_path, [
                *field, f"discretisation.mesh_size={size}"]), pair), comm=comm)[2]
            runs.append((summary["dofs"], summary["drawing_stress"]))
        rows.append(row("drawing field, plane strain", size, runs, exact))
    target = wire(0.05)
    target.accuracy.target, target.accuracy.meshes = 5e-4, "adapted"
    reference = solve_to_accuracy(target, lambda level, previous, generate: solve_scene(
        level, comm=comm, previous=previous, generate=generate), comm)[2]["accuracy"]
    for size in (0.1, 0.05):
        runs = [(s["dofs"], s["drawing_stress"]) for s in
                (solve_scene(graded(wire(size), pair), comm=comm)[2] for pair in PAIRS)]
        rows.append(row("wire 2 -> 1.6 mm, 15 deg, mu 0", size, runs,
                        reference["answer_value"]))
    quarter = graded(wire_scene("axisymmetric", 0.0125, 0.05), (64, 16))
    axisymmetric = solved(coupled_problem(quarter, build_mesh(quarter, comm)))["drawing_stress"]
    for size in (0.45, 0.3, 0.2):
        runs = []
        for pair in ((1, 1), (64, 4), (64, 16)):
            scene = graded(wire_scene("3d", size, 0.05), pair)
            result = solved(coupled_problem(scene, build_mesh(scene, comm)))
            runs.append((result["unknowns"], result["drawing_stress"]))
        rows.append(row("3D quarter wire, 6 deg, mu 0.05", size, runs, axisymmetric))
    coarse = []
    for grading in (4, 16, 32, 64):
        scene = load_scene(DEMOS / "example1_extrusion.toml", [
            *QUIET, "discretisation.mesh_size=1.0", "friction.mu=0.1",
            f"discretisation.corner_grading={grading}"])  # the paper's method (3.33)
        _, result, summary = solve_scene(scene, comm=comm)
        coarse.append([grading, summary["linear_solves"], result.converged,
                       f"{summary['ram_pressure']:.4f}"])
    if comm.rank == 0:
        print(f"references: exact drawing field {exact:.6g}, wire {reference['answer_value']:.6g}"
              f" (estimate {100 * reference['answer_estimate']:.3g} %), 3D quarter wire's "
              f"axisymmetric pass {axisymmetric:.6g}")
        print(markdown_table(None, ["case", "h", "unknowns",
                                    *(f"{c} / {w}" for c, w in PAIRS)], rows[:4]))
        print(markdown_table(None, ["case", "h", "unknowns", "1 / 1", "64 / 4", "64 / 16"],
                             rows[4:]))
        print(markdown_table(None, ["Example 1, mu 0.1, h 1: corner_grading", "linear solves",
                                    "converged", "ram pressure"], coarse))


if __name__ == "__main__":
    main()

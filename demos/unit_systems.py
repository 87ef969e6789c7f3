# # One process in three unit systems and at velocities 1e-3 to 1e3
#
# Drawing (2.0 -> 1.6 mm, 10 degree die) and square-die extrusion (20 -> 12 mm), mu = 0.08, a rate
# power law sigma = 300 MPa (rate in 1/s)^0.1, every numerical parameter at its relative default,
# written in mm/MPa/N, m/Pa/N and in/psi/lbf and run at 1e-3, 1 and 1e3 mm/s (coarse meshes,
# Newton). The dimensionless result (drawing stress or ram pressure over the flow stress at the
# process rate) is the same in every row; the stress in MPa scales with the velocity by lam^0.1.
# tests/test_units.py runs the same scenes.
#
#     .venv/bin/python demos/unit_systems.py

from forming_fenicsx.core.report import markdown_table
from forming_fenicsx.app.run import solve_scene
from forming_fenicsx.config.loader import scene_from_dict
from forming_fenicsx.config.scene import Scene

PSI = 6894.757293168361  # Pa
# the unit system: (its length unit in mm, its stress unit in MPa, labels)
SYSTEMS = {"mm": (1.0, 1.0, ("mm", "s", "MPa", "N")), "m": (1e3, 1e-6, ("m", "s", "Pa", "N")),
           "in": (25.4, PSI * 1e-6, ("in", "s", "psi", "lbf"))}
# rate sensitivity of sigma = A rate^n: a velocity lam times larger multiplies stresses by lam^n
N = 0.1
CASES = [("mm", 1.0), ("m", 1.0), ("in", 1.0), ("mm", 1e-3), ("mm", 1e3)]


def scene(kind: str, system: str, velocity: float) -> Scene:
    """The process of this file in mm, MPa (velocity in mm/s), written in another unit system."""
    length, stress, names = SYSTEMS[system]
    geometry = ({"entry_thickness": 2.0, "exit_thickness": 1.6, "die_angle": 10.0}
                if kind == "drawing" else {"entry_thickness": 20.0, "exit_thickness": 12.0})
    return scene_from_dict({
        "process": {"kind": kind, "velocity": velocity / length},
        "geometry": {key: value if key == "die_angle" else value / length
                     for key, value in geometry.items()},
        "material": {"law": "rate_power", "A": 300.0 / stress, "n": N}, "friction": {"mu": 0.08},
        # the gradings of docs' numbers (the defaults, 64 and 16, grade more)
        "discretisation": {"mesh_size_relative": 0.5, "averaging": "quadrature",
                           "corner_grading": 1.0 if kind == "drawing" else 4.0,
                           "wall_grading": 1.0},
        "solver": {"method": "newton"},
        "units": dict(zip(("length", "time", "stress", "force"), names)),
        "output": {"fields": False, "figures": False}})


def dimensionless(kind: str, system: str, velocity: float) -> tuple[float, float, dict]:
    """(process stress over the flow stress at the process rate, process stress in MPa, summary)."""
    run = scene(kind, system, velocity)
    summary = solve_scene(run)[2]
    value = summary["drawing_stress" if kind == "drawing" else "ram_pressure"]
    return value / run.scales.flow_stress, value * SYSTEMS[system][1], summary


if __name__ == "__main__":
    from mpi4py import MPI

    from forming_fenicsx.app.cli import configure_logging

    configure_logging(quiet=True, rank=MPI.COMM_WORLD.rank)
    rows = []
    for kind in ("drawing", "extrusion"):
        for system, velocity in CASES:
            ratio, stress, summary = dimensionless(kind, system, velocity)
            rows.append([kind, system, f"{velocity:g}", f"{ratio:.10f}", f"{stress:.6g}",
                         summary["linear_solves"], summary["converged"]])
    if MPI.COMM_WORLD.rank == 0:
        print(markdown_table("unit systems and velocities", ["process", "units", "velocity mm/s",
                             "stress / sigma0", "stress MPa", "linear solves", "converged"], rows))

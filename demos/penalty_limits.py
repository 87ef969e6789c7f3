# # The relative penalties against their d, d_N, d_T -> 0 limits
#
# Each penalty of the scene (the volumetric d, the contact d_N, the slip regularisation d_T) is
# varied alone over decades of its relative value, the others at their defaults, on three scenes:
# Example 1 (square die, mu = 0.1), Example 2 (6 degree die, mu = 0.2) and a 2.0 -> 1.6 mm strip
# through a 10 degree die with mu = 0.08 and a 300 MPa flow stress in mm, MPa and mm/s. Every run
# uses Q2 elements with reduced integration, the secant at the Gauss points and Newton's method to
# delta = 1e-6, so that the differences are the penalties' and not the iteration's.
#
#     mpirun -n 2 .venv/bin/python demos/penalty_limits.py  # prints the tables of docs/penalties.md

import argparse
import copy
from pathlib import Path

from mpi4py import MPI

from forming_fenicsx.app.cli import configure_logging
from forming_fenicsx.core.report import markdown_table
from forming_fenicsx.app.run import solve_scene
from forming_fenicsx.config.loader import apply_overrides, read_scene_data, scene_from_dict

DEMOS = Path(__file__).parent
COMMON = ["discretisation.element=Q2", "discretisation.volumetric_integration=reduced",
          "discretisation.averaging=quadrature", "solver.method=newton", "solver.tolerance=1e-6",
          "output.fields=false", "output.figures=false"]
# the paper's absolute penalties are removed so that the relative defaults (or the varied value)
# apply
RELATIVE = ["penalty.d", "penalty.d_N", "penalty.augmented", "friction.d_T"]
STRIP = {"process": {"kind": "drawing", "velocity": 1.0},
         "geometry": {"entry_thickness": 2.0, "exit_thickness": 1.6, "die_angle": 10.0},
         "material": {"law": "piecewise_power", "A": 300.0},
         "friction": {"mu": 0.08},
         "discretisation": {"corner_grading": 1.0, "wall_grading": 1.0},  # docs' meshes
         "units": {"length": "mm", "time": "s", "stress": "MPa", "force": "N"}}
SCENES = {
    "Example 1, mu = 0.1, h = 0.25": (DEMOS / "example1_extrusion_mu01.toml",
                                      ["discretisation.mesh_size=0.25"], "ram_pressure"),
    "Example 2, mu = 0.2, h = 0.05": (DEMOS / "example2_drawing_mu02.toml", [], "drawing_stress"),
    "strip 2.0 -> 1.6 mm, 10 deg, mu = 0.08": (None, [], "drawing_stress"),
}
VALUES = {"penalty.d_relative": [1e-2, 1e-3, 1e-4, 1e-5, 1e-6],
          "penalty.d_N_relative": [1e-1, 1e-2, 1e-3, 1e-4, 1e-5],
          "friction.d_T_relative": [1e-2, 1e-4, 1e-6, 1e-8]}
# the same d_N without the multiplier: the paper's pure penalty (3.4), for comparison
PURE = "penalty.augmented=false"


def scene_for(path, settings, overrides):
    """The scene with the paper's absolute penalties taken out and the given relative values set."""
    if path is None:
        return scene_from_dict(apply_overrides(copy.deepcopy(STRIP),
                                               [*COMMON, *settings, *overrides]))
    data = read_scene_data(path, [*COMMON, *settings])
    for key in RELATIVE:
        section, name = key.split(".")
        data.get(section, {}).pop(name, None)
    return scene_from_dict(apply_overrides(data, overrides))


parser = argparse.ArgumentParser(description=__doc__)
parser.add_argument("--scenes", nargs="*", default=list(SCENES))
args = parser.parse_args()
configure_logging(quiet=True, rank=MPI.COMM_WORLD.rank)
for title in args.scenes:
    path, settings, quantity = SCENES[title]
    rows = []
    sweeps = [(key, values, []) for key, values in VALUES.items()]
    sweeps.append(("penalty.d_N_relative", VALUES["penalty.d_N_relative"], [PURE]))
    limit = None  # the d sweep's smallest d with augmented contact: the d, d_N -> 0 limit
    for key, values, extra in sweeps:
        results = []
        for value in values:
            scene = scene_for(path, settings, [f"{key}={value}", *extra])
            summary = solve_scene(scene)[2]
            results.append((value, scene, summary))
        limit = limit if limit is not None else results[-1][2][quantity]
        for value, scene, s in results:
            absolute = {"penalty.d_relative": scene.penalty.d,
                        "penalty.d_N_relative": scene.penalty.d_N,
                        "friction.d_T_relative": scene.friction.d_T}[key]
            name = key.split(".")[1] + (" (pure penalty)" if extra else "")
            rows.append([name, f"{value:g}", f"{absolute:.3g}", f"{s[quantity]:.6g}",
                         f"{100 * (s[quantity] / limit - 1):+.3f}%",
                         f"{s['relative_divergence']:.2g}",
                         f"{100 * s['die_penetration']:.3g}%", f"{s['solve_error_estimate']:.1e}",
                         s["linear_solves"], "yes" if s["converged"] else "no", len(s["warnings"])])
    if MPI.COMM_WORLD.rank == 0:
        sigma0 = scene.reference_flow_stress
        print(markdown_table(f"{title}: {quantity} (sigma0 = {sigma0:.5g})",
                             ["varied", "relative", "absolute", quantity, "vs limit",
                              "div u / e(u)", "die penetration", "solve error", "linear solves",
                              "converged", "warnings"], rows))
        print(flush=True)

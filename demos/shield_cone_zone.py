"""The FE cone zone against Shield's cone flow: the rise of the mean axial stress per sigma0
ln(A0/A) in the middle of a long conical die, beside Shield's c/2 (closed_forms.shield_cone_factor,
reference section 2) and Avitzur's cone terms (docs/conical_dies.md).

Axisymmetric extrusion (the product cannot yield, so the cone may be long) of a bar of radius 1 to
0.5 (75 % reduction of area; 0.25 for the short cones of 15 and 30 degrees too) through dies of 5 to
30 degrees with friction factor m, the paper's law (4.5) with A = 1 (nearly rate-independent),
Newton. The slope is the least-squares fit of the section mean of sigma_xx
(sections.mean_axial_stress) against ln(A0/A(x)) over the middle half of the cone. Writes
results/shield_cone_zone.json and .md.
Run: .venv/bin/python demos/shield_cone_zone.py (about 4 minutes, 1 core).
"""
from __future__ import annotations

import argparse
import json
import math
from pathlib import Path

import numpy as np

from forming_fenicsx.physics.closed_forms import avitzur_cone_factor, shield_cone_factor
from forming_fenicsx.core.report import markdown_table
from forming_fenicsx.app.run import solve_scene
from forming_fenicsx.config.loader import scene_from_dict
from forming_fenicsx.post.sections import mean_axial_stress

ROOT = Path(__file__).resolve().parents[1]
# the (angle, m) pairs of the reference's table of Shield's c/2, on a bar of radius 1 to 0.5 with
# h = 0.05 and 0.025; the short cones of 15 and 30 degrees again to radius 0.25 (h = 0.0125)
LONG_CONES = ((5.0, 0.1), (5.0, 0.5), (10.0, 0.1), (10.0, 0.2), (10.0, 0.5), (15.0, 0.1),
              (15.0, 0.2), (30.0, 0.1), (30.0, 0.5))
CASES = [(angle, m, 0.5, size) for angle, m in LONG_CONES for size in (0.05, 0.025)]
CASES += [(angle, m, 0.25, 0.0125) for angle, m in ((15.0, 0.1), (15.0, 0.2), (30.0, 0.1),
                                                    (30.0, 0.5))]


def cone_zone_slope(angle: float, m: float, exit_radius: float, mesh_size: float,
                    sections: int = 21) -> dict:
    """One FE run: d(mean sigma_xx)/d ln(A0/A) / sigma0 over the middle half of the cone of a bar
    of radius 1 extruded to ``exit_radius``."""
    scene = scene_from_dict({
        "process": {"kind": "extrusion", "velocity": 1.0},
        "geometry": {"die": "conical", "symmetry": "axisymmetric", "entry_diameter": 2.0,
                     "exit_diameter": 2 * exit_radius, "die_angle": angle, "die_entry": 2.0,
                     "land_length": 0.0},
        "material": {"law": "piecewise_power", "A": 1.0},
        "friction": {"law": "factor", "m": m},
        "discretisation": {"averaging": "quadrature", "mesh_size": mesh_size,
                           "corner_grading": 4.0, "wall_grading": 1.0},  # docs' meshes
        "solver": {"method": "newton"}, "output": {"fields": False, "figures": False}})
    problem, _, summary = solve_scene(scene)
    g, sigma0 = scene.geometry, summary["scales"]["flow_stress"]
    profile = g.profile()
    xs = g.die_entry + g.cone_length * np.linspace(0.25, 0.75, sections)
    radii = [profile.radius_at(x) for x in xs]
    log_area = [2 * math.log(1.0 / r) for r in radii]
    stress = [mean_axial_stress(problem, x, r * (1 - 1e-9), 48) / sigma0 for x, r in zip(xs, radii)]
    slope = float(np.polyfit(log_area, stress, 1)[0])
    return {"angle": angle, "m": m, "mesh_size": mesh_size, "fe_slope": slope,
            "shield": shield_cone_factor(angle, m), "avitzur": avitzur_cone_factor(angle, m),
            "exit_radius": exit_radius, "cone_length_over_exit_radius": g.cone_length / exit_radius,
            "converged": summary["converged"], "solves": summary["linear_solves"],
            "warnings": summary["warnings"]}


def main() -> None:
    argparse.ArgumentParser(description=__doc__.splitlines()[0]).parse_args()
    rows = []
    for angle, m, exit_radius, size in CASES:
        rows.append(cone_zone_slope(angle, m, exit_radius, size))
        print(json.dumps(rows[-1]), flush=True)
    out = ROOT / "results"
    out.mkdir(exist_ok=True)
    (out / "shield_cone_zone.json").write_text(json.dumps(rows, indent=1))
    table = markdown_table("FE cone zone against Shield", [
        "angle", "m", "R1", "h", "cone length / R1", "FE slope", "Shield c/2", "FE / Shield",
        "Avitzur cone terms", "solves", "converged"],
        [[f"{r['angle']:g}", f"{r['m']:g}", f"{r['exit_radius']:g}", f"{r['mesh_size']:g}",
          f"{r['cone_length_over_exit_radius']:.2f}", f"{r['fe_slope']:.4f}", f"{r['shield']:.4f}",
          f"{r['fe_slope'] / r['shield']:.3f}", f"{r['avitzur']:.4f}", r["solves"],
          r["converged"]] for r in rows])
    (out / "shield_cone_zone.md").write_text(table + "\n")
    print(table)


if __name__ == "__main__":
    main()

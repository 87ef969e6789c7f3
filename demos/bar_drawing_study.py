"""Square and rectangular bar drawing as 3D quarters beside the slab method and an upper bound
(docs/three_d.md).

Each demo (demos/square_bar.toml, demos/rectangular_bar.toml) is solved on three meshes, the
scene's own and two finer, with three friction settings: its Coulomb mu (against Sachs' slab method
for the die's faces, which is Sachs' formula for the equivalent round die: the same area reduction,
the faces' width-weighted semi-angle), the friction factor m = sqrt3 mu (tau = mu sigma0,
Coulomb's shear at a die pressure equal to the flow stress, against the upper bound of the
homogeneous-compression field) and none (against the ideal work ln(A0/A1): the redundant work
alone). The finest values carry Richardson's estimate (core/richardson.py). The equivalent round
die is solved axisymmetrically on three meshes too (the same law, frictions, land and speed) to
tell the corners' share of a difference from the redundant work's. Writes results/bar_drawing.json;
``--report`` prints the tables again from it. Run: .venv/bin/python demos/bar_drawing_study.py
(docs/three_d.md gives its time on one core).
"""
from __future__ import annotations

import argparse
import json
import math
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np

from forming_fenicsx.app.run import solve_scene
from forming_fenicsx.config.loader import read_scene_data, scene_from_dict
from forming_fenicsx.core.report import markdown_table
from forming_fenicsx.core.richardson import estimate, relative
from forming_fenicsx.physics.closed_forms import (RectangularDie, avitzur_drawing_stress,
                                                  central_burst_indicator,
                                                  rectangular_upper_bound, sachs_drawing_stress,
                                                  sachs_rectangular_drawing_stress)

ROOT = Path(__file__).resolve().parents[1]
SQRT3 = math.sqrt(3.0)
KEYS = ("drawing_stress", "drawing_force", "mean_die_pressure", "contact_area",
        "mean_exit_strain", "die_separation_force", "die_side_force", "force_balance_residual",
        "dofs", "linear_solves", "wall_time_s", "converged", "warnings", "failed_checks")
LAWS = ("coulomb", "factor", "none")
# solver.force_tolerance of every run: without it Newton stopped the frictionless rectangle on a
# small increment with its x forces 12 to 19 % apart (docs/three_d.md)
FORCE_TOLERANCE = 1e-4
# the round die's meshes, times its exit radius (the default 1/15 and two halvings)
ROUND_SIZES = (1 / 15, 1 / 30, 1 / 60)
# the demo's quantities on every mesh: (summary key, column)
QUANTITIES = (("drawing_stress", "sigma_d [MPa]"), ("drawing_force", "F_d [N]"),
              ("mean_die_pressure", "mean die pressure [MPa]"),
              ("die_separation_force", "separation force [N]"),
              ("die_side_force", "side force [N]"), ("mean_exit_strain", "mean exit strain"))


class Case(NamedTuple):
    """A demo scene and its meshes (mm, coarse to fine; the first is the scene's own)."""

    scene: str
    sizes: tuple[float, ...]


CASES = {"square": Case("demos/square_bar.toml", (1.0, 5 / 7, 0.5)),
         "rectangle": Case("demos/rectangular_bar.toml", (1.0, 2 / 3, 0.5))}


def friction_table(law: str, mu: float) -> dict[str, Any]:
    """The [friction] of a run: the scene's Coulomb mu, the factor m = sqrt3 mu, or none."""
    return {"coulomb": {"law": "coulomb", "mu": mu}, "factor": {"law": "factor", "m": SQRT3 * mu},
            "none": {}}[law]


def run(data: dict[str, Any]) -> dict[str, Any]:
    """One FE run of a scene's data, iterated until the x forces balance to FORCE_TOLERANCE too:
    the summary's numbers and sigma0 (at the process rate)."""
    solver = {**data.get("solver", {}), "force_tolerance": FORCE_TOLERANCE}
    summary = solve_scene(scene_from_dict({**data, "solver": solver}))[2]
    return {**{key: summary.get(key) for key in KEYS},
            "flow_stress": summary["scales"]["flow_stress"]}


def die_of(geometry: dict[str, Any]) -> RectangularDie:
    return RectangularDie.of(geometry["entry_height"], geometry["exit_height"],
                             geometry["entry_width"], geometry["exit_width"],
                             geometry["die_angle"], geometry.get("land_length", 0.0))


def round_die_data(data: dict[str, Any], die: RectangularDie) -> dict[str, Any]:
    """The equivalent round die, axisymmetric: the same areas (diameters 2 sqrt(A/pi)), the faces'
    width-weighted semi-angle in mid-die, the same land, law, friction and speed."""
    geometry = {"symmetry": "axisymmetric",
                "entry_diameter": 4 * math.sqrt(die.h0 * die.w0 / math.pi),
                "exit_diameter": 4 * math.sqrt(die.h1 * die.w1 / math.pi),
                "die_angle": die.effective_angle(0.5 * die.length), "land_length": die.land}
    return {**data, "geometry": geometry}


def solve_case(name: str, case: Case) -> dict[str, Any]:
    """The FE runs of one demo: every friction setting on every mesh, and the round die's."""
    data = read_scene_data(ROOT / case.scene)
    mu = data["friction"]["mu"]
    round_data = round_die_data(data, die_of(data["geometry"]))
    rows: dict[str, Any] = {"scene": case.scene, "mu": mu, "sizes": list(case.sizes)}
    for law in LAWS:
        runs = []
        for size in case.sizes:
            mesh = {**data["discretisation"], "mesh_size": size}
            runs.append(run({**data, "friction": friction_table(law, mu), "discretisation": mesh}))
            print(name, law, size, json.dumps(runs[-1]), flush=True)
        rows[law] = runs
        rows[f"round_{law}"] = [
            run({**round_data, "friction": friction_table(law, mu),
                 "discretisation": {"averaging": "quadrature", "mesh_size_relative": size}})
            for size in ROUND_SIZES]
        print(name, "round", law, json.dumps(rows[f"round_{law}"][-1]), flush=True)
    return rows


def slab_mean_pressure(die: RectangularDie, mu: float, nodes: int = 24) -> float:
    """The slab method's die pressure p = Ybar - sigma_x over Ybar, averaged over the cone's faces:
    sigma_x(x) is Sachs' drawing stress of the die cut off at x."""
    g, weights = np.polynomial.legendre.leggauss(nodes)
    x = 0.5 * die.length * (g + 1)
    h, w = die.sections(x)
    angle = math.degrees(math.atan(die.tan_alpha))
    stress = np.array([sachs_rectangular_drawing_stress(RectangularDie.of(
        2 * die.h0, 2 * hx, 2 * die.w0, 2 * wx, angle), mu) for hx, wx in zip(h, w)])
    area = weights * (w * math.hypot(1, die.tan_alpha) + h * math.hypot(1, die.tan_beta))
    return float(np.sum(area * (1 - stress)) / np.sum(area))


def closed_forms(rows: dict[str, Any]) -> dict[str, float]:
    """The closed forms of a demo over sigma0: the ideal work, Sachs (slab, Coulomb mu) and its
    mean die pressure, the upper bound (m = sqrt3 mu; frictionless) and its land term; for the
    equivalent round die Sachs (its land over its perimeter) and Avitzur's bound, its angle and
    Delta."""
    die = die_of(read_scene_data(ROOT / rows["scene"])["geometry"])
    mu, m = rows["mu"], SQRT3 * rows["mu"]
    bound = rectangular_upper_bound(die, m)
    angle = die.effective_angle(0.5 * die.length)
    reduction = 1 - math.exp(-die.log_area_ratio)
    radius = 2 * math.sqrt(die.h1 * die.w1 / math.pi)
    cone = sachs_drawing_stress(reduction, angle, mu)
    return {"ideal": die.log_area_ratio,
            "sachs": sachs_rectangular_drawing_stress(die, mu),
            "sachs_round": 1 - (1 - cone) * math.exp(-2 * mu * die.land / radius),
            "slab_pressure": slab_mean_pressure(die, mu),
            "bound": bound.total, "bound_land": bound.land,
            "bound_none": rectangular_upper_bound(die, 0.0).total,
            "avitzur": avitzur_drawing_stress(reduction, angle, m, die.land / radius),
            "avitzur_none": avitzur_drawing_stress(reduction, angle, 0.0),
            "width_angle": die.width_angle, "effective_angle": angle,
            "delta": central_burst_indicator(reduction, angle, "axisymmetric")}


def limit(runs: list[dict[str, Any]], sizes: list[float], key: str,
          over: float = 1.0) -> tuple[float, float]:
    """(Richardson's limit of a quantity over ``over``, its finest value's estimated relative
    error); the finest value when nothing extrapolates."""
    values = [r[key] / over for r in runs]
    found = estimate(sizes, values)
    extrapolated = found.extrapolated if math.isfinite(found.extrapolated) else values[-1]
    return extrapolated, relative(found, values[-1])


def mesh_table(name: str, rows: dict[str, Any]) -> str:
    """The demo (its Coulomb friction) on every mesh, with Richardson's limit of each quantity."""
    runs, sizes = rows["coulomb"], rows["sizes"]
    table = [[size, r["dofs"], *(r[key] for key, _ in QUANTITIES), r["linear_solves"],
              f"{r['force_balance_residual']:.1e}", round(r["wall_time_s"])]
             for size, r in zip(sizes, runs, strict=True)]
    limits = [limit(runs, sizes, key) for key, _ in QUANTITIES]
    table.append(["Richardson", "", *(value for value, _ in limits), "", "", ""])
    table.append(["its error", "", *(f"{100 * error:.2g} %" for _, error in limits), "", "", ""])
    return markdown_table(
        f"{name} (Coulomb mu = {rows['mu']}, sigma0 = {runs[-1]['flow_stress']:.5g} MPa)",
        ["mesh size [mm]", "dofs", *(column for _, column in QUANTITIES), "linear solves",
         "force balance", "wall s"], table)


def comparison_rows(name: str, rows: dict[str, Any]) -> list[list[Any]]:
    """sigma_d/sigma0 of each friction setting: the 3D FE (finest, Richardson, its error), the
    round die's FE (Richardson), the estimates for the bar and the round die, and the ratios."""
    forms = closed_forms(rows)
    estimates = {"coulomb": ("Sachs", forms["sachs"], forms["sachs_round"]),
                 "factor": ("bound / Avitzur", forms["bound"], forms["avitzur"]),
                 "none": ("bound / Avitzur", forms["bound_none"], forms["avitzur_none"])}
    table = []
    for law in LAWS:
        sigma0 = rows[law][-1]["flow_stress"]
        bar, error = limit(rows[law], rows["sizes"], "drawing_stress", sigma0)
        round_die = limit(rows[f"round_{law}"], list(ROUND_SIZES), "drawing_stress",
                          rows[f"round_{law}"][-1]["flow_stress"])[0]
        label, for_bar, for_round = estimates[law]
        table.append([name, law, rows[law][-1]["drawing_stress"] / sigma0, bar,
                      f"{100 * error:.2g} %", round_die, forms["ideal"], label, for_bar,
                      for_round, bar / forms["ideal"], bar / for_bar, round_die / for_round,
                      bar / round_die])
    return table


def report(results: dict[str, Any]) -> str:
    """The tables of docs/three_d.md: each demo on its meshes, the FE beside the estimates, the
    closed forms' inputs."""
    parts = [mesh_table(name, rows) for name, rows in results.items()]
    parts.append(markdown_table(
        "sigma_d/sigma0: FE (finest mesh and Richardson) beside the estimates",
        ["bar", "friction", "FE 3D finest", "FE 3D Richardson", "its error", "FE round die",
         "ideal ln(A0/A1)", "estimate", "for the bar", "for the round die", "FE 3D / ideal",
         "FE 3D / estimate", "FE round / estimate", "FE 3D / FE round"],
        [row for name, rows in results.items() for row in comparison_rows(name, rows)]))
    dies = []
    for name, rows in results.items():
        forms = closed_forms(rows)
        pressure = limit(rows["coulomb"], rows["sizes"], "mean_die_pressure",
                         rows["coulomb"][-1]["flow_stress"])[0]
        dies.append([name, forms["width_angle"], forms["effective_angle"], forms["delta"],
                     forms["bound_land"], forms["slab_pressure"], pressure])
    parts.append(markdown_table(
        "the dies and the die pressure over sigma0",
        ["bar", "width angle [deg]", "equivalent round die's angle", "its Delta",
         "the bound's land term", "slab mean die pressure", "FE mean die pressure (Richardson)"],
        dies))
    return "\n".join(parts)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cases", nargs="+", choices=tuple(CASES), default=tuple(CASES))
    parser.add_argument("--out", default=str(ROOT / "results" / "bar_drawing.json"))
    parser.add_argument("--report", action="store_true",
                        help="print the tables from --out without solving")
    args = parser.parse_args()
    out = Path(args.out)
    if not args.report:
        results = json.loads(out.read_text()) if out.exists() else {}
        for name in args.cases:
            results[name] = solve_case(name, CASES[name])
            out.parent.mkdir(parents=True, exist_ok=True)
            out.write_text(json.dumps(results, indent=1))
    print(report(json.loads(out.read_text())))


if __name__ == "__main__":
    main()

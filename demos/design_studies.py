"""The shipped die-angle design studies beside the upper bounds of Avitzur's method: the FE optimum
(parabola through the least run and its neighbours, as `forming study` reports it) against the
bound's optimum angle and drawing stress; a table for docs/design_studies.md and a figure.

    .venv/bin/forming study demos/strip_die_angle.study.toml --out results/strip_die_angle
    .venv/bin/forming study demos/wire_die_angle.study.toml --out results/wire_die_angle
    .venv/bin/python demos/design_studies.py results docs
"""
from __future__ import annotations

import json
import math
import shutil
import sys
from pathlib import Path

from forming_fenicsx.physics.closed_forms import (avitzur_drawing_stress, avitzur_optimum_angle,
                                                  strip_optimum_angle,
                                                  upper_bound_strip_drawing_stress)
from forming_fenicsx.core.report import markdown_table
from forming_fenicsx.app.study import load_study, study_scenes

DEMOS = Path(__file__).parent
CASES = ("strip_die_angle", "wire_die_angle")


def bound(scene, reduction: float):
    """The bound's drawing stress as a function of the semi-angle, in the scene's stress unit, and
    its optimum angle: Avitzur's cone (sigma0 times his factor) or the wedge (2k times its factor),
    with the land's friction; sigma0 is the flow stress at the process strain rate."""
    g, m = scene.geometry, scene.friction.m
    sigma0 = scene.scales.flow_stress
    land = g.land_length / (0.5 * g.exit_thickness)
    if g.axisymmetric:
        return (lambda a: sigma0 * avitzur_drawing_stress(reduction, a, m, land)), \
            avitzur_optimum_angle(reduction, m, land)
    two_k = 2 * sigma0 / math.sqrt(3)
    return (lambda a: two_k * upper_bound_strip_drawing_stress(reduction, a, m, land)), \
        strip_optimum_angle(reduction, m, land)


def main(results: Path, docs: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np

    rows = []
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.5))
    for case, ax in zip(CASES, axes, strict=True):
        data, vary, _ = load_study(DEMOS / f"{case}.study.toml")
        base = study_scenes(data, vary)[0]
        stored = json.loads((results / case / "study.json").read_text())
        runs = stored["runs"]
        angles = [float(r["settings"]["geometry.die_angle"]) for r in runs]
        fe = [r["drawing_stress"] for r in runs]
        optimum = next(o for o in stored["optima"] if o["quantity"] == "drawing_stress")
        reduction = runs[0]["reduction"]
        stress, best = bound(base, reduction)
        fine = np.linspace(min(angles), max(angles), 200)
        ax.plot(angles, fe, "o-", label="FE (forming study)")
        ax.plot(fine, [stress(a) for a in fine], "k--", label="upper bound (Avitzur's method)")
        ax.plot(optimum["location"], optimum["value"], "*", markersize=14, markeredgecolor="k",
                label=f"FE optimum {optimum['location']:.2f} deg")
        ax.plot(best, stress(best), "kD", label=f"bound's optimum {best:.2f} deg")
        kind = "round wire" if base.geometry.axisymmetric else "strip"
        ax.set_title(f"{kind}, reduction {reduction:.2f}, m = {base.friction.m:g}", fontsize=10)
        ax.set_xlabel("die semi-angle [deg]")
        ax.set_ylabel(base.units.labelled("drawing stress", "stress"))
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=8)
        rows.append([kind, f"{reduction:.3f}", f"{optimum['location']:.2f}",
                     f"{optimum['value']:.2f}", f"{best:.2f}", f"{stress(best):.2f}",
                     f"{optimum['value'] / stress(best):.3f}",
                     f"{sum(r['wall_time_s'] for r in runs):.0f}"])
        for quantity in stored["quantities"]:
            shutil.copy(results / case / f"{quantity}.png", docs / f"{case}_{quantity}.png")
    fig.tight_layout()
    fig.savefig(docs / "design_studies.png", dpi=110)
    print(markdown_table(None, ["product", "reduction", "FE optimum [deg]",
                                "FE least drawing stress [MPa]", "bound's optimum [deg]",
                                "bound at its optimum [MPa]", "FE / bound", "wall s (10 runs)"],
                         rows))


if __name__ == "__main__":
    main(Path(sys.argv[1]), Path(sys.argv[2]))

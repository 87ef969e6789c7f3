"""Round-wire drawing through conical dies: the FE drawing stress against Sachs (Coulomb mu) and
Avitzur (friction factor m) over die semi-angles, reductions and friction (docs/conical_dies.md).

Axisymmetric, the paper's law (4.5) with A = 1 (nearly rate-independent: sigma0 = sigma_p at the
process rate), no land, default mesh (Q2). Writes results/conical_dies.json, docs/conical_dies.md
and docs/conical_dies.png. Run: .venv/bin/python demos/conical_die_study.py (about 5 minutes, 1
core).
"""
from __future__ import annotations

import argparse
import json
import math
from pathlib import Path

import numpy as np

from forming_fenicsx.physics.closed_forms import (avitzur_drawing_stress, avitzur_optimum_angle,
                                                  avitzur_optimum_angle_approx,
                                                  sachs_drawing_stress)
from forming_fenicsx.core.report import markdown_table
from forming_fenicsx.app.run import solve_scene
from forming_fenicsx.config.loader import scene_from_dict

ROOT = Path(__file__).resolve().parents[1]
ANGLES = (4.0, 6.0, 8.0, 10.0, 15.0, 20.0, 30.0)
REDUCTIONS = (0.1, 0.2, 0.4)
FRICTION = (("coulomb", 0.0), ("coulomb", 0.1), ("coulomb", 0.2), ("factor", 0.1), ("factor", 0.2))


def drawing_stress(angle: float, reduction: float, law: str, value: float) -> dict:
    """One FE run: sigma_d / sigma0, with its linear solves and whether it converged."""
    scene = scene_from_dict({
        "process": {"kind": "drawing", "velocity": 1.0},
        "geometry": {"symmetry": "axisymmetric", "entry_diameter": 2.0,
                     "exit_diameter": 2.0 * math.sqrt(1 - reduction), "die_angle": angle,
                     "land_length": 0.0},
        "material": {"law": "piecewise_power", "A": 1.0},
        "friction": {"law": law, ("mu" if law == "coulomb" else "m"): value},
        # uniform blocks: the meshes of docs' numbers (the defaults grade toward the die)
        "discretisation": {"averaging": "quadrature", "corner_grading": 1.0, "wall_grading": 1.0},
        "solver": {"method": "newton"}, "output": {"fields": False, "figures": False}})
    summary = solve_scene(scene)[2]
    return {"angle": angle, "reduction": reduction, "law": law, "value": value,
            "fe": summary["drawing_stress"] / summary["scales"]["flow_stress"],
            "converged": summary["converged"], "solves": summary["linear_solves"],
            "central_burst_indicator": summary["central_burst_indicator"],
            "warnings": summary["warnings"]}


def closed_form(row: dict) -> float:
    if row["law"] == "coulomb":
        return sachs_drawing_stress(row["reduction"], row["angle"], row["value"])
    return avitzur_drawing_stress(row["reduction"], row["angle"], row["value"])


def trusted(row: dict) -> bool:
    """Converged with no sanity warning (docs/sanity.md)."""
    return row["converged"] and not row["warnings"]


def warning_name(row: dict) -> str:
    """A short name for the run's sanity warnings."""
    names = {"crosses the free surfaces": "free surface crossed",
             "yield stress in tension": "product near yield"}
    return ", ".join(short for text in row["warnings"] for key, short in names.items()
                     if key in text)


def schey_factor(row: dict) -> float:
    """Schey's redundant-work factor phi = 0.88 + 0.12 Delta (reference section 2, Groover)."""
    return 0.88 + 0.12 * row["central_burst_indicator"]


def fitted_minimum(line: list[dict]) -> tuple[float, float, list[dict]]:
    """The least FE drawing stress over the angles: the vertex of the parabola through the grid's
    least value and its two neighbours (the least grid point itself at an end of the grid), and
    the rows it used."""
    line = sorted(line, key=lambda r: r["angle"])
    least = min(range(len(line)), key=lambda i: line[i]["fe"])
    if least in (0, len(line) - 1):
        return line[least]["angle"], line[least]["fe"], [line[least]]
    near = line[least - 1:least + 2]
    a, b, c = np.polyfit([r["angle"] for r in near], [r["fe"] for r in near], 2)
    return -b / (2 * a), c - b * b / (4 * a), near


def figure(rows: list[dict], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, len(REDUCTIONS), figsize=(15, 4.5), sharey=False)
    for ax, reduction in zip(axes, REDUCTIONS, strict=True):
        for (law, value), colour in zip(FRICTION, ("k", "C0", "C1", "C2", "C3"), strict=True):
            line = [r for r in rows
                    if r["reduction"] == reduction and (r["law"], r["value"]) == (law, value)]
            name = f"mu = {value:g}" if law == "coulomb" else f"m = {value:g}"
            ax.plot([r["angle"] for r in line], [r["fe"] for r in line], "-", color=colour)
            ax.plot([r["angle"] for r in line if trusted(r)], [r["fe"] for r in line if trusted(r)],
                    "o", color=colour, label=f"FE {name}")
            ax.plot([r["angle"] for r in line if not trusted(r)],
                    [r["fe"] for r in line if not trusted(r)], "o", mfc="none", color=colour)
            ax.plot([r["angle"] for r in line], [r["closed_form"] for r in line], "--",
                    color=colour, label=("Sachs " if law == "coulomb" else "Avitzur ") + name)
        ax.set_title(f"reduction of area {reduction:.0%}")
        ax.set_xlabel("die semi-angle [deg]")
        ax.set_ylabel("drawing stress / flow stress")
        ax.grid(True, alpha=0.3)
    axes[0].legend(fontsize=7)
    fig.suptitle("Round wire drawing, FE (lines with dots; open dots: not converged or a sanity "
                 "warning) against Sachs (Coulomb mu) and Avitzur (friction factor m)")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--angles", type=float, nargs="+", default=ANGLES)
    parser.add_argument("--out", default=str(ROOT / "results" / "conical_dies.json"))
    parser.add_argument("--replot", action="store_true",
                        help="redraw the figure and tables from the --out file, without running")
    args = parser.parse_args()
    out = Path(args.out)
    rows = json.loads(out.read_text()) if args.replot else []
    for reduction in REDUCTIONS if not args.replot else ():
        for angle in args.angles:
            for law, value in FRICTION:
                row = drawing_stress(angle, reduction, law, value)
                row["closed_form"] = closed_form(row)
                rows.append(row)
                print(json.dumps(row), flush=True)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(rows, indent=1))
    figure(rows, ROOT / "docs" / "conical_dies.png")
    table = markdown_table("conical dies", [
        "reduction", "angle", "friction", "FE", "closed form", "FE / closed form", "Delta",
        "FE / (Sachs phi)", "solves", "converged", "warning"],
        [[f"{r['reduction']:.0%}", f"{r['angle']:g}", ("mu " if r["law"] == "coulomb" else "m ")
          + f"{r['value']:g}", f"{r['fe']:.4f}", f"{r['closed_form']:.4f}",
          f"{r['fe'] / r['closed_form']:.3f}", f"{r['central_burst_indicator']:.2f}",
          f"{r['fe'] / (r['closed_form'] * schey_factor(r)):.3f}" if r["law"] == "coulomb" else "",
          r["solves"], r["converged"], warning_name(r)] for r in rows])
    optima = []
    for reduction in REDUCTIONS:
        for m in (0.1, 0.2):
            line = [r for r in rows if r["reduction"] == reduction and r["law"] == "factor"
                    and r["value"] == m and r["converged"]]
            angle, value, near = fitted_minimum(line)
            flagged = ", ".join(f"{r['angle']:g}" for r in near if not trusted(r))
            optima.append([f"{reduction:.0%}", f"{m:g}", f"{angle:.2f}", f"{value:.4f}", flagged,
                           f"{avitzur_optimum_angle(reduction, m):.2f}",
                           f"{avitzur_optimum_angle_approx(reduction, m):.2f}"])
    (ROOT / "results" / "conical_dies_table.md").write_text(
        table + "\n\n" + markdown_table("optimum", [
            "reduction", "m", "FE optimum angle", "FE least sigma_d/sigma0",
            "fitted angles with a warning", "Avitzur optimum",
            "Avitzur approximation"], optima))
    print(table)


if __name__ == "__main__":
    main()

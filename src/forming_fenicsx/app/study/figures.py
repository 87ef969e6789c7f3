"""Figures of `forming study`: the Pareto plot of a study with references and, for a design study,
each quantity against the design parameter with its interior optimum."""
from __future__ import annotations

import itertools
import math
from pathlib import Path
from typing import Any

import numpy as np

from forming_fenicsx.app.study.analysis import (MESH_KEYS, is_design_key, positions, relative_error,
                                                series, value)
from forming_fenicsx.core.numbers import is_number
from forming_fenicsx.core.units import Units

NOT_LENGTHS = ("symmetry", "die", "mesh_file", "die_profile_file")


def _pyplot():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def parameter_label(key: str, units: Units) -> str:
    """An axis label for a varied scene key: angles in degrees, geometry sizes in the length unit,
    the process velocity in its unit, other keys by name."""
    name = key.split(".")[-1]
    if name.endswith("angle"):
        return f"{name.replace('_', ' ')} [deg]"
    if key.startswith("geometry.") and name not in NOT_LENGTHS:
        return units.labelled(name.replace("_", " "), "length")
    if key == "process.velocity":
        return units.labelled("velocity", "velocity")
    return name.replace("_", " ")


def quantity_plots(out: Path, rows: list[dict[str, Any]], quantities: list[str], keys: list[str],
                   optima: list[dict[str, Any]], units: Units, whole_forces: bool) -> list[Path]:
    """<quantity>.png for each quantity: its converged values against the first design key, one
    line per setting of the other keys, the reference per design point (dashed) where there is
    one, and each line's interior optimum (a star at the vertex of the dotted parabola through the
    least value and its neighbours); a converged run with sanity warnings ringed in red (its
    numbers may be off: study.md lists the warnings)."""
    plt = _pyplot()
    parameter = next(k for k in keys if is_design_key(k))
    name = parameter.split(".")[-1].replace("_", " ")
    paths = []
    for quantity in quantities:
        fig, ax = plt.subplots(figsize=(8, 5))
        lines = series(rows, quantity, keys)
        for (label, xs, ys, kind), marker in zip(lines, itertools.cycle("osD^v<>p")):
            runs = kind == "runs"
            shown = (label or quantity) if runs else f"{kind}{', ' + label if label else ''}"
            drawn = ax.plot(xs, ys, "-" if runs else "k--", marker=marker if runs else None,
                            label=shown)[0]
            optimum = next((o for o in optima if o["quantity"] == quantity and o["others"] == label
                            and o["line"] == kind and o["location"] is not None), None)
            if optimum is not None:
                through = np.array(optimum["through"])
                fine = np.linspace(through[0, 0], through[-1, 0], 50)
                parabola = np.polyval(np.polyfit(*through.T, 2), fine)
                ax.plot(fine, parabola, ":", color=drawn.get_color())
                ax.plot(optimum["location"], optimum["value"], "*", markersize=14,
                        color=drawn.get_color(), markeredgecolor="k",
                        label=f"optimum {optimum['location']:.4g}: {optimum['value']:.4g}")
        where = positions(rows, parameter)
        warned = [(where[r["settings"][parameter]], value(r, quantity)) for r in rows
                  if r["converged"] and r.get("warnings")]
        if warned:
            ax.plot(*zip(*warned, strict=True), "o", markersize=13, markerfacecolor="none",
                    markeredgecolor="tab:red", linestyle="none",
                    label="warned: its numbers may be off (study.md)")
        if not all(is_number(v) for v in where):  # categories: their names at their places
            ax.set_xticks(list(where.values()), list(where))
        ax.set_xlabel(parameter_label(parameter, units))
        unit = units.label(units.dimension(quantity, whole_forces))
        ax.set_ylabel(f"{quantity.replace('_', ' ')}{f' [{unit}]' if unit else ''}")
        ax.set_title(f"{quantity.replace('_', ' ')} against {name}")
        ax.grid(True, alpha=0.3)
        if lines:
            ax.legend(fontsize=8)
        fig.tight_layout()
        path = out / f"{quantity}.png"
        fig.savefig(path, dpi=120)
        plt.close(fig)
        paths.append(path)
    return paths


def pareto_plot(path: Path, rows: list[dict[str, Any]], quantities: list[str],
                keys: list[str]) -> Path:
    """Wall time against relative error, log-log, a panel per quantity with a reference, one line
    per setting of the varied keys but the mesh size."""
    plt = _pyplot()
    width = 9 + 4 * (len(quantities) - 1)
    fig, axes = plt.subplots(1, len(quantities), figsize=(width, 5), squeeze=False)
    others = [k for k in keys if k not in MESH_KEYS]
    for ax, quantity in zip(axes[0], quantities, strict=True):
        lines: dict[str, list[tuple[float, float]]] = {}
        for row in rows:
            error = relative_error(row, quantity)
            if row["converged"] and math.isfinite(error) and error > 0:
                label = ", ".join(str(row["settings"][k]) for k in others) or quantity
                lines.setdefault(label, []).append((row["wall_time_s"], error))
        for marker, (label, points) in zip(itertools.cycle("osD^v<>p*"), lines.items()):
            ax.loglog(*zip(*sorted(points), strict=True), marker=marker, label=label)
        ax.set_xlabel("wall time [s]")
        ax.set_ylabel(f"relative error of {quantity}")
        ax.grid(True, which="both", alpha=0.3)
        if lines and ax is axes[0][-1]:
            title = ", ".join(k.split(".")[-1] for k in others) or None
            ax.legend(fontsize=8, title=title, title_fontsize=8, loc="upper left",
                      bbox_to_anchor=(1.02, 1.0))
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path

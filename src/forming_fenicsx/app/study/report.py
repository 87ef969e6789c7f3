"""A study's report: study.md (runs, optima, the cheapest settings, the warnings) and study.csv."""
from __future__ import annotations
import math
from pathlib import Path
from typing import Any
from forming_fenicsx.core.report import markdown_table
from forming_fenicsx.core.units import Units
from forming_fenicsx.app.study.analysis import (cheapest, has_reference, is_design_key,
                                                relative_error, value)


def _unit_label(units: Units, name: str, whole_forces: bool) -> str:
    unit = units.label(units.dimension(name, whole_forces))
    return f"{name} [{unit}]" if unit else name


def report(rows: list[dict[str, Any]], quantities: list[str],
           optima: list[dict[str, Any]] | None = None, units: Units | None = None,
           whole_forces: bool = False) -> str:
    """Markdown: every run (a design study's in parameter order, a speed-accuracy study's by wall
    time) with its quantities, their errors and references where there are any, whether it
    converged, how many sanity warnings it has, and its cost; a design study's interior optima;
    the cheapest converged setting per error level (per design point) where a reference exists;
    each warned run's warnings, by its settings."""
    units = units or Units()
    keys = list(rows[0]["settings"]) if rows else []
    design = any(is_design_key(k) for k in keys)
    measured = [q for q in quantities if has_reference(rows, q)]
    header = [*keys]
    for q in quantities:
        header += [_unit_label(units, q, whole_forces)]
        header += ["error", "reference"] if q in measured else []
    header += ["converged", "warnings", "wall s", "linear solves", "dofs"]
    lines = []
    for r in rows if design else sorted(rows, key=lambda r: r["wall_time_s"]):
        line = [str(r["settings"][k]) for k in keys]
        for q in quantities:
            line.append(f"{value(r, q):.5g}")
            if q in measured:
                error = relative_error(r, q)
                line += [f"{100 * error:.2f}%", r["reference"][q]["kind"]] if math.isfinite(error) \
                    else ["-", "none"]
        lines.append([*line, "yes" if r["converged"] else "no",
                      len(r.get("warnings", [])) or "-", f"{r['wall_time_s']:.2f}",
                      r["linear_solves"], r["dofs"]])
    parts = [markdown_table(None, header, lines)]
    if design:
        parts.append(_optima_table(optima or [], units, whole_forces))
    if measured:
        parts.append(_cheapest_table(rows, quantities, keys))
    elif not design:
        parts.append("No reference: errors need an exact value or at least three mesh sizes "
                     "(discretisation.mesh_size or mesh_size_relative, halved each time).")
    parts.append(_warnings_list(rows, keys))
    return "\n\n".join(p for p in parts if p)


def _warnings_list(rows: list[dict[str, Any]], keys: list[str]) -> str:
    """The sanity warnings of the runs that have any, by their settings (the numbers of a warned
    run may be off: docs/outputs.md)."""
    def named(settings: dict[str, str]) -> str:
        return ", ".join(f"{k.split('.')[-1]} = {settings[k]}" for k in keys)

    items = [f"- {named(r['settings'])}: {warning}" for r in rows
             for warning in r.get("warnings", [])]
    return "\n".join(["Warnings (the numbers of these runs may be off):", *items]) if items else ""


def _optima_table(optima: list[dict[str, Any]], units: Units, whole_forces: bool) -> str:
    if not optima:
        return ""
    parameter = optima[0]["parameter"]
    lines = [[_unit_label(units, o["quantity"], whole_forces), o["others"] or "-", o["line"],
              "no interior optimum" if o["location"] is None else f"{o['location']:.4g}",
              "" if o["value"] is None else f"{o['value']:.5g}"] for o in optima]
    header = ["quantity", "other settings", "line", f"optimum {parameter.split('.')[-1]}",
              "least value (parabola)"]
    return markdown_table(None, header, lines)


def _cheapest_table(rows: list[dict[str, Any]], quantities: list[str], keys: list[str]) -> str:
    design = [k for k in keys if is_design_key(k)]
    lines = []
    for entry in cheapest(rows, quantities):
        r = entry["run"]
        point = [str(entry["design"][k]) for k in design]
        if entry["level"] is None:
            lines.append([*point, "-", "no reference", "", "", "", ""])
            continue
        level = f"{100 * entry['level']:g} %"
        if r is None:
            lines.append([*point, level, "none reaches it", "", "", "", ""])
        else:
            setting = ", ".join(f"{k.split('.')[-1]} = {v}" for k, v in r["settings"].items()
                                if k not in design)
            lines.append([*point, level, setting or "-", f"{100 * entry['error']:.2f}%",
                          f"{r['wall_time_s']:.2f}", r["linear_solves"], r["dofs"]])
    return markdown_table(None, [*design, "error within", "cheapest setting", "error", "wall s",
                                 "linear solves", "dofs"], lines)


def write_csv(path: Path, rows: list[dict[str, Any]], quantities: list[str],
              keys: list[str]) -> None:
    """study.csv: settings, each quantity (with its reference, kind and relative error where the
    study has references for it), convergence and cost, and the run's folder when kept."""
    import csv

    measured = [q for q in quantities if has_reference(rows, q)]
    columns = [*keys]
    for q in quantities:
        columns.append(q)
        if q in measured:
            columns += [f"{q}_reference", f"{q}_reference_kind", f"{q}_relative_error"]
    tail = ["converged", "warnings", "wall_time_s", "linear_solves", "dofs"]
    tail += ["output"] if "output" in rows[0] else []
    with path.open("w", newline="") as stream:
        writer = csv.writer(stream)
        writer.writerow(columns + tail)
        for row in rows:
            line = [row["settings"][k] for k in keys]
            for q in quantities:
                line.append(row.get(q))
                if q in measured:
                    found = row["reference"][q]
                    line += [found["value"], found["kind"], found["relative_error"]]
            writer.writerow(line + [len(row.get("warnings", [])) if c == "warnings" else row.get(c)
                                    for c in tail])

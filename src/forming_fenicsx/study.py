"""`forming study`: a grid of runs of one scene over varied keys, each with its quantities and cost.

Two kinds of study, told apart by the varied keys:
- a speed-accuracy study varies numerical keys only (sections discretisation, solver, penalty,
  output): each quantity's error is taken against the exact value where one is known (Hill's ram
  pressure for frictionless Example 1 geometry at reduction 1/2, Hill's drawing field), otherwise
  against a Richardson extrapolation from the three finest mesh sizes of the same other settings;
  the report lists the runs by wall time and the cheapest setting per error level;
- a design study varies at least one physical key (process, geometry, material, friction): the
  report lists the runs in parameter order, each quantity is plotted against the first design key
  (one line per setting of the other keys) and an interior minimum is located by a parabola through
  the least value and its two neighbours. Error columns and the cheapest settings appear only where
  a reference exists (with the mesh varied too: Richardson per design point).
A study stopped and started again skips the runs its study.json already holds.
"""
from __future__ import annotations

import itertools
import json
import logging
import math
import re
import time
import tomllib
from pathlib import Path
from typing import Any

from mpi4py import MPI

from .errors import SceneError
from .output import json_safe
from .report import markdown_table, richardson
from .run import run_scene, solve_scene
from .scene import Scene, apply_overrides, parse_override, read_scene_data, scene_from_dict
from .units import Units

log = logging.getLogger(__name__)
QUANTITIES = {"extrusion": "ram_pressure", "drawing": "mean_die_pressure"}
NUMERICAL_SECTIONS = ("discretisation", "solver", "penalty", "output")
MESH_KEYS = ("discretisation.mesh_size", "discretisation.mesh_size_relative")  # absolute, relative
ERROR_LEVELS = (0.10, 0.03, 0.01)
# below this observed order the Richardson limit lies more than 2.4 times the last change beyond the
# finest value: the three meshes are taken as not yet in the asymptotic range (no reference)
LEAST_ORDER = 0.5


def parse_vary(texts: list[str]) -> list[tuple[str, list[str]]]:
    """``section.key=v1,v2,...`` -> (key, [override strings])."""
    grid = []
    for text in texts:
        keys, _ = parse_override(text)
        path = ".".join(keys)
        values = text.split("=", 1)[1].split(",")
        if not all(v.strip() for v in values):
            raise SceneError(path, "--vary needs a comma-separated list of values")
        grid.append((path, [f"{path}={v.strip()}" for v in values]))
    return grid


def parse_quantities(texts: str | list[str] | None) -> list[str]:
    """Quantity names from ``a,b`` strings or a list of them, in order, each once."""
    if texts is None:
        return []
    texts = [texts] if isinstance(texts, str) else texts
    names = [name.strip() for text in texts for name in text.split(",")]
    if not all(names):
        raise SceneError("--quantity", "needs summary keys separated by commas")
    return list(dict.fromkeys(names))


def is_design_key(key: str) -> bool:
    """A physical key (process, geometry, material, friction), not a numerical one."""
    return key.split(".")[0] not in NUMERICAL_SECTIONS


def load_study(path: str | Path, overrides: list[str] | None = None
               ) -> tuple[dict[str, Any], list[str], list[str]]:
    """A study file: a ``[study]`` table with ``scene`` (relative to the file), ``vary`` (a table of
    key = [values]), optional ``set`` (a list of overrides) and ``quantity`` (a summary key or a
    list of them). Returns the scene document (with ``set`` and then ``overrides`` applied), the
    --vary strings and the quantities (empty: the process's default)."""
    path = Path(path)
    try:
        table = tomllib.loads(path.read_text()).get("study")
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise SceneError(str(path), f"not valid TOML: {exc}") from None
    if not isinstance(table, dict):
        raise SceneError("study", f"{path} has no [study] table")
    unknown = set(table) - {"scene", "vary", "set", "quantity"}
    if unknown:
        raise SceneError(f"study.{sorted(unknown)[0]}",
                         "unknown key (known: scene, vary, set, quantity)")
    if not isinstance(table.get("scene"), str):
        raise SceneError("study.scene", "must name the scene file (relative to the study file)")
    vary, settings = table.get("vary"), table.get("set", [])
    if not (isinstance(vary, dict) and vary
            and all(isinstance(v, list) and v for v in vary.values())):
        raise SceneError("study.vary", "must be a table of section.key = [value, ...]")
    if not (isinstance(settings, list) and all(isinstance(o, str) for o in settings)):
        raise SceneError("study.set", "must be a list of \"section.key=value\" strings")
    quantity = table.get("quantity")
    if quantity is not None and not (isinstance(quantity, str) or (
            isinstance(quantity, list) and quantity and all(isinstance(q, str) for q in quantity))):
        raise SceneError("study.quantity", "must be a summary key or a list of them")
    data = read_scene_data(path.parent / table["scene"], [*settings, *(overrides or [])])
    texts = [f"{key}={','.join(_toml_value(v) for v in values)}" for key, values in vary.items()]
    return data, texts, parse_quantities(quantity)


def _toml_value(value: Any) -> str:
    return str(value).lower() if isinstance(value, bool) else str(value)


def exact_value(scene, quantity: str) -> float | None:
    """The exact value of ``quantity`` where a slip-line field is exact (verification.md):
    - frictionless square-die extrusion at reduction 1/2: Hill's ram pressure (1 + pi/2) k;
    - frictionless drawing without back tension at r = 2 sin(a)/(1 + 2 sin(a)) for the die
      semi-angle a: one triangle and a centred fan, q = 2k(1 + a)(1 - r), drawing stress
      2k(1 + a) r.
    Both are plane-strain fields: a round bar (symmetry = "axisymmetric") has none."""
    geometry, process = scene.geometry, scene.process
    rough = scene.friction.mu != 0 or scene.friction.m != 0
    if (rough or process.applied_force is not None or geometry.mesh_file is not None
            or geometry.axisymmetric):
        return None
    k = scene.material.flow_stress([1.0])[0] / math.sqrt(3.0)
    if (process.kind == "extrusion" and quantity == "ram_pressure" and geometry.die == "square"
            and math.isclose(geometry.exit_thickness, 0.5 * geometry.entry_thickness)):
        return (1 + math.pi / 2) * k
    if (process.kind == "drawing" and quantity in ("mean_die_pressure", "drawing_stress")
            and len(geometry.profile().segments) <= 2 and not geometry.entry_radius):
        angle = math.radians(geometry.die_angle)
        r = 2 * math.sin(angle) / (1 + 2 * math.sin(angle))
        if math.isclose(geometry.exit_thickness, geometry.entry_thickness * (1 - r), rel_tol=1e-9):
            return 2 * k * (1 + angle) * ((1 - r) if quantity == "mean_die_pressure" else r)
    return None


def value(row: dict[str, Any], quantity: str) -> float:
    """A run's quantity as a float (nan when missing or stored as null)."""
    found = row.get(quantity)
    return math.nan if found is None else float(found)


def _settings_key(settings: dict[str, str], skip: tuple[str, ...] = ()) -> str:
    return json.dumps({k: v for k, v in settings.items() if k not in skip}, sort_keys=True)


def _mesh_size(settings: dict[str, str]) -> float:
    """The varied mesh size (absolute or relative; inf when the mesh is not varied)."""
    return next((float(settings[k]) for k in MESH_KEYS if k in settings), math.inf)


def references(rows: list[dict[str, Any]], quantities: list[str]) -> None:
    """Set every row's ``reference``: for each quantity its value, kind (exact, Richardson from the
    three finest mesh sizes of the same other settings when their observed order is at least
    LEAST_ORDER, or none) and relative error (in place; the exact values are the rows'
    ``exact``)."""
    groups: dict[str, list[dict[str, Any]]] = {}
    for row in rows:
        groups.setdefault(_settings_key(row["settings"], MESH_KEYS), []).append(row)
        row["reference"] = {}
    for quantity, group in itertools.product(quantities, groups.values()):
        ranked = sorted((r for r in group if r["converged"] and math.isfinite(value(r, quantity))),
                        key=lambda r: -_mesh_size(r["settings"]))
        limit, order = richardson([value(r, quantity) for r in ranked]) if len(ranked) >= 3 \
            else (math.nan, math.nan)
        limit = limit if order >= LEAST_ORDER else math.nan
        for row in group:
            exact = row["exact"].get(quantity)
            if exact is not None:
                reference, kind = exact, "exact"
            elif math.isfinite(limit):
                reference, kind = limit, "richardson (three finest mesh sizes)"
            else:
                reference, kind = math.nan, "none"
            error = abs(value(row, quantity) / reference - 1) if math.isfinite(reference) \
                else math.nan
            row["reference"][quantity] = {"value": reference, "kind": kind, "relative_error": error}


def relative_error(row: dict[str, Any], quantity: str) -> float:
    """The row's relative error of ``quantity`` (nan without a reference)."""
    found = row.get("reference", {}).get(quantity, {}).get("relative_error")
    return math.nan if found is None else float(found)


def has_reference(rows: list[dict[str, Any]], quantity: str) -> bool:
    return any(math.isfinite(relative_error(r, quantity)) for r in rows)


def study_scenes(data: dict[str, Any], vary: list[str]
                 ) -> tuple[Scene, list[tuple[str, ...]], list[Scene]]:
    """The unvaried scene, every combination of the varied overrides and its scene, all validated
    before anything is solved (a SceneError names the first bad key)."""
    grid = parse_vary(vary)
    combinations = list(itertools.product(*[values for _, values in grid]))
    base = scene_from_dict(json.loads(json.dumps(data)))  # validates the unvaried scene first
    scenes = [scene_from_dict(apply_overrides(json.loads(json.dumps(data)), list(c)))
              for c in combinations]
    return base, combinations, scenes


def run_folder(settings: dict[str, str]) -> str:
    """The folder name of a kept run, e.g. ``die_angle=9_mesh_size=0.1``."""
    text = "_".join(f"{k.split('.')[-1]}={v}" for k, v in settings.items())
    return re.sub(r"[^A-Za-z0-9_=.,+-]+", "-", text)


def run_study(data: dict[str, Any], vary: list[str], out: Path,
              quantity: str | list[str] | None = None, comm: MPI.Comm = MPI.COMM_WORLD,
              keep_runs: bool = False) -> list[dict[str, Any]]:
    """Run every combination of the varied values (skipping those already in out/study.json) and
    write study.json, study.csv, study.md and the figures. ``quantity``: a summary key or a list
    of them (default: the process's); ``keep_runs``: each run writes its own folder
    out/runs/<settings> (run_scene's files), else only its numbers are kept."""
    base, combinations, scenes = study_scenes(data, vary)
    quantities = parse_quantities(quantity) or [QUANTITIES[base.process.kind]]
    keys = [override.split("=", 1)[0] for override in combinations[0]]  # the varied keys, in order
    if comm.rank == 0:
        out.mkdir(parents=True, exist_ok=True)
    store = out / "study.json"
    done = json.loads(store.read_text())["runs"] if comm.rank == 0 and store.exists() else []
    done = comm.bcast(done, root=0)
    rows = {_settings_key(r["settings"]): r for r in done}
    start = time.perf_counter()
    for index, (combination, scene) in enumerate(zip(combinations, scenes, strict=True), start=1):
        settings = dict(override.split("=", 1) for override in combination)
        key = _settings_key(settings)
        if key not in rows:
            row = {"settings": settings}
            if keep_runs:
                row["output"] = f"runs/{run_folder(settings)}"
                summary = run_scene(scene, out / row["output"], comm=comm,
                                    title=run_folder(settings), overwrite=True)
            else:
                summary = solve_scene(scene, comm=comm)[2]
            missing = [q for q in quantities if not isinstance(summary.get(q), (int, float))]
            if missing:
                known = ", ".join(k for k, v in summary.items() if isinstance(v, float))
                raise SceneError("--quantity", f"{missing[0]} is not a number of this run's "
                                 f"summary (known: {known})")
            rows[key] = {**row, **{k: v for k, v in summary.items() if k != "scene"}}
            if comm.rank == 0:
                _write_json(store, {"quantities": quantities, "runs": list(rows.values())})
        elapsed = time.perf_counter() - start
        if comm.rank == 0:
            numbers = ", ".join(f"{q} {value(rows[key], q):.5g}" for q in quantities)
            left = elapsed / index * (len(combinations) - index)
            log.info("run %d of %d (%s): %s; %.0f s elapsed, about %.0f s left", index,
                     len(combinations), run_folder(settings), numbers, elapsed, left)
    ordered = [rows[_settings_key(dict(o.split("=", 1) for o in c))] for c in combinations]
    for row, scene in zip(ordered, scenes, strict=True):
        row["exact"] = {q: exact_value(scene, q) for q in quantities}
    references(ordered, quantities)
    design = any(is_design_key(k) for k in keys)
    optima = find_optima(ordered, quantities, keys) if design else []
    if comm.rank == 0:
        from .study_figures import pareto_plot, quantity_plots

        _write_json(store, {"kind": "design" if design else "speed-accuracy",
                            "quantities": quantities, "varied": keys, "optima": optima,
                            "runs": ordered})
        _write_csv(out / "study.csv", ordered, quantities, keys)
        with_reference = [q for q in quantities if has_reference(ordered, q)]
        if with_reference:
            pareto_plot(out / "pareto.png", ordered, with_reference, keys)
        if design:
            quantity_plots(out, ordered, quantities, keys, optima, base.units,
                           base.geometry.whole_forces)
        (out / "study.md").write_text(report(ordered, quantities, optima, base.units,
                                             base.geometry.whole_forces) + "\n")
    return ordered


def _write_json(path: Path, document: dict[str, Any]) -> None:
    """Valid JSON: non-finite numbers as null."""
    path.write_text(json.dumps(json_safe(document), indent=1, allow_nan=False) + "\n")


def interior_minimum(xs: list[float], ys: list[float]
                     ) -> tuple[float, float, list[tuple[float, float]]] | None:
    """Location and value of the vertex of the parabola through the least of ``ys`` and its two
    neighbours (``xs`` increasing): with divided differences f[x0,x1], f[x0,x1,x2] = a, the parabola
    y1 + f[x1,x2](x - x1) + a (x - x1)(x - x2) has its vertex where its slope is zero. None when the
    least value is at either end of the grid (no interior minimum) or the three points are not
    convex; else (location, value, the three points)."""
    finite = [(x, y) for x, y in zip(xs, ys, strict=True) if math.isfinite(y)]
    if len(finite) < 3:
        return None
    i = min(range(len(finite)), key=lambda j: finite[j][1])
    if i in (0, len(finite) - 1):
        return None
    (x0, y0), (x1, y1), (x2, y2) = finite[i - 1:i + 2]
    right = (y2 - y1) / (x2 - x1)
    a = (right - (y1 - y0) / (x1 - x0)) / (x2 - x0)
    if a <= 0:
        return None
    # d/dx [y1 + right (x - x1) + a (x - x1)(x - x2)] = right + a (2x - x1 - x2) = 0
    location = 0.5 * (x1 + x2) - right / (2 * a)
    least = y1 + right * (location - x1) + a * (location - x1) * (location - x2)
    return location, least, finite[i - 1:i + 2]


def positions(rows: list[dict[str, Any]], parameter: str) -> dict[str, float]:
    """Where each value of ``parameter`` sits on the plot's axis: the number itself, or for values
    that are not all numbers (e.g. friction.law) their index in the order of the grid."""
    values = list(dict.fromkeys(row["settings"][parameter] for row in rows))
    if all(numeric(v) for v in values):
        return {v: float(v) for v in values}
    return {v: float(i) for i, v in enumerate(values)}


def numeric(text: str) -> bool:
    """Whether a --vary value is a number."""
    try:
        float(text)
    except ValueError:
        return False
    return True


def series(rows: list[dict[str, Any]], quantity: str, keys: list[str]
           ) -> list[tuple[str, list[float], list[float], str]]:
    """The lines of a design study's plot of ``quantity`` against its first design key, sorted
    along it: (label of the other keys' setting, parameter values, converged values, kind) with
    kind "runs"; where the rows have a reference also its line per setting of the other keys but
    the mesh size (kind "reference: <kind>")."""
    parameter = next(k for k in keys if is_design_key(k))
    others = [k for k in keys if k != parameter]
    where = positions(rows, parameter)
    lines = []
    for skip, kind in (((), "runs"), (MESH_KEYS, "reference")):
        grouped: dict[str, list[tuple[float, float, str]]] = {}
        for row in rows:
            x = where[row["settings"][parameter]]
            if kind == "runs":
                y = value(row, quantity) if row["converged"] else math.nan
                label_of = ""
            else:
                found = row["reference"].get(quantity, {})
                y = math.nan if found.get("value") is None else found["value"]
                label_of = found.get("kind", "none")
            if not math.isfinite(y):
                continue
            label = ", ".join(f"{k.split('.')[-1]} = {row['settings'][k]}"
                              for k in others if k not in skip)
            grouped.setdefault(label, []).append((x, y, label_of))
        for label, points in grouped.items():
            points = sorted(set(points))
            if kind == "reference" and len(points) < 2:
                continue
            lines.append((label, [p[0] for p in points], [p[1] for p in points],
                          "runs" if kind == "runs" else f"reference: {points[0][2]}"))
    return lines


def find_optima(rows: list[dict[str, Any]], quantities: list[str], keys: list[str]
                ) -> list[dict[str, Any]]:
    """For every quantity and line of ``series``: the interior minimum (location, value and the
    three points of the parabola; None each where there is none, and for a parameter whose values
    are not numbers)."""
    parameter = next(k for k in keys if is_design_key(k))
    numbers = all(numeric(row["settings"][parameter]) for row in rows)
    found = []
    for quantity in quantities:
        for label, xs, ys, kind in series(rows, quantity, keys):
            minimum = interior_minimum(xs, ys) if numbers else None
            found.append({"quantity": quantity, "parameter": parameter, "others": label,
                          "line": kind, "location": minimum[0] if minimum else None,
                          "value": minimum[1] if minimum else None,
                          "through": minimum[2] if minimum else None})
    return found


def cheapest(rows: list[dict[str, Any]], quantities: list[str],
             levels: tuple[float, ...] = ERROR_LEVELS) -> list[dict[str, Any]]:
    """For each setting of the design keys and each error level, the converged run of least wall
    time whose relative error of every quantity with a reference is within it (None where no run
    reaches the level; one entry of level None for a design point without any reference).
    ``error`` is that run's largest relative error."""
    measured = [q for q in quantities if has_reference(rows, q)]
    design = [k for k in rows[0]["settings"] if is_design_key(k)] if rows else []
    groups: dict[str, list[dict[str, Any]]] = {}
    for row in rows:
        groups.setdefault(json.dumps([row["settings"][k] for k in design]), []).append(row)
    found = []
    for point, group in groups.items():
        errors = [(max(relative_error(r, q) for q in measured), r)
                  for r in group if r.get("converged")]
        design_point = dict(zip(design, json.loads(point), strict=True))
        if not any(math.isfinite(e) for e, _ in errors):
            found.append({"design": design_point, "level": None, "error": math.nan, "run": None})
            continue
        for level in levels:
            within = [(e, r) for e, r in errors if math.isfinite(e) and e <= level]
            best = min(within, key=lambda item: item[1]["wall_time_s"]) if within \
                else (math.nan, None)
            found.append({"design": design_point, "level": level, "error": best[0],
                          "run": best[1]})
    return found


def _unit_label(units: Units, name: str, whole_forces: bool) -> str:
    unit = units.label(units.dimension(name, whole_forces))
    return f"{name} [{unit}]" if unit else name


def report(rows: list[dict[str, Any]], quantities: list[str],
           optima: list[dict[str, Any]] | None = None, units: Units | None = None,
           whole_forces: bool = False) -> str:
    """Markdown: every run (a design study's in parameter order, a speed-accuracy study's by wall
    time) with its quantities, their errors and references where there are any, whether it
    converged and its cost; a design study's interior optima; the cheapest converged setting per
    error level (per design point) where a reference exists."""
    units = units or Units()
    keys = list(rows[0]["settings"]) if rows else []
    design = any(is_design_key(k) for k in keys)
    measured = [q for q in quantities if has_reference(rows, q)]
    header = [*keys]
    for q in quantities:
        header += [_unit_label(units, q, whole_forces)]
        header += ["error", "reference"] if q in measured else []
    header += ["converged", "wall s", "linear solves", "dofs"]
    lines = []
    for r in rows if design else sorted(rows, key=lambda r: r["wall_time_s"]):
        line = [str(r["settings"][k]) for k in keys]
        for q in quantities:
            line.append(f"{value(r, q):.5g}")
            if q in measured:
                error = relative_error(r, q)
                line += [f"{100 * error:.2f}%", r["reference"][q]["kind"]] if math.isfinite(error) \
                    else ["-", "none"]
        lines.append([*line, "yes" if r["converged"] else "no", f"{r['wall_time_s']:.2f}",
                      r["linear_solves"], r["dofs"]])
    parts = [markdown_table(None, header, lines)]
    if design:
        parts.append(_optima_table(optima or [], units, whole_forces))
    if measured:
        parts.append(_cheapest_table(rows, quantities, keys))
    elif not design:
        parts.append("No reference: errors need an exact value or at least three mesh sizes "
                     "(discretisation.mesh_size or mesh_size_relative, halved each time).")
    return "\n\n".join(p for p in parts if p)


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


def _write_csv(path: Path, rows: list[dict[str, Any]], quantities: list[str],
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
    tail = ["converged", "wall_time_s", "linear_solves", "dofs"]
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
            writer.writerow(line + [row.get(c) for c in tail])

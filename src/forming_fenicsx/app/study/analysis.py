"""A study's analysis: exact or Richardson references per design point, relative errors, the
lines of a design study and their interior optima, the cheapest setting per error level."""
from __future__ import annotations
import itertools
import json
import math
from typing import Any
from forming_fenicsx.core.numbers import is_number
from forming_fenicsx.core.richardson import MIN_ORDER, richardson


QUANTITIES = {"extrusion": "ram_pressure", "drawing": "mean_die_pressure", "rolling": "roll_force"}


NUMERICAL_SECTIONS = ("discretisation", "solver", "penalty", "output")


MESH_KEYS = ("discretisation.mesh_size", "discretisation.mesh_size_relative")  # absolute, relative


ERROR_LEVELS = (0.10, 0.03, 0.01)


def is_design_key(key: str) -> bool:
    """A physical key (process, geometry, material, friction), not a numerical one."""
    return key.split(".")[0] not in NUMERICAL_SECTIONS


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


def settings_key(settings: dict[str, str], skip: tuple[str, ...] = ()) -> str:
    return json.dumps({k: v for k, v in settings.items() if k not in skip}, sort_keys=True)


def mesh_size(settings: dict[str, str]) -> float:
    """The varied mesh size (absolute or relative; inf when the mesh is not varied)."""
    return next((float(settings[k]) for k in MESH_KEYS if k in settings), math.inf)


def references(rows: list[dict[str, Any]], quantities: list[str]) -> None:
    """Set every row's ``reference``: for each quantity its value, kind (exact, Richardson from the
    three finest mesh sizes of the same other settings when their observed order is at least
    core.richardson.MIN_ORDER, or none) and relative error (in place; the exact values are the
    rows' ``exact``)."""
    groups: dict[str, list[dict[str, Any]]] = {}
    for row in rows:
        groups.setdefault(settings_key(row["settings"], MESH_KEYS), []).append(row)
        row["reference"] = {}
    for quantity, group in itertools.product(quantities, groups.values()):
        ranked = sorted((r for r in group if r["converged"] and math.isfinite(value(r, quantity))),
                        key=lambda r: -mesh_size(r["settings"]))
        limit, order = richardson([mesh_size(r["settings"]) for r in ranked],
                                  [value(r, quantity) for r in ranked]) if len(ranked) >= 3 \
            else (math.nan, math.nan)
        limit = limit if order >= MIN_ORDER else math.nan
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
    if all(is_number(v) for v in values):
        return {v: float(v) for v in values}
    return {v: float(i) for i, v in enumerate(values)}


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
    numbers = all(is_number(row["settings"][parameter]) for row in rows)
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

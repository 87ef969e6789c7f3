"""`forming study`: a grid of runs of one scene over varied keys, each with its error and its cost.

The error of each run's quantity (ram pressure for extrusion, q_av for drawing, or --quantity) is taken
against the exact value where one is known (Hill's ram pressure for frictionless Example 1 geometry
at reduction 1/2), otherwise against a Richardson extrapolation from the three finest mesh sizes of
the same other settings; `reference_kind` says which. A study stopped and started again skips the runs
its study.json already holds.
"""
from __future__ import annotations

import itertools
import json
import logging
import math
import time
import tomllib
from pathlib import Path
from typing import Any

from mpi4py import MPI

from .errors import SceneError
from .report import markdown_table, richardson
from .run import solve_scene
from .scene import Scene, apply_overrides, parse_override, read_scene_data, scene_from_dict

log = logging.getLogger(__name__)
QUANTITIES = {"extrusion": "ram_pressure", "drawing": "mean_die_pressure"}


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


def load_study(path: str | Path, overrides: list[str] | None = None) -> tuple[dict[str, Any], list[str], str | None]:
    """A study file: a ``[study]`` table with ``scene`` (relative to the file), ``vary`` (a table of
    key = [values]), optional ``set`` (a list of overrides) and ``quantity``. Returns the scene
    document (with ``set`` and then ``overrides`` applied), the --vary strings and the quantity."""
    path = Path(path)
    try:
        table = tomllib.loads(path.read_text()).get("study")
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise SceneError(str(path), f"not valid TOML: {exc}") from None
    if not isinstance(table, dict):
        raise SceneError("study", f"{path} has no [study] table")
    unknown = set(table) - {"scene", "vary", "set", "quantity"}
    if unknown:
        raise SceneError(f"study.{sorted(unknown)[0]}", "unknown key (known: scene, vary, set, quantity)")
    if not isinstance(table.get("scene"), str):
        raise SceneError("study.scene", "must name the scene file (relative to the study file)")
    vary, settings = table.get("vary"), table.get("set", [])
    if not isinstance(vary, dict) or not vary or not all(isinstance(v, list) and v for v in vary.values()):
        raise SceneError("study.vary", "must be a table of section.key = [value, ...]")
    if not (isinstance(settings, list) and all(isinstance(o, str) for o in settings)):
        raise SceneError("study.set", "must be a list of \"section.key=value\" strings")
    quantity = table.get("quantity")
    if quantity is not None and not isinstance(quantity, str):
        raise SceneError("study.quantity", "must be a summary key")
    data = read_scene_data(path.parent / table["scene"], [*settings, *(overrides or [])])
    texts = [f"{key}={','.join(_toml_value(v) for v in values)}" for key, values in vary.items()]
    return data, texts, quantity


def _toml_value(value: Any) -> str:
    return str(value).lower() if isinstance(value, bool) else str(value)


def exact_value(scene, quantity: str) -> float | None:
    """The exact value of ``quantity`` where a slip-line field is exact (verification.md):
    - frictionless square-die extrusion at reduction 1/2: Hill's ram pressure (1 + pi/2) k;
    - frictionless drawing without back tension at r = 2 sin(a)/(1 + 2 sin(a)) for the die semi-angle
      a: one triangle and a centred fan, q = 2k(1 + a)(1 - r), drawing stress 2k(1 + a) r.
    Both are plane-strain fields: a round bar (symmetry = "axisymmetric") has none."""
    geometry, process = scene.geometry, scene.process
    rough = scene.friction.mu != 0 or scene.friction.m != 0
    if rough or process.applied_force is not None or geometry.mesh_file is not None or geometry.axisymmetric:
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


def references(rows: list[dict[str, Any]], quantity: str) -> None:
    """Add reference, reference_kind and relative_error to every row (in place)."""
    groups: dict[str, list[dict[str, Any]]] = {}
    for row in rows:
        others = {k: v for k, v in row["settings"].items() if k != "discretisation.mesh_size"}
        groups.setdefault(json.dumps(others, sort_keys=True), []).append(row)
    for group in groups.values():
        ranked = sorted((r for r in group if r["converged"]),
                        key=lambda r: -float(r["settings"].get("discretisation.mesh_size", math.inf)))
        limit = richardson([r[quantity] for r in ranked])[0] if len(ranked) >= 3 else math.nan
        for row in group:
            if row.get("exact") is not None:
                row["reference"], row["reference_kind"] = row["exact"], "exact"
            elif math.isfinite(limit):
                row["reference"], row["reference_kind"] = limit, "richardson (three finest mesh sizes)"
            else:
                row["reference"], row["reference_kind"] = math.nan, "none"
            row["relative_error"] = abs(row[quantity] / row["reference"] - 1) if math.isfinite(row["reference"]) \
                else math.nan


def study_scenes(data: dict[str, Any], vary: list[str]) -> tuple[Scene, list[tuple[str, ...]], list[Scene]]:
    """The unvaried scene, every combination of the varied overrides and its scene, all validated before
    anything is solved (a SceneError names the first bad key)."""
    grid = parse_vary(vary)
    combinations = list(itertools.product(*[values for _, values in grid]))
    base = scene_from_dict(json.loads(json.dumps(data)))  # validates the unvaried scene first
    scenes = [scene_from_dict(apply_overrides(json.loads(json.dumps(data)), list(c))) for c in combinations]
    return base, combinations, scenes


def run_study(data: dict[str, Any], vary: list[str], out: Path, quantity: str | None = None,
              comm: MPI.Comm = MPI.COMM_WORLD) -> list[dict[str, Any]]:
    """Run every combination of the varied values (skipping those already in out/study.json)."""
    base, combinations, scenes = study_scenes(data, vary)
    quantity = quantity or QUANTITIES[base.process.kind]
    if comm.rank == 0:
        out.mkdir(parents=True, exist_ok=True)
    store = out / "study.json"
    done = json.loads(store.read_text())["runs"] if comm.rank == 0 and store.exists() else []
    done = comm.bcast(done, root=0)
    rows = {json.dumps(r["settings"], sort_keys=True): r for r in done}
    start = time.perf_counter()
    for index, (combination, scene) in enumerate(zip(combinations, scenes, strict=True), start=1):
        settings = dict(override.split("=", 1) for override in combination)
        key = json.dumps(settings, sort_keys=True)
        if key not in rows:
            summary = solve_scene(scene, comm=comm)[2]
            rows[key] = {"settings": settings, "exact": exact_value(scene, quantity),
                         **{k: v for k, v in summary.items() if k != "scene"}}
            if comm.rank == 0:
                store.write_text(json.dumps({"quantity": quantity, "runs": list(rows.values())}, indent=1))
        elapsed = time.perf_counter() - start
        if comm.rank == 0:
            log.info("run %d of %d done, %.0f s elapsed, about %.0f s left", index, len(combinations), elapsed,
                     elapsed / index * (len(combinations) - index))
    ordered = [rows[json.dumps(dict(o.split("=", 1) for o in c), sort_keys=True)] for c in combinations]
    references(ordered, quantity)
    if comm.rank == 0:
        store.write_text(json.dumps({"quantity": quantity, "runs": ordered}, indent=1, default=str))
        keys = [override.split("=", 1)[0] for override in combinations[0]]  # the varied keys, in order
        _write_csv(out / "study.csv", ordered, quantity, keys)
        _pareto_plot(out / "pareto.png", ordered, quantity, keys)
        (out / "study.md").write_text(report(ordered, quantity) + "\n")
    return ordered


ERROR_LEVELS = (0.10, 0.03, 0.01)


def cheapest(rows: list[dict[str, Any]], levels: tuple[float, ...] = ERROR_LEVELS) -> list[dict[str, Any]]:
    """For each error level, the converged run of least wall time whose relative error is within it
    (None where no run reaches the level)."""
    found = []
    for level in levels:
        within = [r for r in rows if r.get("converged") and math.isfinite(r.get("relative_error", math.nan))
                  and r["relative_error"] <= level]
        found.append({"level": level, "run": min(within, key=lambda r: r["wall_time_s"]) if within else None})
    return found


def report(rows: list[dict[str, Any]], quantity: str) -> str:
    """Markdown: every run sorted by wall time (with whether it converged), then the cheapest converged
    setting for each error level."""
    keys = list(rows[0]["settings"]) if rows else []
    runs = markdown_table(None, [*keys, quantity, "error", "reference", "converged", "wall s", "linear solves",
                                 "dofs"],
                          [[*(str(r["settings"][k]) for k in keys), f"{r[quantity]:.5g}",
                            f"{100 * r['relative_error']:.2f}%", r["reference_kind"], "yes" if r["converged"] else "no",
                            f"{r['wall_time_s']:.2f}", r["linear_solves"], r["dofs"]]
                           for r in sorted(rows, key=lambda r: r["wall_time_s"])])
    best = []
    for entry in cheapest(rows):
        r = entry["run"]
        level = f"{100 * entry['level']:g} %"
        if r is None:
            best.append([level, "none reaches it", "", "", "", ""])
        else:
            best.append([level, ", ".join(f"{k.split('.')[-1]} = {v}" for k, v in r["settings"].items()),
                         f"{100 * r['relative_error']:.2f}%", f"{r['wall_time_s']:.2f}", r["linear_solves"], r["dofs"]])
    return runs + "\n\n" + markdown_table(None, ["error within", "cheapest setting", "error", "wall s",
                                                 "linear solves", "dofs"], best)


def _write_csv(path: Path, rows: list[dict[str, Any]], quantity: str, keys: list[str]) -> None:
    import csv

    columns = [*keys, quantity, "reference", "reference_kind", "relative_error", "converged", "wall_time_s",
               "linear_solves", "dofs"]
    with path.open("w", newline="") as stream:
        writer = csv.writer(stream)
        writer.writerow(columns)
        for row in rows:
            writer.writerow([row["settings"].get(k) for k in keys] + [row.get(c) for c in columns[len(keys):]])


def _pareto_plot(path: Path, rows: list[dict[str, Any]], quantity: str, keys: list[str]) -> None:
    """Wall time against relative error, log-log, one marker per setting of the varied keys but the mesh."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(9, 5))
    series: dict[str, list[tuple[float, float]]] = {}
    others = [k for k in keys if k != "discretisation.mesh_size"]
    for row in rows:
        label = ", ".join(str(row["settings"][k]) for k in others) or quantity
        if math.isfinite(row["relative_error"]) and row["relative_error"] > 0:
            series.setdefault(label, []).append((row["wall_time_s"], row["relative_error"]))
    for marker, (label, points) in zip(itertools.cycle("osD^v<>p*"), series.items()):
        ax.loglog(*zip(*sorted(points), strict=True), marker=marker, label=label)
    ax.set_xlabel("wall time [s]")
    ax.set_ylabel(f"relative error of {quantity}")
    ax.grid(True, which="both", alpha=0.3)
    if series:
        ax.legend(fontsize=8, title=", ".join(k.split(".")[-1] for k in others) or None, title_fontsize=8,
                  loc="upper left", bbox_to_anchor=(1.02, 1.0))
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)

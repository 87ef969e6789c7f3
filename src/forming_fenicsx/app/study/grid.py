"""`forming study`'s grid: the runs of one scene over the varied keys (a study file or --vary),
each run's quantities and cost in study.json, resumed where it stopped."""
from __future__ import annotations
import itertools
import json
import logging
import re
import time
import tomllib
from pathlib import Path
from typing import Any
from mpi4py import MPI
from forming_fenicsx.core.errors import SceneError
from forming_fenicsx.io.output import json_safe
from forming_fenicsx.app.run import run_scene, solve_scene
from forming_fenicsx.config.loader import (apply_overrides, parse_override, read_scene_data,
                                           scene_from_dict)
from forming_fenicsx.config.scene import Scene
from forming_fenicsx.app.study.analysis import (QUANTITIES, settings_key, exact_value, find_optima,
                                                has_reference, is_design_key, references, value)
from forming_fenicsx.app.study.report import write_csv, report


log = logging.getLogger(__name__)


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
    rows = {settings_key(r["settings"]): r for r in done}
    start = time.perf_counter()
    for index, (combination, scene) in enumerate(zip(combinations, scenes, strict=True), start=1):
        settings = dict(override.split("=", 1) for override in combination)
        key = settings_key(settings)
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
    ordered = [rows[settings_key(dict(o.split("=", 1) for o in c))] for c in combinations]
    for row, scene in zip(ordered, scenes, strict=True):
        row["exact"] = {q: exact_value(scene, q) for q in quantities}
    references(ordered, quantities)
    design = any(is_design_key(k) for k in keys)
    optima = find_optima(ordered, quantities, keys) if design else []
    if comm.rank == 0:
        from forming_fenicsx.app.study.figures import pareto_plot, quantity_plots

        _write_json(store, {"kind": "design" if design else "speed-accuracy",
                            "quantities": quantities, "varied": keys, "optima": optima,
                            "runs": ordered})
        write_csv(out / "study.csv", ordered, quantities, keys)
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

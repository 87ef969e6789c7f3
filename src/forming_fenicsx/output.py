"""Files of a run: summary.json, history.csv and fields.xdmf (with its .h5)."""
from __future__ import annotations

import csv
import json
import math
from pathlib import Path
from typing import Any

from dolfinx.io import XDMFFile

from .solvers import IterationRecord


def _json_safe(value: Any) -> Any:
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if isinstance(value, dict):
        return {k: _json_safe(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_json_safe(v) for v in value]
    return value


def write_summary(path: Path, summary: dict[str, Any]) -> None:
    """summary.json; non-finite numbers are written as null."""
    path.write_text(json.dumps(_json_safe(summary), indent=2) + "\n")


def write_history(path: Path, history: list[IterationRecord]) -> None:
    """history.csv: a row per linear solve."""
    with path.open("w", newline="") as stream:
        writer = csv.writer(stream)
        writer.writerow(["outer", "inner", "relative_increment", "elapsed_s"])
        for record in history:
            writer.writerow([record.outer, record.inner, f"{record.increment:.6e}", f"{record.elapsed:.4f}"])


def write_fields(path: Path, mesh, fields) -> None:
    """fields.xdmf: the mesh and each field once, under its fixed name (collective)."""
    with XDMFFile(mesh.comm, str(path), "w") as xdmf:
        xdmf.write_mesh(mesh)
        for field in fields:
            xdmf.write_function(field)


def write_die_profile(path: Path, profile: dict) -> None:
    """die.csv: a row per node of Gamma3, ordered along the die (s from where the workpiece meets it)."""
    names = list(profile)
    with path.open("w", newline="") as stream:
        writer = csv.writer(stream)
        writer.writerow(names)
        for row in zip(*(profile[name] for name in names), strict=True):
            writer.writerow([f"{value:.8g}" for value in row])

"""A pass schedule: one scene run as consecutive passes, each from the strain profile across the
product that the pass before wrote (exit_strain.csv, read as material.initial_strain_file)."""
from __future__ import annotations

from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

from forming_fenicsx.app.run import run_scene
from forming_fenicsx.config.loader import load_scene


def run_passes(scene: Path, sizes: Sequence[float], size_name: str, out: Path,
               overrides: list[str] | None = None,
               load: Callable[..., Any] = load_scene) -> list[dict]:
    """Run ``scene`` from sizes[0] to sizes[1], sizes[1] to sizes[2], ... (geometry.entry_ and
    exit_``size_name``: "thickness" or "diameter") into out/pass1, out/pass2, ...; returns their
    summaries. ``load`` reads a scene with its overrides (load_scene)."""
    summaries, out = [], Path(out).resolve()  # the next pass reads the CSV from its scene's folder
    for number, (entry, exit_) in enumerate(zip(sizes, sizes[1:]), start=1):
        settings = [f"geometry.entry_{size_name}={entry}", f"geometry.exit_{size_name}={exit_}",
                    *(overrides or [])]
        if summaries:
            previous = out / f"pass{number - 1}" / "exit_strain.csv"
            settings.append(f"material.initial_strain_file=\"{previous}\"")
        summaries.append(run_scene(load(scene, settings), out / f"pass{number}",
                                   title=f"pass {number}", overwrite=True))
    return summaries

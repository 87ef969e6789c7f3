"""A three-pass copper wire drawing schedule, 2.0 -> 1.8 -> 1.62 -> 1.46 mm (19 % reduction of area
each), annealed copper hardening along the streamlines (demos/copper_wire_pass.toml): each pass
starts from the strain profile across the wire that the pass before wrote (exit_strain.csv).
Prints each pass's drawing stress, mean exit strain, redundant-work factor, the product's flow
stress and the drawing stress over it (the drawn wire yields at 1).

Run: mpirun -n 2 .venv/bin/python demos/copper_wire_schedule.py [--out results/copper_schedule]
The same passes of another scene (the steel wire of docs/hardening.md):
     demos/copper_wire_schedule.py --scene demos/steel_wire_pass.toml --out results/steel_schedule
"""
from __future__ import annotations

import argparse
import logging
from pathlib import Path

from mpi4py import MPI

from forming_fenicsx.app.schedule import run_passes
from forming_fenicsx.config.loader import load_scene
from forming_fenicsx.core.report import markdown_table

SCENE = Path(__file__).with_name("copper_wire_pass.toml")
DIAMETERS = (2.0, 1.8, 1.62, 1.46)
COLUMNS = ("drawing_stress", "mean_entry_strain", "mean_exit_strain", "redundant_work_factor",
           "product_flow_stress", "product_yield_ratio", "linear_solves")


def run_schedule(out: Path, overrides: list[str] | None = None, scene: Path = SCENE) -> list[dict]:
    """Run the passes of ``scene`` in order into out/pass1, out/pass2, ...; returns their
    summaries."""
    return run_passes(scene, DIAMETERS, "diameter", out, overrides, load=load_scene)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default="results/copper_schedule")
    parser.add_argument("--scene", type=Path, default=SCENE,
                        help="the pass (its diameters replaced)")
    args = parser.parse_args()
    logging.basicConfig(level=logging.WARNING)
    summaries = run_schedule(Path(args.out), scene=args.scene)
    if MPI.COMM_WORLD.rank == 0:
        rows = [[f"{d0} -> {d1} mm", *(f"{s[c]:.4g}" for c in COLUMNS)]
                for d0, d1, s in zip(DIAMETERS, DIAMETERS[1:], summaries)]
        print(markdown_table(None, ["pass", *COLUMNS], rows))


if __name__ == "__main__":
    main()

"""A three-pass cold rolling schedule of annealed aluminium strip, 3.0 -> 2.4 -> 1.9 -> 1.5 mm
(20, 21 and 21 % reduction), hardening along the streamlines (demos/aluminium_strip_pass.toml):
each pass starts from the strain profile across the strip that the pass before wrote
(exit_strain.csv). Prints each pass's roll force and torque (per roll, the 100 mm wide strip),
neutral angle, forward slip, mean exit strain and the product's flow stress.

Run: mpirun -n 2 .venv/bin/python demos/rolling_schedule.py [--out results/rolling_schedule]
"""
from __future__ import annotations

import argparse
import logging
from pathlib import Path

from mpi4py import MPI

from forming_fenicsx.app.schedule import run_passes
from forming_fenicsx.core.report import markdown_table

SCENE = Path(__file__).with_name("aluminium_strip_pass.toml")
THICKNESSES = (3.0, 2.4, 1.9, 1.5)
COLUMNS = ("roll_force", "roll_torque", "neutral_angle", "forward_slip", "mean_entry_strain",
           "mean_exit_strain", "product_flow_stress", "linear_solves")


def run_schedule(out: Path, overrides: list[str] | None = None) -> list[dict]:
    """Run the passes in order into out/pass1, out/pass2, ...; returns their summaries."""
    return run_passes(SCENE, THICKNESSES, "thickness", out, overrides)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default="results/rolling_schedule")
    args = parser.parse_args()
    logging.basicConfig(level=logging.WARNING)
    summaries = run_schedule(Path(args.out))
    if MPI.COMM_WORLD.rank == 0:
        rows = [[f"{h0} -> {h1} mm", *(f"{s[c]:.4g}" for c in COLUMNS)]
                for h0, h1, s in zip(THICKNESSES, THICKNESSES[1:], summaries)]
        print(markdown_table(None, ["pass", *COLUMNS], rows))


if __name__ == "__main__":
    main()

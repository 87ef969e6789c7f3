# # Example 2: plane-strain drawing through a 6 degree die, mu = 0, 0.2, 0.4
#
# Angelov (2014), section 4, Example 2: a strip 1.625 thick is drawn to 1.5 at velocity 1000 through
# a die of semi-angle 6 degrees; k = 100. The paper reports mean die pressures q_av = 243, 255, 273;
# the slip-line value for mu = 0 is q = 2.5 k = 250.
#
#     mpirun -n 2 python demos/example2_drawing.py
#
# writes results/example2_drawing*/ (summary.json, die.csv, die.png, fields.xdmf, figures).

import argparse
import math
import sys
from pathlib import Path

from mpi4py import MPI

from forming_fenicsx import load_scene
from forming_fenicsx.app.cli import configure_logging
from forming_fenicsx.app.run import run_scene

PAPER = {"example2_drawing": 243.0, "example2_drawing_mu02": 255.0, "example2_drawing_mu04": 273.0}

parser = argparse.ArgumentParser(description="Example 2 of Angelov (2014) for mu = 0, 0.2, 0.4")
parser.add_argument("--set", action="append", default=[], metavar="SECTION.KEY=VALUE")
args = parser.parse_args()
configure_logging(quiet=True, rank=MPI.COMM_WORLD.rank)

# ## Solve the three scenes
# Each scene is the paper's Example 2 with one friction coefficient; results go to results/<scene>.
rows, converged = [], True
for name, paper_q in PAPER.items():
    scene = load_scene(Path(__file__).with_name(f"{name}.toml"), args.set)
    summary = run_scene(scene, Path("results") / name, title=name, overwrite=True)
    converged &= summary["converged"]
    rows.append((scene.friction.mu, summary, paper_q))

# ## Compare with the paper
# The drawing stress follows from q by the force balance F = q (h0 - h1)(1 + mu cot(alpha)).
if MPI.COMM_WORLD.rank == 0:
    cot = 1 / math.tan(math.radians(scene.geometry.die_angle))
    ratio = ((scene.geometry.entry_thickness - scene.geometry.exit_thickness)
             / scene.geometry.exit_thickness)
    print("| mu | q_av | paper q_av | drawing stress | from paper q | force balance "
          "| linear solves |")
    print("|---|---|---|---|---|---|---|")
    for mu, s, paper_q in rows:
        print(f"| {mu} | {s['mean_die_pressure']:.1f} | {paper_q:.0f} | "
              f"{s['drawing_stress']:.2f} | {paper_q * ratio * (1 + mu * cot):.2f} | "
              f"{s['force_balance_residual']:.1e} | {s['linear_solves']} |")
sys.exit(0 if converged else 3)

# # Example 1: plane-strain extrusion through a square die
#
# Angelov (2014), section 4, Example 1: a strip of thickness 10 is extruded to thickness 5 through a
# square die by a ram moving at u_N^0 = 1. The material follows the flow-stress law (4.5) with
# A = sqrt(3), so the shear yield stress is k ~ 1 and Hill's slip-line ram pressure is
# (1 + pi/2) k = 2.571 for a frictionless die.
#
# Run it on two ranks with
#
#     mpirun -n 2 python demos/example1_extrusion.py demos/example1_extrusion.toml
#
# and open `results/example1_extrusion/fields.xdmf` in ParaView.

import argparse
import math
import sys
from pathlib import Path

from mpi4py import MPI

from forming_fenicsx import SceneError, load_scene
from forming_fenicsx.app.cli import configure_logging
from forming_fenicsx.app.run import run_scene

HILL_RAM_PRESSURE = 1.0 + math.pi / 2.0  # slip-line solution, in units of k

parser = argparse.ArgumentParser(description=__doc__)
parser.add_argument("scene", nargs="?",
                    default=str(Path(__file__).with_name("example1_extrusion.toml")))
parser.add_argument("--out", help="output folder (default: results/<scene name>)")
parser.add_argument("--set", action="append", default=[], metavar="SECTION.KEY=VALUE")
args = parser.parse_args()

# Rank-0 logging of every secant iterate.
configure_logging(quiet=False, rank=MPI.COMM_WORLD.rank)

# ## The scene
# Everything about the run is in the TOML scene; `--set` overrides single values.
try:
    scene = load_scene(args.scene, args.set)
except SceneError as error:
    sys.exit(f"invalid scene: {error}")

# ## Solve and write results
# The mesh is built by gmsh on rank 0 and distributed; the secant-modulus iteration runs until the
# relative increment falls below delta; results go to summary.json, history.csv, fields.xdmf and
# PNGs.
out = Path(args.out) if args.out else Path("results") / Path(args.scene).stem
# a re-run replaces its results
summary = run_scene(scene, out, title=Path(args.scene).stem, overwrite=True)

# ## Compare with the slip-line solution
# The ram pressure is the consistent reaction on Gamma1 over the inlet half-height.
if MPI.COMM_WORLD.rank == 0:
    p = summary["ram_pressure"]
    print(f"mu = {scene.friction.mu}: ram pressure {p:.4f} "
          f"(Hill, frictionless: {HILL_RAM_PRESSURE:.4f}; "
          f"{100 * (p / HILL_RAM_PRESSURE - 1):+.2f}%), "
          f"p_av {summary['mean_hydrostatic_pressure']:.4f}, "
          f"force balance residual {summary['force_balance_residual']:.1e}, "
          f"{summary['linear_solves']} linear solves, converged: {summary['converged']}")
    print(f"results in {out}")
sys.exit(0 if summary["converged"] else 3)

# # Rigorous bounds on Example 2's frictionless die pressure (limit analysis)
#
#     python demos/example2_bounds.py [--sizes 0.05:0.2 0.025:0.1] [--sides 48]
#                                     [--out results/example2_bounds]
#
# The paper quotes a slip-line die pressure q = 2.5 k = 250 for its drawing example. This script
# brackets the die pressure of the rigid-perfectly plastic strip (k = A/sqrt(3), the limit
# alpha -> 0 of (4.5)) with the same geometry and boundary conditions as the finite element runs,
# mu = 0: a lower bound from an equilibrium stress field and an upper bound from an incompressible
# velocity field, both optimised by linear programming
# (`forming_fenicsx.verification.limit_analysis`). Each size pair is "smallest:largest" element
# size. It runs for the paper's reduction and for the reduction where Hill's slip-line field is
# exact (q = 182.74), a check of both bounds. Serial; docs/example2.md shows a run.

import argparse
import json
import logging
import math
from pathlib import Path

from forming_fenicsx import load_scene
from forming_fenicsx.verification.limit_analysis import lower_bound, upper_bound
from forming_fenicsx.core.report import markdown_table
from forming_fenicsx.app.study import exact_value

DEMOS = Path(__file__).parent
CASES = [("paper (quoted slip-line q = 250)", DEMOS / "example2_drawing.toml", 250.0),
         ("exact field", DEMOS / "example2_exact_field.toml", None)]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--sizes", nargs="+", default=["0.05:0.2", "0.025:0.1"],
                        help="element sizes smallest:largest, one bound pair per entry")
    parser.add_argument("--sides", type=int, default=48,
                        help="sides of the polygons replacing the yield circle")
    parser.add_argument("--cases", nargs="+", choices=["paper", "exact"],
                        default=["paper", "exact"])
    parser.add_argument("--out", type=Path, default=Path("results/example2_bounds"))
    args = parser.parse_args()
    logging.basicConfig(level=logging.INFO, format="%(message)s")

    rows = []
    for name, path, quoted in CASES:
        if name.split()[0] not in args.cases:
            continue
        scene = load_scene(path)
        k = scene.material.flow_stress([1.0])[0] / math.sqrt(3.0)   # as exact_value: A / sqrt(3)
        reference = exact_value(scene, "mean_die_pressure") if quoted is None else quoted
        for pair in args.sizes:
            size_min, size_max = (float(v) for v in pair.split(":"))
            low = lower_bound(scene.geometry, k, size_min, size_max, sides=args.sides)
            high = upper_bound(scene.geometry, k, size_min, size_max, sides=args.sides)
            rows.append([name, pair, low.triangles, low.die_pressure, high.die_pressure, reference,
                         low.drawing_stress, high.drawing_stress, low.seconds + high.seconds])
            logging.info("%s", rows[-1])
    header = ["case", "sizes", "triangles", "lower q", "upper q", "reference q",
              "lower drawing stress", "upper drawing stress", "seconds"]
    print(markdown_table(f"Bounds on the frictionless die pressure, k = {k:g}, "
                         f"{args.sides}-sided polygons", header, rows))
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "example2_bounds.json").write_text(
        json.dumps([dict(zip(header, row, strict=True)) for row in rows], indent=1))


if __name__ == "__main__":
    main()

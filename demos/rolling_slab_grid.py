# # Flat rolling by slab theory over the grid of issue 39
#
#     python demos/rolling_slab_grid.py [--out results/rolling_slab]
#
# The von Karman (Orowan) slab solution for rigid rolls (forming_fenicsx.physics.rolling_slab),
# dimensionless: exit thickness h1 = 1 and 2k = 1 (k the shear flow stress), no tensions. For R/h1
# from 10 to 200, reductions from 10 to 40 % and Coulomb mu from 0.05 to 0.3 (capped at k), and
# sticking friction: the mean roll pressure P/(2k L) over the projected contact length L, the
# torque per roll G/(2k L^2), the neutral angle over the bite angle and the forward slip. "slips"
# marks a friction below what steady rolling needs (no neutral point). The finite-element rolling
# model is to be compared with this table (docs/rolling_slab.md shows a run).

import argparse
import json
import math
from pathlib import Path

from forming_fenicsx.core.report import markdown_table
from forming_fenicsx.physics.rolling_slab import slab_rolling

RATIOS = (10.0, 25.0, 50.0, 100.0, 200.0)
REDUCTIONS = (0.1, 0.2, 0.3, 0.4)
FRICTIONS = (0.05, 0.1, 0.2, 0.3, "sticking")


def row(ratio: float, reduction: float, friction) -> dict:
    """One grid point's dimensionless slab numbers (h1 = 1, 2k = 1)."""
    entry = 1.0 / (1.0 - reduction)
    kind = "sticking" if friction == "sticking" else "coulomb"
    mu = 0.0 if friction == "sticking" else friction
    bite = math.degrees(math.acos(1 - (entry - 1.0) / (2 * ratio)))
    point = {"R/h1": ratio, "reduction": reduction, "friction": friction, "bite_angle_deg": bite}
    try:
        r = slab_rolling(ratio, entry, 1.0, 0.5, mu=mu, friction=kind)
    except ValueError:
        return {**point, "slips": True}
    length = r.contact_length
    return {**point, "slips": False, "mean_pressure": r.roll_force / length,
            "torque": r.torque / length**2, "neutral_over_bite": r.neutral_angle / r.bite_angle,
            "forward_slip": r.forward_slip}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--out", type=Path, default=Path("results/rolling_slab"))
    args = parser.parse_args()
    rows = [row(ratio, reduction, friction) for ratio in RATIOS for reduction in REDUCTIONS
            for friction in FRICTIONS]
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "slab.json").write_text(json.dumps(rows, indent=1))

    def cell(r: dict, key: str, fmt: str) -> str:
        return "slips" if r["slips"] else format(r[key], fmt)

    table = markdown_table("slab theory, h1 = 1, 2k = 1", [
        "R/h1", "reduction", "bite angle deg", "friction", "P/(2k L)", "G/(2k L^2)",
        "phi_n/alpha", "forward slip"],
        [[r["R/h1"], r["reduction"], f"{r['bite_angle_deg']:.3g}",
          r["friction"], cell(r, "mean_pressure", ".4f"), cell(r, "torque", ".4f"),
          cell(r, "neutral_over_bite", ".3f"), cell(r, "forward_slip", ".4f")] for r in rows])
    (args.out / "slab.md").write_text(table + "\n")
    print(table)


if __name__ == "__main__":
    main()

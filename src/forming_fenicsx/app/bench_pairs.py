"""Two cases timed against each other on a shared machine: each run in a process of its own
(``launch``, bench._launch), a first pair not counted (it compiles the forms), then pairs run back
to back, so that a load that comes or goes between rounds weighs on both."""
from __future__ import annotations

from typing import Any, Callable

Row = dict[str, Any]


def median_run(runs: list[Row]) -> Row:
    """The run of median wall time (the lower middle one of an even count), with every run's wall
    time: on a shared machine one run's time is a sample, not a measurement."""
    ordered = sorted(runs, key=lambda row: row["wall_time_s"])
    return {**ordered[(len(ordered) - 1) // 2],
            "wall_time_runs_s": [row["wall_time_s"] for row in runs]}


def timed_pair(first: Row, second: Row, ranks: int, repeat: int,
               launch: Callable[[Row, int], Row], first_warm: bool = False
               ) -> tuple[Row, Row, list[float]]:
    """The median runs of ``first`` and ``second`` over ``repeat`` pairs (after one pair not
    counted; only ``second`` not counted when ``first`` has run already, ``first_warm``) and the
    pairs' time ratios first/second, sorted."""
    if not first_warm:
        launch(first, ranks)
    launch(second, ranks)
    pairs = [(launch(first, ranks), launch(second, ranks)) for _ in range(repeat)]
    one, other = (median_run([pair[k] for pair in pairs]) for k in (0, 1))
    return one, other, sorted(a["wall_time_s"] / b["wall_time_s"] for a, b in pairs)


def pair_rows(name: str, first: Row, second: Row, ratios: list[float], labels: tuple[str, str],
              against: str) -> tuple[Row, Row]:
    """The two rows with their solves and time over ``second``'s (``*_vs_<against>``; the time
    the median of the pairs' ratios), printed as one line that names them by ``labels``."""
    rows = tuple({**row, f"time_vs_{against}": ratio, "time_ratio_runs": runs,
                  f"solves_vs_{against}": row["linear_solves"] / second["linear_solves"]}
                 for row, ratio, runs in ((first, ratios[(len(ratios) - 1) // 2], ratios),
                                          (second, 1.0, [1.0])))
    print(f"{name}: " + ", ".join(f"{row['linear_solves']} solves {row['wall_time_s']:.2f} s "
                                  f"{label}" for row, label in zip((first, second), labels))
          + ", time ratios " + ", ".join(f"{r:.2f}" for r in ratios), flush=True)
    return rows

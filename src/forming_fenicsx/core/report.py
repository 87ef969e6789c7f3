"""Helpers for measurement scripts: Richardson extrapolation and markdown tables."""
from __future__ import annotations

import math


def richardson(values: list[float]) -> tuple[float, float]:
    """Limit and observed order from the last three values of a sequence of halved mesh sizes.

    NaN when the differences do not shrink monotonically (no asymptotic range).
    """
    a, b, c = values[-3:]
    if (a - b) * (b - c) <= 0 or abs(b - c) >= abs(a - b):
        return math.nan, math.nan
    order = math.log2((a - b) / (b - c))
    return c - (b - c) / (2**order - 1), order


def markdown_table(title: str | None, header: list[str], rows: list[list]) -> str:
    """A markdown table under a ``### title`` heading (none for None); floats with five significant
    digits. Empty when there are no rows."""
    if not rows:
        return ""
    heading = [f"\n### {title}\n"] if title is not None else []
    lines = [*heading, "| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    for row in rows:
        lines.append("| " + " | ".join(f"{v:.5g}" if isinstance(v, float) else str(v) for v in row) + " |")
    return "\n".join(lines)

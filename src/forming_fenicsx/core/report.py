"""Markdown tables for the reports of measurement scripts, `forming bench` and `forming study`."""
from __future__ import annotations


def markdown_table(title: str | None, header: list[str], rows: list[list]) -> str:
    """A markdown table under a ``### title`` heading (none for None); floats with five significant
    digits. Empty when there are no rows."""
    if not rows:
        return ""
    heading = [f"\n### {title}\n"] if title is not None else []
    lines = [*heading, "| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    for row in rows:
        cells = (f"{v:.5g}" if isinstance(v, float) else str(v) for v in row)
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)

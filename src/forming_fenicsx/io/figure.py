"""What every figure of a run shares: matplotlib without a display, the heading above each plot
(the run's name and main settings and, for a run that did not converge, why), tick labels
without an offset, and saving."""
from __future__ import annotations

import re
import textwrap
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from forming_fenicsx.config.scene import Scene

FAILURE_COLOUR = "tab:red"


def pyplot() -> Any:
    """matplotlib.pyplot on the Agg backend (files only: ranks and CI have no display)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def not_converged(summary: dict[str, Any]) -> str | None:
    """"NOT CONVERGED: why" for a run that did not converge (summary["converged"] false: the
    iteration's reason, or when the iteration converged the first failed sanity check), cut at its
    first clause and to 90 characters; None for a run that converged."""
    if summary["converged"]:
        return None
    why = summary["failed_checks"][0] if summary["iteration_converged"] else summary["reason"]
    first = re.split(r" \(|: |; ", why, maxsplit=1)[0]
    return "NOT CONVERGED: " + textwrap.shorten(first, 90, placeholder=" ...")


def run_settings(scene: Scene) -> str:
    """The run's main settings for a figure title, numbers to 4 significant digits, e.g.
    "drawing, strip 2 -> 1.6 mm, die 10 deg, mu = 0.08, Q2 h = 0.0533 mm"; a two-angle or CSV
    die gives the angle of its chord (DieProfile.effective_angle)."""
    g, f, d = scene.geometry, scene.friction, scene.discretisation
    length = scene.units.label("length")
    unit = f" {length}" if length else ""
    shape = "round" if g.axisymmetric else "strip"
    if getattr(g, "die_angle", None) is None:
        die = f", {g.die} die"
    else:
        chord = g.die_profile_file is not None or g.second_angle is not None
        die = f", die {g.semi_angle:.4g} deg{' (chord)' if chord else ''}"
    friction = f"m = {f.m:.4g}" if f.law == "factor" else f"mu = {f.mu:.4g}"
    mesh = f"mesh {Path(g.mesh_file).name}" if g.mesh_file else f"h = {d.mesh_size:.3g}{unit}"
    return (f"{scene.process.kind}, {shape} {g.entry_thickness:.4g} -> {g.exit_thickness:.4g}"
            f"{unit}{die}, {friction}, {d.element} {mesh}")


@dataclass(frozen=True)
class Heading:
    """What each figure of a run says above its plot: the run's name and main settings and, for a
    run that did not converge, why (not_converged), so that its figures cannot pass for those of a
    converged run."""

    name: str
    settings: str
    failure: str | None = None

    @classmethod
    def of_run(cls, name: str, scene: Scene, summary: dict[str, Any]) -> Heading:
        return cls(name, run_settings(scene), not_converged(summary))

    def put(self, ax: Any, what: str) -> None:
        """Title the axes with the run and ``what`` they show; a failed run's title is red and led
        by its failure, and "NOT CONVERGED" is written across the axes."""
        lines = [f"{self.name}: {self.settings}", what]
        if self.failure is None:
            ax.set_title("\n".join(lines), fontsize=9)
            return
        ax.set_title("\n".join([self.failure, *lines]), fontsize=9, color=FAILURE_COLOUR)
        ax.text(0.5, 0.5, "NOT CONVERGED", transform=ax.transAxes, ha="center", va="center",
                fontsize=24, fontweight="bold", color=FAILURE_COLOUR, alpha=0.3, rotation=12,
                zorder=20)


def plain_ticks(ax: Any) -> None:
    """Tick labels without an offset ("+7.3e2" above an axis of temperatures): the values shown
    are in the axis label's unit (Units.shown keeps them readable)."""
    from matplotlib.ticker import ScalarFormatter

    for axis in (ax.xaxis, ax.yaxis):
        if axis.get_scale() == "linear":
            axis.set_major_formatter(ScalarFormatter(useOffset=False))


def save(fig: Any, path: Path) -> Path:
    """Save at 130 dpi cropped to what is drawn, and close."""
    fig.savefig(path, dpi=130, bbox_inches="tight")
    pyplot().close(fig)
    return path

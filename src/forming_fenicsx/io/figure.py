"""What every figure of a run shares: matplotlib without a display, the heading above each plot
(the run's name and main settings and, for a run that did not converge, why), tick labels
without an offset, and saving."""
from __future__ import annotations

import re
import textwrap
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

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
    die gives the angle of its chord (DieProfile.effective_angle); a 3D bar its height and width,
    "3D bar 4 x 6 -> 3.2 x 5 mm, die 8 deg (width 10.06 deg)"."""
    g, f, d = scene.geometry, scene.friction, scene.discretisation
    length = scene.units.label("length")
    unit = f" {length}" if length else ""
    sizes = f"{g.entry_thickness:.4g} -> {g.exit_thickness:.4g}"
    shape = "round" if g.round else "strip"
    if g.three_dimensional:
        shape = f"3D {'round' if g.round else 'bar'}"
        if not g.round:
            sizes = (f"{g.entry_thickness:.4g} x {g.entry_width:.4g} -> {g.exit_thickness:.4g} x "
                     f"{g.exit_width:.4g}")
    if scene.process.kind == "rolling":
        die = f", rolls R = {g.roll_radius:.4g}{unit}, bite {g.die_angle:.3g} deg"
    elif getattr(g, "die_angle", None) is None:
        die = f", {g.die} die"
    else:
        chord = g.die_profile_file is not None or g.second_angle is not None
        width = g.three_dimensional and not g.round
        die = (f", die {g.semi_angle:.4g} deg{' (chord)' if chord else ''}"
               f"{f' (width {g.width_angle:.4g} deg)' if width else ''}")
    friction = {"factor": f"m = {f.m:.4g}", "coulomb": f"mu = {f.mu:.4g}",
                "sticking": "sticking"}[f.law] + (" (sticking)" if f.law == "factor" and f.sticks
                                                  else "")
    mesh = f"mesh {Path(g.mesh_file).name}" if g.mesh_file else f"h = {d.mesh_size:.3g}{unit}"
    return (f"{scene.process.kind}, {shape} {sizes}{unit}{die}, {friction}, {d.element} "
            f"{mesh}")


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
        text, style = self._title(what)
        ax.set_title(text, **style)
        self.mark(ax)

    def put_above(self, fig: Any, axes: list[Any], what: str) -> tuple[float, float, float, float]:
        """The title of ``put`` above a figure of several panels, "NOT CONVERGED" across each;
        returns the rectangle (figure fractions) that leaves the title its lines, for
        fig.tight_layout(rect=...): tight_layout alone lays the top panels' titles over it."""
        text, style = self._title(what)
        fig.suptitle(text, **style)
        for ax in axes:
            self.mark(ax)
        lines = text.count("\n") + 1
        return (0.0, 0.0, 1.0, 1.0 - (0.17 * lines + 0.1) / fig.get_figheight())

    def _title(self, what: str) -> tuple[str, dict[str, Any]]:
        """The title's text and style: the run and its settings, ``what`` the figure shows, led by
        the failure in red for a failed run."""
        lines = [f"{self.name}: {self.settings}", what]
        if self.failure is None:
            return "\n".join(lines), {"fontsize": 9}
        return "\n".join([self.failure, *lines]), {"fontsize": 9, "color": FAILURE_COLOUR}

    def mark(self, ax: Any) -> None:
        """"NOT CONVERGED" across the axes of a run that did not converge (every panel of a
        figure whose heading is above one of them); nothing for a converged run."""
        if self.failure is None:
            return
        ax.text(0.5, 0.5, "NOT CONVERGED", transform=ax.transAxes, ha="center", va="center",
                fontsize=24, fontweight="bold", color=FAILURE_COLOUR, alpha=0.3, rotation=12,
                zorder=20)


def colour_range(values: list[np.ndarray]) -> tuple[float, float]:
    """The least and largest of the values, at least 1e-3 of their size apart (a constant field,
    e.g. no friction stress before the first solve, gets a readable colour bar rather than one
    1e-12 wide with an offset above it)."""
    low = min(float(np.nanmin(v)) for v in values)
    high = max(float(np.nanmax(v)) for v in values)
    return low, max(high, low + 1e-3 * max(abs(low), abs(high), 1.0))


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

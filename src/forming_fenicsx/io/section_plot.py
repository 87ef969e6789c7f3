"""exit_<quantity>.png of a 3D run: a quantity over the product's exit section (the hardness of a
hardening run's product), the model's quarter (or half) mirrored about the symmetry planes into the
whole section, seen along the flow: z across, y up, at 1:1."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from forming_fenicsx.core.units import Units, bracketed
from forming_fenicsx.io.figure import Heading, colour_range, plain_ticks, pyplot, save
from forming_fenicsx.post.facet_samples import FacetSamples

SECTION_MAP = "inferno"  # perceptually uniform


def write_section_plot(samples: FacetSamples, path: Path, heading: Heading, label: str,
                       dimension: str, units: Units, mirrored: tuple[bool, bool],
                       reference: tuple[str, float] | None = None) -> Path:
    """exit_<quantity>.png (rank 0): ``samples`` of the exit face (views3d.exit_face), mirrored
    about y = 0 and z = 0 as ``mirrored`` says (the model's symmetry planes Gamma6 and Gamma7),
    the symmetry planes dashed; the title gives the least and largest value and ``reference``
    (label, value: the entry strain plus the ideal strain). Triangles with a NaN value (a
    strain left out, views3d.strain_undershoot) are left blank."""
    from mpl_toolkits.axes_grid1 import make_axes_locatable

    points, triangles, values = samples.merged(lambda p: p[:, [2, 1]])
    shown, unit = units.shown(dimension, values[:, 0])
    low, high = colour_range([shown])
    fig, ax = pyplot().subplots(figsize=(8, 6))
    signs = [(sz, sy) for sz in ((1, -1) if mirrored[1] else (1,))
             for sy in ((1, -1) if mirrored[0] else (1,))]
    for sz, sy in signs:
        mapped = ax.tripcolor(sz * points[:, 0], sy * points[:, 1], triangles,
                              np.nan_to_num(shown), mask=np.isnan(shown)[triangles].any(axis=1),
                              shading="gouraud", cmap=SECTION_MAP, vmin=low, vmax=high)
    for on, line in zip(mirrored, (ax.axhline, ax.axvline), strict=True):
        if on:
            line(0.0, color="w", linestyle="--", linewidth=0.8)
    bar = make_axes_locatable(ax).append_axes("right", size="4%", pad=0.1)
    fig.colorbar(mapped, cax=bar, label=bracketed(label, unit))
    ax.set_aspect("equal")
    ax.set_xlabel(units.labelled("z", "length"))
    ax.set_ylabel(units.labelled("y", "length"))
    plain_ticks(ax)
    x = float(samples.points[..., 0].mean())
    length = units.label("length")
    levels = f"min {float(np.nanmin(shown)):.4g}, max {float(np.nanmax(shown)):.4g}"
    if reference is not None:
        levels += f"; {reference[0]} = {float(units.shown(dimension, reference[1])[0]):.4g}"
    heading.put(ax, f"{label} over the exit section x = {x:.4g}{' ' + length if length else ''}"
                    f"\n(the model mirrored about its symmetry planes, dashed); {levels}")
    fig.tight_layout()
    return save(fig, path)

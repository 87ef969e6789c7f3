"""die.png of a 3D run: the stresses over the die's faces, each face seen square-on at 1:1 (a
rectangular die's height faces in the (x, z) plane, its width faces in (x, y); a round die
unrolled into x and the arc length from the plane z = 0), with the die's edges: the outline of
each face (where it meets the other face, the die entry and exit, the symmetry planes) and the
crease where the cone meets the land."""
from __future__ import annotations

from pathlib import Path
from typing import NamedTuple

import numpy as np

from forming_fenicsx.config.scene import Scene
from forming_fenicsx.core.units import bracketed
from forming_fenicsx.io.figure import Heading, colour_range, plain_ticks, pyplot, save
from forming_fenicsx.post.facet_samples import FacetSamples

# each stress shown (die.py: die_stresses), its colour bar's label in two lines (in one a short
# row of panels let it run into the next row's label) and perceptually uniform colour map
SHOWN = {"contact_pressure": ("contact pressure\n-sigma_N", "viridis"),
         "friction_stress": ("friction stress\n|sigma_T|", "cividis")}


def unrolled(points: np.ndarray) -> np.ndarray:
    """A round die's points (N, 3) unrolled: x and the arc length r theta from the plane z = 0
    (theta = atan2(z, y))."""
    radius = np.hypot(points[:, 1], points[:, 2])
    return np.column_stack([points[:, 0], radius * np.arctan2(points[:, 2], points[:, 1])])


class Face(NamedTuple):
    """A face of the die as the figure shows it: its title, the upward axis' label, its samples
    triangulated in the view (points (P, 2), triangles, values (P, columns)) and its edges (E, 2,
    2) in the view."""

    title: str
    upward: str
    points: np.ndarray
    triangles: np.ndarray
    values: np.ndarray
    edges: np.ndarray


def faces(samples: FacetSamples, scene: Scene) -> list[Face]:
    """The die's faces seen square-on: a round die unrolled; a rectangular die's facets by their
    normal, mostly along y (the height faces, seen in (x, z)) or z (the width faces, (x, y))."""
    if scene.geometry.round:
        views = [("the die unrolled", samples, unrolled,
                  "arc length from the plane z = 0, r theta")]
    else:
        height = np.abs(samples.normals[:, 1]) >= np.abs(samples.normals[:, 2])
        views = [("height faces (y = h(x)), seen along y", samples.subset(height),
                  lambda p: p[:, [0, 2]], "z"),
                 ("width faces (z = w(x)), seen along z", samples.subset(~height),
                  lambda p: p[:, [0, 1]], "y")]
    return [Face(title, upward, *view.merged(project),
                 np.array([project(edge) for edge in view.outline()]))
            for title, view, project, upward in views if len(view.points)]


def write_die_faces(samples: FacetSamples, names: list[str], path: Path, heading: Heading,
                    scene: Scene) -> Path:
    """die.png of a 3D run (rank 0): a row per stress of SHOWN among ``names`` (the samples'
    columns, die_stresses' order), a column per face (faces), one colour scale per row from its
    least to its largest value; the stresses in the scene's unit, or one of its family that
    reads 1 to 1000 (Units.shown)."""
    from mpl_toolkits.axes_grid1 import make_axes_locatable

    units = scene.units
    shown_faces = faces(samples, scene)
    rows = [name for name in SHOWN if name in names]
    extents = [np.ptp(face.points, axis=0) for face in shown_faces]
    # a row per stress, a column per face; one face: the stresses side by side
    shape = (len(rows), len(extents)) if len(extents) > 1 else (1, len(rows))
    panel = 8.5 / shape[1]  # inches of a panel, colour bars and labels aside
    tall = max(e[1] / e[0] for e in extents) * panel
    fig, axes = pyplot().subplots(*shape, squeeze=False,
                                  figsize=(11, shape[0] * (tall + 0.9) + 0.9),
                                  gridspec_kw={"width_ratios": [e[0] for e in extents]
                                               if len(extents) > 1 else None})
    axes = axes.reshape(len(rows), len(extents))
    for row, name in enumerate(rows):
        column = names.index(name)
        largest = max(np.nanmax(np.abs(face.values[:, column]), initial=0.0)
                      for face in shown_faces)
        unit = units.shown("stress", [largest])[1]
        shown = [units.shown("stress", face.values[:, column], largest)[0]
                 for face in shown_faces]
        low, high = colour_range(shown)
        for ax, face, values in zip(axes[row], shown_faces, shown, strict=True):
            mapped = ax.tripcolor(face.points[:, 0], face.points[:, 1], face.triangles, values,
                                  shading="gouraud", cmap=SHOWN[name][1], vmin=low, vmax=high)
            for edge in face.edges:
                ax.plot(edge[:, 0], edge[:, 1], color="k", linewidth=1.0)
            ax.set_aspect("equal")
            ax.set_xlabel(units.labelled("x", "length"))
            ax.set_ylabel(units.labelled(face.upward, "length"))
            ax.set_title(face.title, fontsize=9)
            plain_ticks(ax)
        bar = make_axes_locatable(axes[row][-1]).append_axes("right", size="4%", pad=0.1)
        fig.colorbar(mapped, cax=bar, label=bracketed(SHOWN[name][0], unit))
    fig.tight_layout(rect=heading.put_above(fig, list(axes.flat), "stresses on the die over its "
                                            "faces, with the die's edges"))
    return save(fig, path)

"""The maps of a 3D run on its symmetry planes, z = 0 (x, y: across the height) above y = 0 (x, z:
across the width): flow lines with time lines (velocity.png) and the equivalent strain rate of the
cells along each plane (strain_rate.png), as the 2D maps (maps.py) show them: over the process
window at 1:1 with the die's section. The velocity has no part normal to a symmetry plane, so the
flow lines drawn in it are streamlines of the 3D flow."""
from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import Any

import numpy as np

from forming_fenicsx.core.units import Units
from forming_fenicsx.io.figure import Heading, pyplot, save
from forming_fenicsx.io.maps import (FLOW_LINES, STRAIN_RATE, Frame, draw_flow_lines,
                                     rate_cells)
from forming_fenicsx.post.facet_samples import FacetSamples
from forming_fenicsx.post.views3d import PLANES

PLANE_NAMES = {"gamma7_symmetry": "symmetry plane z = 0 (across the height)",
               "gamma6_symmetry": "symmetry plane y = 0 (across the width)"}


@dataclasses.dataclass(frozen=True)
class Plane:
    """One symmetry plane's part of a map: its cells' outlines (F, k, 2) and strain rates (F,),
    the velocity on its triangulated nodes, and its frame."""

    name: str
    outlines: np.ndarray
    rate: np.ndarray
    nodes: tuple[np.ndarray, np.ndarray, np.ndarray]
    frame: Frame


def _plane(role: str, samples: FacetSamples, table: dict[str, np.ndarray], units: Units
           ) -> Plane:
    """The plane of a symmetry role from its samples (velocity, strain rate) and the die's
    nodes on it (die.csv's table: Gamma3's nodes whose other coordinate is zero)."""
    axes = PLANES[role]
    other = "xyz"[3 - axes[1]]  # the coordinate that is zero on the plane
    outlines = samples.points[:, samples.ring][:, :, axes]
    rate = samples.values[:, 0, 3]
    points, triangles, values = samples.merged(lambda p: p[:, axes])
    scale = max(np.ptp(table["x"]), 1e-300)
    on = np.abs(table[other]) < 1e-9 * scale
    order = np.argsort(table["x"][on], kind="stable")
    wall = np.column_stack([table["x"][on][order], table["xyz"[axes[1]]][on][order]])
    frame = Frame.of_run(outlines, rate, wall, units, "xyz"[axes[1]])
    return Plane(PLANE_NAMES[role], outlines, rate, (points, triangles, values[:, list(axes)]),
                 frame)


def _figure(planes: list[Plane]) -> tuple[Any, list[Any]]:
    """A figure of the planes one above the other, each at 1:1 over the same x window."""
    width = planes[0].frame.x[1] - planes[0].frame.x[0]
    heights = [plane.frame.top for plane in planes]
    fig, axes = pyplot().subplots(len(planes), 1, squeeze=False,
                                  figsize=(10, 8.5 * sum(heights) / width + 2.4),
                                  gridspec_kw={"height_ratios": heights})
    return fig, list(axes[:, 0])


def _finish(fig: Any, axes: list[Any], planes: list[Plane], heading: Heading, what: str,
            path: Path) -> Path:
    """The heading above the first plane, each plane's name above it (a failed run marked on
    every one); saved."""
    heading.put(axes[0], f"{what}\n{planes[0].name}")
    for plane, ax in zip(planes[1:], axes[1:], strict=True):
        ax.set_title(plane.name, fontsize=9)
        heading.mark(ax)
    fig.tight_layout()
    return save(fig, path)


def write_maps_3d(samples: dict[str, FacetSamples], table: dict[str, np.ndarray],
                  directory: Path, heading: Heading, units: Units) -> list[Path]:
    """velocity.png and strain_rate.png of a 3D run (rank 0): ``samples`` of each symmetry plane
    (views3d.symmetry_planes), ``table`` the die's nodes (die.py: die_profile)."""
    planes = [_plane(role, samples[role], table, units) for role in PLANES if role in samples]
    window = (min(p.frame.x[0] for p in planes), max(p.frame.x[1] for p in planes))
    planes = [dataclasses.replace(p, frame=dataclasses.replace(p.frame, x=window))
              for p in planes]
    paths = []
    fig, axes = _figure(planes)
    for plane, ax in zip(planes, axes, strict=True):
        draw_flow_lines(ax, plane.outlines, plane.nodes)
        plane.frame.draw(fig, ax)
    paths.append(_finish(fig, axes, planes, heading, FLOW_LINES, directory / "velocity.png"))

    fig, axes = _figure(planes)
    largest = max(np.nanmax(p.rate, initial=0.0) for p in planes)
    for plane, ax in zip(planes, axes, strict=True):
        cells = rate_cells(plane.outlines, plane.rate, largest)
        ax.add_collection(cells)
        plane.frame.draw(fig, ax, (cells, units.labelled("equivalent strain rate",
                                                         "strain_rate")))
    paths.append(_finish(fig, axes, planes, heading, STRAIN_RATE, directory / "strain_rate.png"))
    return paths

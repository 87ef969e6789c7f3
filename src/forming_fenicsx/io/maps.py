"""The maps of a run: flow lines with time lines (the picture of a grid-marker experiment), the
equivalent strain-rate map (the paper's Fig. 4) and the temperature map.

The maps show the process window (where the workpiece deforms, the die and some product) at 1:1
with the die drawn, so that a long thin product does not shrink the die zone to a thin band; a run
that did not converge says so on every figure."""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import dolfinx.fem
import numpy as np

from forming_fenicsx.core.compat import cell_geometry_nodes
from forming_fenicsx.core.units import Units, bracketed
from forming_fenicsx.fem.forms import FlowProblem
from forming_fenicsx.fem.projection import cell_means
from forming_fenicsx.io.die_plot import die_parts
from forming_fenicsx.io.figure import Heading, plain_ticks, pyplot, save
from forming_fenicsx.io.flow_lines import flow_lines
from forming_fenicsx.post.facet_samples import coincident
from forming_fenicsx.post.output_fields import nodal_velocity

QUAD_OUTLINE = [0, 1, 3, 2]  # dolfinx quadrilateral vertices in tensor order -> polygon order
STRAIN_RATE_MAP = "viridis"  # perceptually uniform colour maps
TEMPERATURE_MAP = "magma"
# dolfinx's quadrilateral node order: vertices (0, 0), (1, 0), (0, 1), (1, 1), then Q2's edge
# midpoints of the edges 0-1, 0-2, 1-3, 2-3 and the centre: the 3 x 3 rows 0 4 1 / 5 8 6 / 2 7 3
SUB_TRIANGLES = {4: np.array([[0, 1, 3], [0, 3, 2]]),
                 9: np.array([[0, 4, 8], [0, 8, 5], [4, 1, 6], [4, 6, 8], [5, 8, 7], [5, 7, 2],
                              [8, 6, 3], [8, 3, 7]])}
# the flow lines' velocity is linear on at most this many triangles: beyond, matplotlib's point
# location took most of a run's drawing time (1.35 s of 2.3 s for 155k triangles) for lines that
# look the same at the figure's resolution
FLOW_TRIANGLES = 50_000
# the window of the maps: the middle DEFORMING share of the strain rate's integral, from BEFORE
# entry half-sizes ahead of it to AFTER beyond it, up to HEADROOM times the entry half-size
DEFORMING = 0.98
BEFORE, AFTER, HEADROOM = 0.5, 1.0, 1.15


def _gather_cells(problem: FlowProblem) -> list[np.ndarray] | None:
    """Cell outlines and cell-mean equivalent strain rate of every cell, on rank 0."""
    mesh = problem.mesh
    owned = mesh.topology.index_map(mesh.topology.dim).size_local
    nodes = cell_geometry_nodes(mesh)[:owned][:, QUAD_OUTLINE]
    outlines = mesh.geometry.x[nodes][:, :, :2]
    degree = problem.full_degree
    rate = cell_means(problem.mesh, problem.equivalent_strain_rate(problem.u), "rate",
                      degree).x.array[:owned]
    parts = problem.comm.gather((outlines, rate), root=0)
    if problem.comm.rank != 0:
        return None
    return [np.concatenate(p) for p in zip(*parts, strict=True)]


def _gather_nodes(function: dolfinx.fem.Function, most: float = np.inf
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """Sub-triangles of every owned cell through the nodes of a Lagrange function of degree 1 or 2
    (Q2: the 3 x 3 nodes, 8 triangles; Q1: 2) and its values there, on rank 0: (points, triangles,
    values of shape (nodes, block size)) with coincident nodes merged (collective; None on other
    ranks). Beyond ``most`` sub-triangles in all, two per cell through its corners (the first
    four nodes in both layouts)."""
    space = function.function_space
    mesh = space.mesh
    owned = mesh.topology.index_map(mesh.topology.dim).size_local
    coordinates = space.tabulate_dof_coordinates()[:, :2]
    values = function.x.array.reshape(len(coordinates), -1)
    cells = np.array([space.dofmap.cell_dofs(c) for c in range(owned)])
    parts = mesh.comm.gather((coordinates[cells], values[cells]), root=0)
    if mesh.comm.rank != 0:
        return None
    points = np.concatenate([p for p, _ in parts])  # (cells, nodes per cell, 2)
    found = np.concatenate([v for _, v in parts])
    local = SUB_TRIANGLES[points.shape[1]]
    if len(points) * len(local) > most:
        local = SUB_TRIANGLES[4]
    first, index = coincident(points.reshape(-1, 2))
    triangles = (index.reshape(points.shape[:2])[:, local]).reshape(-1, 3)
    return points.reshape(-1, 2)[first], triangles, found.reshape(-1, found.shape[-1])[first]


def process_window(outlines: np.ndarray, rate: np.ndarray, wall: np.ndarray
                   ) -> tuple[float, float]:
    """The x range the maps show: where the workpiece deforms (the middle DEFORMING share of the
    integral of the cell-mean strain rate over the section, by cell centre) and the die from where
    it leaves the entry size (past any container wall) to its end, BEFORE entry half-sizes ahead
    and AFTER beyond, within the workpiece."""
    x, y = outlines[..., 0], outlines[..., 1]
    areas = 0.5 * np.abs((x * np.roll(y, -1, axis=1) - np.roll(x, -1, axis=1) * y).sum(axis=1))
    centres = x.mean(axis=1)
    order = np.argsort(centres)
    total = np.cumsum(np.nan_to_num(rate * areas)[order])
    ends = (x.min(), x.max())
    first, last = ends
    if total[-1] > 0:
        tail = 0.5 * (1 - DEFORMING) * total[-1]
        first, last = np.interp([tail, total[-1] - tail], total, centres[order])
    level = wall[:, 1] >= wall[:, 1].max() * (1 - 1e-6)  # the container wall or the die entry
    first, last = min(first, wall[level, 0].max()), max(last, wall[:, 0].max())
    size = y.max()
    return max(ends[0], first - BEFORE * size), min(ends[1], last + AFTER * size)


def die_body(wall: np.ndarray, right: float, top: float) -> np.ndarray:
    """The die as a polygon for a map: its wall (Gamma3's nodes along the die) closed above at
    ``top``; a wall ending on a die face (a square die) goes on level to ``right`` (the die plate),
    any other ends with a vertical back face."""
    face = die_parts(wall[-2:, 0], wall[-2:, 1]) == ["die face"]
    end = right if face else wall[-1, 0]
    return np.vstack([wall, [[end, wall[-1, 1]], [end, top], [wall[0, 0], top]]])


@dataclass(frozen=True)
class Frame:
    """The window every map of a run shows (process_window, at 1:1 up to HEADROOM times the entry
    half-size) and the die drawn over it; ``across`` names the coordinate shown upward (a 3D
    run's plane y = 0 shows z)."""

    x: tuple[float, float]
    top: float
    wall: np.ndarray  # the die wall: Gamma3's nodes in order along the die, (N, 2)
    units: Units
    across: str = "y"

    @classmethod
    def of_run(cls, outlines: np.ndarray, rate: np.ndarray, wall: np.ndarray, units: Units,
               across: str = "y") -> Frame:
        return cls(process_window(outlines, rate, wall), HEADROOM * outlines[..., 1].max(), wall,
                   units, across)

    def axes(self) -> tuple[Any, Any]:
        """A figure and its axes sized to the window."""
        width = self.x[1] - self.x[0]
        return pyplot().subplots(figsize=(10, 8.5 * self.top / width + 1.6))

    def draw(self, fig: Any, ax: Any, colour: tuple[Any, str] | None = None) -> None:
        """The die (hatched, over the workpiece) on the window at 1:1, labelled axes and a colour
        bar as tall as the map (``colour``: the mapping and its label)."""
        from matplotlib.patches import Polygon
        from mpl_toolkits.axes_grid1 import make_axes_locatable

        ax.add_patch(Polygon(die_body(self.wall, self.x[1], self.top), closed=True,
                             facecolor="0.82", edgecolor="0.15", hatch="//", linewidth=1.0,
                             zorder=3, label="die"))
        ax.set_xlim(*self.x)
        ax.set_ylim(0.0, self.top)
        ax.set_aspect("equal")
        ax.set_xlabel(self.units.labelled("x", "length"))
        ax.set_ylabel(self.units.labelled(self.across, "length"))
        plain_ticks(ax)
        if colour is not None:
            bar = make_axes_locatable(ax).append_axes("right", size="2%", pad=0.1)
            fig.colorbar(colour[0], cax=bar, label=colour[1])

    def finish(self, fig: Any, ax: Any, path: Path, heading: Heading, what: str,
               colour: tuple[Any, str] | None = None) -> Path:
        """draw, the heading; saved."""
        self.draw(fig, ax, colour)
        heading.put(ax, what)
        return save(fig, path)


FLOW_LINES = ("flow lines (streamlines of the steady velocity) and time lines (a grid of markers "
              "1 x 2 bands at the entry)")
STRAIN_RATE = "equivalent strain rate (cell means, log scale)"


def draw_flow_lines(ax: Any, outlines: np.ndarray,
                    nodes: tuple[np.ndarray, np.ndarray, np.ndarray]) -> None:
    """The cells' outlines in light grey, and the flow lines and time lines (flow_lines.py) of
    the velocity on the triangulated nodes (points, triangles, values)."""
    from matplotlib.collections import PolyCollection

    ax.add_collection(PolyCollection(outlines, facecolors="none", edgecolors="0.85",
                                     linewidths=0.3))
    lines, times = flow_lines(*nodes)
    for line in lines:
        ax.plot(line[:, 0], line[:, 1], color="tab:blue", linewidth=1.0)
    for line in times:
        ax.plot(line[:, 0], line[:, 1], color="0.3", linewidth=0.6)


def rate_cells(outlines: np.ndarray, rate: np.ndarray, largest: float) -> Any:
    """The cells coloured by their strain rate on a log scale from 1e-4 of ``largest`` (the
    largest of every panel that shares the scale) up to it."""
    from matplotlib.collections import PolyCollection
    from matplotlib.colors import LogNorm

    floor = max(largest * 1e-4, 1e-12)
    return PolyCollection(outlines, array=np.maximum(rate, floor), cmap=STRAIN_RATE_MAP,
                          norm=LogNorm(vmin=floor, vmax=max(largest, 2 * floor)),
                          edgecolors="face")


def write_figures(problem: FlowProblem, directory: Path, heading: Heading,
                  profile: dict | None, die_wall: np.ndarray | None = None,
                  surfaces: dict[str, np.ndarray] | None = None) -> list[Path]:
    """velocity.png (flow lines and time lines), strain_rate.png and, with [thermal],
    temperature.png, each over the process window with the die drawn (collective: every rank
    gathers, rank 0 draws; ``profile``: die_profile's, on rank 0). ``die_wall``: the whole die
    wall (N, 2) where Gamma3 is only its part in contact (a free-surface run), and ``surfaces``
    the free surfaces found, drawn in velocity.png."""
    cells = _gather_cells(problem)
    nodes = _gather_nodes(nodal_velocity(problem), FLOW_TRIANGLES)
    field = problem.field("temperature")
    temperatures = _gather_nodes(field.T) if field is not None else None
    if cells is None:
        return []
    outlines, rate = cells
    units = problem.scene.units
    wall = np.column_stack([profile["x"], profile["y"]]) if die_wall is None else die_wall
    frame = Frame.of_run(outlines, rate, wall, units)

    fig, ax = frame.axes()
    draw_flow_lines(ax, outlines, nodes)
    for number, line in enumerate((surfaces or {}).values()):
        ax.plot(line[:, 0], line[:, 1], color="tab:red", linewidth=1.6, zorder=4,
                label="free surface (a streamline)" if number == 0 else None)
    if surfaces:
        ax.legend(loc="lower left", fontsize="small")
    paths = [frame.finish(fig, ax, directory / "velocity.png", heading, FLOW_LINES)]

    fig, ax = frame.axes()
    cells = rate_cells(outlines, rate, np.nanmax(rate, initial=0.0))
    ax.add_collection(cells)
    paths.append(frame.finish(fig, ax, directory / "strain_rate.png", heading, STRAIN_RATE,
                              (cells, units.labelled("equivalent strain rate", "strain_rate"))))

    if temperatures is not None:
        points, triangles, values = temperatures
        shown, unit = units.shown("temperature", values[:, 0])
        fig, ax = frame.axes()
        mapped = ax.tripcolor(points[:, 0], points[:, 1], triangles, shown, shading="gouraud",
                              cmap=TEMPERATURE_MAP)
        paths.append(frame.finish(fig, ax, directory / "temperature.png", heading,
                                  "steady temperature", (mapped, bracketed("temperature", unit))))
    return paths

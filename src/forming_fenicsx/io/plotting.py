"""PNG figures of a run: flow lines with time lines (the picture of a grid-marker experiment), the
equivalent strain-rate map (the paper's Fig. 4), the temperature map, the die stresses along the
die and the profiles across the product.

The maps show the process window (where the workpiece deforms, the die and some product) at 1:1
with the die drawn, so that a long thin product does not shrink the die zone to a thin band; a run
that did not converge says so on every figure."""
from __future__ import annotations

import re
import textwrap
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from forming_fenicsx.core.compat import cell_geometry_nodes
from forming_fenicsx.fem.forms import FlowProblem
from forming_fenicsx.fem.projection import cell_means
from forming_fenicsx.post.postprocess import nodal_velocity
from forming_fenicsx.post.streamlines import rk4_step
from forming_fenicsx.core.units import Units, bracketed

QUAD_OUTLINE = [0, 1, 3, 2]  # dolfinx quadrilateral vertices in tensor order -> polygon order
STRAIN_RATE_MAP = "viridis"  # perceptually uniform colour maps
TEMPERATURE_MAP = "magma"
FAILURE_COLOUR = "tab:red"


def _pyplot():
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


def run_settings(scene) -> str:
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
    def of_run(cls, name: str, scene, summary: dict[str, Any]) -> Heading:
        return cls(name, run_settings(scene), not_converged(summary))

    def put(self, ax, what: str) -> None:
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


def _plain_ticks(ax) -> None:
    """Tick labels without an offset ("+7.3e2" above an axis of temperatures): the values shown
    are in the axis label's unit (Units.shown keeps them readable)."""
    from matplotlib.ticker import ScalarFormatter

    for axis in (ax.xaxis, ax.yaxis):
        if axis.get_scale() == "linear":
            axis.set_major_formatter(ScalarFormatter(useOffset=False))


def _save(fig, path: Path) -> Path:
    """Save at 130 dpi cropped to what is drawn, and close."""
    fig.savefig(path, dpi=130, bbox_inches="tight")
    _pyplot().close(fig)
    return path


def _gather_cells(problem: FlowProblem):
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


def _gather_nodes(function):
    """Sub-triangles of every owned cell through the nodes of a Lagrange function of degree 1 or 2
    (Q2: the 3 x 3 nodes, 8 triangles; Q1: 2) and its values there, on rank 0: (points, triangles,
    values of shape (nodes, block size)) with coincident nodes merged (collective; None on other
    ranks)."""
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
    scale = max(np.ptp(points.reshape(-1, 2), axis=0).max(), 1e-300)
    keys = np.round(points.reshape(-1, 2) / scale * 1e9).astype(np.int64)
    _, first, index = np.unique(keys, axis=0, return_index=True, return_inverse=True)
    triangles = (index.reshape(points.shape[:2])[:, local]).reshape(-1, 3)
    return points.reshape(-1, 2)[first], triangles, found.reshape(-1, found.shape[-1])[first]


# dolfinx's quadrilateral node order: vertices (0, 0), (1, 0), (0, 1), (1, 1), then Q2's edge
# midpoints of the edges 0-1, 0-2, 1-3, 2-3 and the centre: the 3 x 3 rows 0 4 1 / 5 8 6 / 2 7 3
SUB_TRIANGLES = {4: np.array([[0, 1, 3], [0, 3, 2]]),
                 9: np.array([[0, 4, 8], [0, 8, 5], [4, 1, 6], [4, 6, 8], [5, 8, 7], [5, 7, 2],
                              [8, 6, 3], [8, 3, 7]])}


# the window of the maps: the middle DEFORMING share of the strain rate's integral, from BEFORE
# entry half-sizes ahead of it to AFTER beyond it, up to HEADROOM times the entry half-size
DEFORMING = 0.98
BEFORE, AFTER, HEADROOM = 0.5, 1.0, 1.15


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
    half-size) and the die drawn over it."""

    x: tuple[float, float]
    top: float
    wall: np.ndarray  # the die wall: Gamma3's nodes in order along the die, (N, 2)
    units: Units

    @classmethod
    def of_run(cls, outlines: np.ndarray, rate: np.ndarray, profile: dict, units: Units) -> Frame:
        wall = np.column_stack([profile["x"], profile["y"]])
        return cls(process_window(outlines, rate, wall), HEADROOM * outlines[..., 1].max(), wall,
                   units)

    def axes(self):
        """A figure and its axes sized to the window."""
        width = self.x[1] - self.x[0]
        return _pyplot().subplots(figsize=(10, 8.5 * self.top / width + 1.6))

    def finish(self, fig, ax, path: Path, heading: Heading, what: str,
               colour: tuple[Any, str] | None = None) -> Path:
        """The die (hatched, over the workpiece) on the window at 1:1, labelled axes, a colour bar
        as tall as the map (``colour``: the mapping and its label), the heading; saved."""
        from matplotlib.patches import Polygon
        from mpl_toolkits.axes_grid1 import make_axes_locatable

        ax.add_patch(Polygon(die_body(self.wall, self.x[1], self.top), closed=True,
                             facecolor="0.82", edgecolor="0.15", hatch="//", linewidth=1.0,
                             zorder=3, label="die"))
        ax.set_xlim(*self.x)
        ax.set_ylim(0.0, self.top)
        ax.set_aspect("equal")
        ax.set_xlabel(self.units.labelled("x", "length"))
        ax.set_ylabel(self.units.labelled("y", "length"))
        _plain_ticks(ax)
        if colour is not None:
            bar = make_axes_locatable(ax).append_axes("right", size="2%", pad=0.1)
            fig.colorbar(colour[0], cax=bar, label=colour[1])
        heading.put(ax, what)
        return _save(fig, path)


def write_figures(problem: FlowProblem, directory: Path, heading: Heading,
                  profile: dict | None) -> list[Path]:
    """velocity.png (flow lines and time lines), strain_rate.png and, with [thermal],
    temperature.png, each over the process window with the die drawn (collective: every rank
    gathers, rank 0 draws; ``profile``: die_profile's, on rank 0)."""
    cells = _gather_cells(problem)
    nodes = _gather_nodes(nodal_velocity(problem))
    field = problem.field("temperature")
    temperatures = _gather_nodes(field.T) if field is not None else None
    if cells is None:
        return []
    from matplotlib.collections import PolyCollection
    from matplotlib.colors import LogNorm

    outlines, rate = cells
    units = problem.scene.units
    frame = Frame.of_run(outlines, rate, profile, units)

    fig, ax = frame.axes()
    ax.add_collection(PolyCollection(outlines, facecolors="none", edgecolors="0.85",
                                     linewidths=0.3))
    lines, times = flow_lines(*nodes)
    for line in lines:
        ax.plot(line[:, 0], line[:, 1], color="tab:blue", linewidth=1.0)
    for line in times:
        ax.plot(line[:, 0], line[:, 1], color="0.3", linewidth=0.6)
    paths = [frame.finish(fig, ax, directory / "velocity.png", heading,
                          "flow lines (streamlines of the steady velocity) and time lines "
                          "(a grid of markers 1 x 2 bands at the entry)")]

    fig, ax = frame.axes()
    largest = np.nanmax(rate, initial=0.0)
    floor = max(largest * 1e-4, 1e-12)
    cells = PolyCollection(outlines, array=np.maximum(rate, floor), cmap=STRAIN_RATE_MAP,
                           norm=LogNorm(vmin=floor, vmax=max(largest, 2 * floor)),
                           edgecolors="face")
    ax.add_collection(cells)
    paths.append(frame.finish(fig, ax, directory / "strain_rate.png", heading,
                              "equivalent strain rate (cell means, log scale)",
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


FLOW_LINES = 10  # flow lines from the centres of as many equal bands across the entry section
PER_BAND = 8  # material points per band on each time line to start with (even: a band's centre
#               is one)


def flow_lines(points: np.ndarray, triangles: np.ndarray, velocity: np.ndarray,
               count: int = FLOW_LINES, steps_per_mark: int = 20
               ) -> tuple[list[np.ndarray], list[np.ndarray]]:
    """Flow lines and time lines of the steady flow, as a grid-marker experiment shows them.

    Material points x' = u(x), integrated by classical Runge-Kutta (RK4) with a fixed time step
    from seeds across the entry section (the smallest x, y from the axis to the outermost of
    ``count`` equal bands' centres), u linear on the triangles through the nodes, until a point
    leaves the workpiece or stops. The flow lines are the paths from the band centres; a time line
    joins the points that entered together, 2 (band width)/U_entry apart in time: the material
    lines of a grid of 1 x 2 bands at the entry. PER_BAND seeds per band to start with, and more
    between two neighbours that drift more than MAX_GAP band widths apart on a time line (a
    product sped up by extrusion, a surface held back by friction), so that a time line follows
    its material line instead of cutting across the die. Returns both (none when the entry does
    not move)."""
    from matplotlib.tri import LinearTriInterpolator, Triangulation

    mesh = Triangulation(points[:, 0], points[:, 1], triangles)
    finder = mesh.get_trifinder()
    ux = LinearTriInterpolator(mesh, velocity[:, 0], trifinder=finder)
    uy = LinearTriInterpolator(mesh, velocity[:, 1], trifinder=finder)

    def u(x: np.ndarray) -> np.ndarray:
        return np.ma.column_stack([ux(x[:, 0], x[:, 1]), uy(x[:, 0], x[:, 1])]).filled(np.nan)

    start = points[:, 0].min()
    entry = points[np.isclose(points[:, 0], start, atol=1e-9 * np.ptp(points[:, 0]))]
    top = entry[:, 1].max()
    band = top / count
    inset = 1e-6 * np.ptp(points[:, 0])
    seeds = (count - 1) * PER_BAND + PER_BAND // 2  # from the axis to the outermost band centre
    heights = band * np.maximum(np.arange(seeds + 1) / PER_BAND, 1e-4 * count)
    centres = np.arange(count) * PER_BAND + PER_BAND // 2
    entry_speed = np.nanmean(np.abs(u(np.column_stack([np.full(count, start + inset),
                                                       heights[centres]]))[:, 0]))
    if not entry_speed > 0:  # a run stopped before its first solve: nothing flows
        return [], []
    dt = band / entry_speed / steps_per_mark
    limit = int(min(3 * np.ptp(points[:, 0]) / (entry_speed * dt), 1e5))

    def paths_from(ys: np.ndarray) -> list[np.ndarray]:
        x = np.column_stack([np.full(len(ys), start + inset), ys])
        fastest = np.abs(velocity).max()
        paths = [[p] for p in x]
        alive = np.ones(len(x), dtype=bool)
        for _ in range(limit):
            if not alive.any():
                break
            moved = rk4_step(u, x, dt)
            step, x = moved - x, moved
            alive &= np.isfinite(x).all(axis=1) & (np.abs(step).max(axis=1) > 1e-9 * fastest * dt)
            for i in np.flatnonzero(alive):
                paths[i].append(x[i])
        return [np.array(path) for path in paths]

    every = 2 * steps_per_mark
    paths = dict(zip(heights, paths_from(heights), strict=True))
    for _ in range(REFINEMENTS):
        ys = sorted(paths)
        wide = [0.5 * (a + b) for a, b in zip(ys[:-1], ys[1:], strict=True)
                if _drift(paths[a], paths[b], every) > MAX_GAP * band and b - a > 1e-6 * band]
        if not wide or len(paths) + len(wide) > MAX_SEEDS:
            break
        paths.update(zip(wide, paths_from(np.array(wide)), strict=True))
    ordered = [paths[y] for y in sorted(paths)]
    times = [np.array([path[index] for path in ordered if index < len(path)])
             for index in range(every, max(len(path) for path in ordered), every)]
    return [paths[y] for y in heights[centres]], [line for line in times if len(line) > 1]


MAX_GAP = 0.5  # band widths between neighbouring points of a time line before seeds are added
REFINEMENTS = 6  # rounds of added seeds (each halves the spacing where the points drift apart)
MAX_SEEDS = 4000


def _drift(a: np.ndarray, b: np.ndarray, every: int) -> float:
    """The largest distance between two paths' points at the time lines' instants both reach."""
    shared = min(len(a), len(b))
    marks = np.arange(every, shared, every)
    if len(marks) == 0:
        return 0.0
    return float(np.linalg.norm(a[marks] - b[marks], axis=1).max())


DIE_PARTS = {"container wall": "tab:green", "die face": "tab:red", "cone": "tab:purple",
             "land": "tab:brown"}


def die_parts(x: np.ndarray, y: np.ndarray) -> list[str]:
    """The part of the die each segment between consecutive nodes of Gamma3 lies on, by its slope:
    "die face" (within 10 deg of the normal to the axis, a square die's face), level (within 1 deg
    of the axis: the "container wall" before the first inclined segment, the "land" after it),
    else "cone"."""
    slope = np.degrees(np.arctan2(np.abs(np.diff(y)), np.abs(np.diff(x))))
    parts, reached = [], False
    for angle in slope:
        if angle > 80.0:
            parts.append("die face")
        elif angle < 1.0:
            parts.append("land" if reached else "container wall")
        else:
            parts.append("cone")
        reached |= angle >= 1.0
    return parts


def write_die_plot(profile: dict, path: Path, heading: Heading, scene) -> Path:
    """die.png: the stresses on the die (contact pressure, averaged normal stress and friction
    stress, as present) along the die coordinate s, over bands marking the part of the die
    (die_parts), and below it the die profile y(x) through the nodes of Gamma3 (die.csv's x and y)
    at 1:1, coloured by part; axes with the scene's units (stresses far from 1 in another unit of
    their family, Units.shown), the run's main settings in the title."""
    plt = _pyplot()
    units = scene.units
    fig, (ax, shape) = plt.subplots(2, 1, figsize=(8, 7.5), gridspec_kw={"height_ratios": [3, 2]})
    names = {"contact_pressure": ("contact pressure", " -sigma_N"), "averaged_normal_stress":
             ("averaged normal stress", ""), "friction_stress": ("friction stress", " |sigma_T|")}
    shown = [key for key in names if key in profile]
    parts = die_parts(profile["x"], profile["y"])
    for index, part in enumerate(parts):
        first = index == parts.index(part)
        label = part if first else None
        ax.axvspan(profile["s"][index], profile["s"][index + 1], color=DIE_PARTS[part], alpha=0.12,
                   lw=0, label=label)
        shape.plot(profile["x"][index:index + 2], profile["y"][index:index + 2], "-",
                   color=DIE_PARTS[part], linewidth=2.5, label=label)
    largest = max(np.nanmax(np.abs(profile[key]), initial=0.0) for key in shown)
    unit = units.shown("stress", [largest])[1]  # one unit for every stress on the axis
    for key in shown:
        ax.plot(profile["s"], units.shown("stress", profile[key], largest)[0], marker=".",
                label="".join(names[key]))
    ax.set_xlabel(units.labelled("s, distance along the die from where the workpiece meets it",
                                 "length"))
    ax.set_ylabel(bracketed("stress on the die", unit))
    heading.put(ax, "stresses on the die")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    shape.plot(profile["x"], profile["y"], "k.", markersize=1.5, label="nodes of Gamma3")
    shape.set_xlabel(units.labelled("x, along the axis", "length"))
    size = "radius" if scene.geometry.axisymmetric else "half-thickness"
    shape.set_ylabel(units.labelled(size, "length"))
    shape.update_datalim([[profile["x"][0], 0.0]])  # from the axis
    shape.autoscale()
    shape.set_aspect("equal", adjustable="datalim")  # 1:1, the limits widened to fill the panel
    shape.set_title("die profile (1:1)", fontsize=9)
    shape.grid(True, alpha=0.3)
    shape.legend(fontsize=8)
    for axes in (ax, shape):
        _plain_ticks(axes)
    fig.tight_layout()
    return _save(fig, path)


def write_exit_profile_plot(profile: dict, path: Path, heading: Heading, label: str,
                            dimension: str, units: Units,
                            reference: tuple[str, float] | None = None) -> Path:
    """exit_<quantity>.png: a quantity across the product against y (the hardness or temperature
    profile; temperatures in units.temperature), with a reference level (``(label, value)``: the
    ideal strain, the inflow temperature); the strain's profile (postprocess.exit_strain_profile)
    also shows the strain traced along the streamlines and the transported field, and shades the
    outermost elements, across which the written profile takes its mean (docs/hardening.md)."""
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(7, 4.5))
    values, unit = units.shown(dimension, profile["values"])
    strain = "surface_layer" in profile
    if strain:  # a layer at the surface is not resolved
        surface = profile["y"][-1]
        ax.axvspan(surface - profile["surface_layer"], surface, color="0.88",
                   label="the outermost elements: the written value is their mean")
        ax.plot(profile["y"], profile["transported"], "--", color="tab:orange",
                label=f"transported {label} (FE field)")
        ax.plot(profile["y"], profile["streamlines"], "-", color="0.5", linewidth=0.8,
                label=f"{label} along the streamlines")
    ax.plot(profile["y"], values, "b.-",
            label=f"{label}: the written profile (CSV)" if strain else f"FE {label}")
    if reference is not None:
        level = float(units.shown(dimension, reference[1])[0])
        ax.axhline(level, color="k", linestyle="--", label=f"{reference[0]} = {level:.4g}")
    ax.set_xlabel(units.labelled("y, from the axis to the surface of the product", "length"))
    ax.set_ylabel(bracketed(label, unit))
    heading.put(ax, f"{label} across the product")
    if dimension != "temperature":
        ax.set_ylim(bottom=0.0)
    ax.grid(True, alpha=0.3)
    ax.legend()
    _plain_ticks(ax)
    fig.tight_layout()
    return _save(fig, path)

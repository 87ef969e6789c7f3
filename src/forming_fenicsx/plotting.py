"""PNG figures of a run: flow lines with time lines (the picture of a grid-marker experiment), the
equivalent strain-rate map (the paper's Fig. 4) and the die stresses along the die."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from .compat import cell_geometry_nodes
from .forms import FlowProblem
from .postprocess import cell_means, nodal_velocity
from .streamlines import rk4_step
from .units import Units

QUAD_OUTLINE = [0, 1, 3, 2]  # dolfinx quadrilateral vertices in tensor order -> polygon order


def _gather_cells(problem: FlowProblem):
    """Cell outlines and cell-mean equivalent strain rate of every cell, on rank 0."""
    mesh = problem.mesh
    owned = mesh.topology.index_map(mesh.topology.dim).size_local
    nodes = cell_geometry_nodes(mesh)[:owned][:, QUAD_OUTLINE]
    outlines = mesh.geometry.x[nodes][:, :, :2]
    degree = problem.full_degree
    rate = cell_means(problem, problem.equivalent_strain_rate(problem.u), "rate", degree).x.array[:owned]
    parts = problem.comm.gather((outlines, rate), root=0)
    if problem.comm.rank != 0:
        return None
    return [np.concatenate(p) for p in zip(*parts, strict=True)]


def write_figures(problem: FlowProblem, directory: Path, title: str) -> list[Path]:
    """velocity.png (flow lines and time lines, flow_lines) and strain_rate.png (collective; rank 0
    draws)."""
    data = _gather_cells(problem)
    nodes = _gather_velocity_nodes(problem)
    if data is None:
        return []
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.collections import PolyCollection
    from matplotlib.colors import LogNorm

    outlines, rate = data
    scene = problem.scene
    units = scene.units
    extent = np.ptp(outlines.reshape(-1, 2), axis=0)
    size = (10, max(2.5, 10 * extent[1] / extent[0] + 1.0))
    heading = f"{title}: {run_settings(scene)}"
    paths = []

    fig, ax = plt.subplots(figsize=size)
    ax.add_collection(PolyCollection(outlines, facecolors="none", edgecolors="0.85",
                                     linewidths=0.3))
    lines, every = flow_lines(*nodes)
    for line in lines:
        ax.plot(line[:, 0], line[:, 1], color="tab:blue", linewidth=1.0)
    for index in range(every, max((len(line) for line in lines), default=0), every):
        marks = np.array([line[index] for line in lines if index < len(line)])
        if len(marks) > 1:
            ax.plot(marks[:, 0], marks[:, 1], color="0.3", linewidth=0.6)
    ax.set_title(f"{heading}\nflow lines (streamlines of the steady velocity) and time lines "
                 "(grid markers)", fontsize=9)
    paths.append(_finish(fig, ax, outlines, directory / "velocity.png", units))

    fig, ax = plt.subplots(figsize=size)
    floor = max(rate.max() * 1e-4, 1e-12)
    cells = PolyCollection(outlines, array=np.maximum(rate, floor), cmap="jet",
                           norm=LogNorm(vmin=floor, vmax=max(rate.max(), 2 * floor)), edgecolors="face")
    ax.add_collection(cells)
    fig.colorbar(cells, ax=ax, label=units.labelled("equivalent strain rate", "strain_rate"))
    ax.set_title(f"{heading}\nequivalent strain rate (cell means)", fontsize=9)
    paths.append(_finish(fig, ax, outlines, directory / "strain_rate.png", units))
    return paths


FLOW_LINES = 10  # flow lines from the centres of as many equal bands across the entry section


def _gather_velocity_nodes(problem: FlowProblem):
    """Sub-triangles of every owned cell through its nodes of the geometry degree (Q2: the 3 x 3
    nodes, 8 triangles; Q1: 2) and the velocity at the nodes, on rank 0: (points, triangles,
    velocities) with coincident nodes merged (collective; None on other ranks)."""
    velocity = nodal_velocity(problem)
    space = velocity.function_space
    owned = problem.mesh.topology.index_map(problem.mesh.topology.dim).size_local
    coordinates = space.tabulate_dof_coordinates()[:, :2]
    values = velocity.x.array.reshape(-1, 2)
    cells = np.array([space.dofmap.cell_dofs(c) for c in range(owned)])
    parts = problem.comm.gather((coordinates[cells], values[cells]), root=0)
    if problem.comm.rank != 0:
        return None
    points = np.concatenate([p for p, _ in parts])  # (cells, nodes per cell, 2)
    speeds = np.concatenate([v for _, v in parts])
    local = SUB_TRIANGLES[points.shape[1]]
    scale = max(np.ptp(points.reshape(-1, 2), axis=0).max(), 1e-300)
    keys = np.round(points.reshape(-1, 2) / scale * 1e9).astype(np.int64)
    _, first, index = np.unique(keys, axis=0, return_index=True, return_inverse=True)
    triangles = (index.reshape(points.shape[:2])[:, local]).reshape(-1, 3)
    return points.reshape(-1, 2)[first], triangles, speeds.reshape(-1, 2)[first]


# dolfinx's quadrilateral node order: vertices (0, 0), (1, 0), (0, 1), (1, 1), then Q2's edge
# midpoints of the edges 0-1, 0-2, 1-3, 2-3 and the centre: the 3 x 3 rows 0 4 1 / 5 8 6 / 2 7 3
SUB_TRIANGLES = {4: np.array([[0, 1, 3], [0, 3, 2]]),
                 9: np.array([[0, 4, 8], [0, 8, 5], [4, 1, 6], [4, 6, 8], [5, 8, 7], [5, 7, 2],
                              [8, 6, 3], [8, 3, 7]])}


def flow_lines(points: np.ndarray, triangles: np.ndarray, velocity: np.ndarray,
               count: int = FLOW_LINES, steps_per_mark: int = 20) -> tuple[list[np.ndarray], int]:
    """Material lines of the steady flow: x' = u(x) integrated by classical Runge-Kutta
    (streamlines.rk4_step) with a fixed time step from ``count`` seeds at the centres of equal
    bands across the entry section (the smallest x, y from 0 to the largest y there), u linear on
    the triangles through the nodes, until a point leaves the workpiece or stops. Returns the
    lines (positions at every step; none when the entry does not move) and the number of steps
    between time lines: marks placed every 2 (band width)/U_entry in time, which start as a grid
    of 1 x 2 bands at the entry and show its distortion, as grid markers do."""
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
    inset = 1e-6 * np.ptp(points[:, 0])
    x = np.column_stack([np.full(count, start + inset), top * (np.arange(count) + 0.5) / count])
    entry_speed = np.nanmean(np.abs(u(x)[:, 0]))
    if not entry_speed > 0:  # a run stopped before its first solve: nothing flows
        return [], 2 * steps_per_mark
    dt = top / count / entry_speed / steps_per_mark
    fastest = np.abs(velocity).max()
    limit = int(min(3 * np.ptp(points[:, 0]) / (entry_speed * dt), 1e5))
    lines = [[p] for p in x]
    alive = np.ones(count, dtype=bool)
    for _ in range(limit):
        if not alive.any():
            break
        moved = rk4_step(u, x, dt)
        step, x = moved - x, moved
        alive &= np.isfinite(x).all(axis=1) & (np.abs(step).max(axis=1) > 1e-9 * fastest * dt)
        for i in np.flatnonzero(alive):
            lines[i].append(x[i])
    return [np.array(line) for line in lines], 2 * steps_per_mark


def run_settings(scene) -> str:
    """The run's main settings for a figure title, e.g. "drawing, strip 2 -> 1.6 mm, die 10 deg,
    mu = 0.08, Q2 h = 0.053 mm"."""
    g, f, d = scene.geometry, scene.friction, scene.discretisation
    length = scene.units.label("length")
    unit = f" {length}" if length else ""
    shape = "round" if g.axisymmetric else "strip"
    angle = getattr(g, "die_angle", None)
    die = f", die {angle:g} deg" if angle is not None else f", {g.die} die"
    friction = f"m = {f.m:g}" if f.law == "factor" else f"mu = {f.mu:g}"
    mesh = f"mesh {Path(g.mesh_file).name}" if g.mesh_file else f"h = {d.mesh_size:.2g}{unit}"
    return (f"{scene.process.kind}, {shape} {g.entry_thickness:.4g} -> {g.exit_thickness:.4g}"
            f"{unit}{die}, {friction}, {d.element} {mesh}")


def _finish(fig, ax, outlines: np.ndarray, path: Path, units: Units) -> Path:
    import matplotlib.pyplot as plt

    points = outlines.reshape(-1, 2)
    ax.set_xlim(points[:, 0].min(), points[:, 0].max())
    ax.set_ylim(points[:, 1].min(), points[:, 1].max())
    ax.set_aspect("equal")
    ax.set_xlabel(units.labelled("x", "length"))
    ax.set_ylabel(units.labelled("y", "length"))
    fig.tight_layout()
    fig.savefig(path, dpi=130)
    plt.close(fig)
    return path


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


def write_die_plot(profile: dict, path: Path, title: str, scene) -> Path:
    """die.png: the stresses on the die (contact pressure, averaged normal stress and friction
    stress, as present) along the die coordinate s, over bands marking the part of the die
    (die_parts), and below it the die profile y(x) through the nodes of Gamma3 (die.csv's x and y),
    coloured by part; axes with the scene's units, the run's main settings in the title."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

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
    for key in shown:
        ax.plot(profile["s"], profile[key], marker=".", label="".join(names[key]))
    ax.set_xlabel(units.labelled("s, distance along the die from where the workpiece meets it", "length"))
    ax.set_ylabel(units.labelled(", ".join(names[key][0] for key in shown), "stress"))
    ax.set_title(f"{title}: {run_settings(scene)}\nstresses on the die", fontsize=9)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    shape.plot(profile["x"], profile["y"], "k.", markersize=1.5, label="nodes of Gamma3")
    shape.set_xlabel(units.labelled("x, along the axis", "length"))
    size = "radius" if scene.geometry.axisymmetric else "half-thickness"
    shape.set_ylabel(units.labelled(size, "length"))
    shape.set_ylim(bottom=0.0)
    shape.set_title("die profile", fontsize=9)
    shape.grid(True, alpha=0.3)
    shape.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=130)
    plt.close(fig)
    return path


def write_exit_profile_plot(profile: dict, path: Path, title: str, label: str, dimension: str,
                           units: Units, reference: tuple[str, float] | None = None) -> Path:
    """exit_<quantity>.png: a quantity across the product against y (the hardness or temperature
    profile), with a reference level (``(label, value)``: the ideal strain, the inflow
    temperature); the strain's profile (postprocess.exit_strain_profile) also shows the strain
    traced along the streamlines and the transported field, and shades the outermost elements,
    across which the written profile takes its mean (docs/hardening.md)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 4.5))
    strain = "surface_layer" in profile
    if strain:  # a layer at the surface is not resolved
        surface = profile["y"][-1]
        ax.axvspan(surface - profile["surface_layer"], surface, color="0.88",
                   label="the outermost elements: the written value is their mean")
        ax.plot(profile["y"], profile["transported"], "--", color="tab:orange",
                label=f"transported {label} (FE field)")
        ax.plot(profile["y"], profile["streamlines"], "-", color="0.5", linewidth=0.8,
                label=f"{label} along the streamlines")
    ax.plot(profile["y"], profile["values"], "b.-",
            label=f"{label}: the written profile (CSV)" if strain else f"FE {label}")
    if reference is not None:
        ax.axhline(reference[1], color="k", linestyle="--", label=f"{reference[0]} = {reference[1]:.4g}")
    ax.set_xlabel(units.labelled("y, from the axis to the surface of the product", "length"))
    ax.set_ylabel(units.labelled(label, dimension))
    ax.set_title(f"{title}: {label} across the product")
    if dimension != "temperature":
        ax.set_ylim(bottom=0.0)
    ax.grid(True, alpha=0.3)
    ax.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=130)
    plt.close(fig)
    return path

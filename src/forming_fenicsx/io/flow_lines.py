"""Flow lines and time lines of a steady flow, as a grid-marker experiment shows them: material
points carried by the nodal velocity from seeds across the entry section."""
from __future__ import annotations

import numpy as np

from forming_fenicsx.post.streamlines import rk4_step

FLOW_LINES = 10  # flow lines from the centres of as many equal bands across the entry section
# material points per band on each time line to start with (even: a band's centre is one)
PER_BAND = 8
MAX_GAP = 0.5  # band widths between neighbouring points of a time line before seeds are added
REFINEMENTS = 6  # rounds of added seeds (each halves the spacing where the points drift apart)
MAX_SEEDS = 4000


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


def _drift(a: np.ndarray, b: np.ndarray, every: int) -> float:
    """The largest distance between two paths' points at the time lines' instants both reach."""
    shared = min(len(a), len(b))
    marks = np.arange(every, shared, every)
    if len(marks) == 0:
        return 0.0
    return float(np.linalg.norm(a[marks] - b[marks], axis=1).max())

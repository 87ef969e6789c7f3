"""The free surfaces made streamlines of the flow (v.n = 0): the product's after the die and
where the contact with the die ends, the stock's before a drawing die and where the contact starts.

In 2D a free surface y(x) is a streamline (x along the axis, y the half-size or radius). Since the
axis is one too, the flux between them is the same through every section: the surface is the
level F(x, y) = int_0^y u_x w dy' = F(x0, y0) of the flux from the axis (w = y' axisymmetric, 1 in
plane strain) through the point (x0, y0) where the contact ends (flux_surface). F is integrated
across each of STEPS_PER_CELL sections per element along x, and the level found on it by Newton's
method on Hermite's cubic (F and its derivative u_x w are known at the samples). Where the contact
ends at a corner toward which the mesh is graded, the first sections and their samples are as
much closer (the corner's velocity turns within its small elements: sampled at the nominal
spacing, the level there missed the flux and the product came out up to 1.3 % too thin,
docs/free_surface.md). The velocity is evaluated through the mesh's columns (columns.py). The
slope dy/dx = v_y/v_x is not integrated: at a sticking wall's corner, where the contact may end,
the velocity vanishes and its direction is noise (docs/free_surface.md).

The product's surface starts where the contact with the die ends: the last node of the die with
positive contact pressure (a contact whose pressure would be tensile has released, and the
penalty's pressure is zero where the workpiece moves away from the die). A surface that would
enter the die after that lies on the wall instead (the contact goes on), and leaves it where the
streamline from the wall turns inward.

The stock's surface before a drawing die is the streamline from the entry face's edge (x = 0,
y = h0): the flux level of the whole throughput (updated_stock). Where flow crossed the stock's
surface into the workpiece, that streamline passes under the die wall at the contact start, by the
height of the flux that crossed; continued at its slope it meets the wall further on. Where it
rose over the wall before the contact start, it meets the wall there. The contact start moves
toward that meeting point: half way at the first update, then by the secant step on the meeting
point's offset (the offset falls as the start moves on), at most an element an update. The surface
is the streamline up to the old start, then Hermite's cubic tangent to it and to the wall at the
new start: the velocity there is along both. A bulge above the stock's size is kept as drawn.
A soft stock narrows before the die over a length that does not shrink with the mesh; on a
perfectly plastic stock the dip is the die entry's velocity jump smeared over elements, and the
contact start tends to the die entry as the mesh is refined (docs/free_surface.md).
"""
from __future__ import annotations

import math
from typing import Callable

import dolfinx.fem
import numpy as np

from forming_fenicsx.config.die_profile import DieProfile
from forming_fenicsx.fem.forms import FlowProblem
from forming_fenicsx.mesh.free_shape import FreeShape, clipped, onto_wall, wall_height
from forming_fenicsx.mesh.columns import ColumnValues
from forming_fenicsx.post.surface_least_squares import StandingSurface, least_squares_surface

STEPS_PER_CELL = 4
# the growth of the stations' spacing from a graded corner (flux_surface)
GROWTH = 1.25
# contact ends within this fraction of an element of a wall corner are moved onto it
SNAP = 0.5
# the contact start moves by this fraction of the way to where the stock's streamline meets the
# wall until a secant step exists (a fixed fraction of 1 did not settle on an annealed rod, 0.7
# swung, docs/free_surface.md), and by at most MAX_SHIFT elements an update (2 took the rod 4
# updates instead of 3 and left an annealed strip crossed by 0.22 % instead of 0.073 %)
STOCK_RELAXATION = 0.5
MAX_SHIFT = 1.0
# a contact start within this fraction of an element of a wall corner is moved onto it
START_SNAP = 0.05


class SurfaceNotFound(ValueError):
    """No streamline from the start passes a station: the flow at the top boundary stands or runs
    back there (u_x <= 0) while the level lies beyond it; ``cause``: what that likely is."""

    def __init__(self, message: str,
                 cause: str = "a bulge or a dead zone, which the update does not follow"):
        super().__init__(message)
        self.cause = cause


def flux_surface(u: dolfinx.fem.Function, top: Callable[[np.ndarray], np.ndarray],
                 start: tuple[float, float], end_x: float, step: float, axisymmetric: bool,
                 wall: DieProfile | None = None, grading: float = 1.0, toward_end: bool = False
                 ) -> tuple[np.ndarray, float | None]:
    """The surface y(x) under which the flux of u equals the flux at ``start``'s section,
    F(x, y) = int_0^y u_x w dy' = F(x0, y0) (w = y' axisymmetric, 1 in plane strain): the
    streamline through the start for a divergence-free u, at stations about ``step`` apart in x to
    x = ``end_x``. F is integrated by Simpson's rule at samples as far apart as the stations there
    (or closer) from the axis to the current top boundary ``top(x)``, and beyond it with u_x held
    at its value there. ``grading``: the mesh is that much finer at the start (a die corner graded
    by discretisation.corner_grading), and so are the first stations and their samples
    (_stations). With ``wall``, a point past the die wall is put back onto it.
    Returns the points (N, 2) and the last x put on the wall (None if none was); raises
    SurfaceNotFound where the level lies beyond the top and u_x there is not positive (on every
    rank alike). Collective."""
    xs, spacings = _stations(start[0], end_x, step, grading, toward_end)
    heights = np.maximum(top(xs), start[1])
    # per station an even number of equal intervals (Simpson) no longer than its spacing
    cells = np.maximum(2, 2 * np.ceil(heights / np.minimum(spacings, step) / 2)).astype(int)
    ys = _samples(heights, cells)
    valid = np.arange(ys.shape[1]) <= cells[:, None]
    points = np.column_stack([np.repeat(xs, cells + 1), ys[valid]])
    values, _ = ColumnValues(u).evaluate(points, outside="column")
    along = np.zeros_like(ys)
    along[valid] = values[:, 0]
    cumulative, integrand = _sections(ys, along, cells, axisymmetric)
    first = _level(start[1], ys[0, :cells[0] + 1], cumulative[0, :cells[0] + 1],
                   integrand[0, :cells[0] + 1])
    rows = np.arange(len(xs))
    total, at_top = cumulative[rows, cells], along[rows, cells]
    inside = total >= first
    standing = ~inside & (at_top <= 0.0)
    if standing.any():
        i = int(np.argmax(standing))
        raise SurfaceNotFound(
            f"the flow along the surface stands or runs back at x = {xs[i]:.6g} (u_x = "
            f"{at_top[i]:.3g}), and the streamline from x = {start[0]:.6g} would pass over it")
    found = _roots(first, ys, np.where(valid, cumulative, np.inf), integrand, cells)
    rest = (first - total[~inside]) / at_top[~inside]  # beyond the top, u_x as at the top
    found[~inside] = (np.sqrt(heights[~inside] ** 2 + 2 * rest) if axisymmetric
                      else heights[~inside] + rest)
    found[0] = start[1]
    line = np.column_stack([xs, found])
    return line, None if wall is None else onto_wall(line, wall)


def streamline(problem: FlowProblem, top: Callable[[np.ndarray], np.ndarray],
               start: tuple[float, float], end_x: float, grading: float = 1.0,
               toward_end: bool = False, wall: DieProfile | None = None
               ) -> tuple[np.ndarray, float | None]:
    """The streamline of the problem's velocity from ``start`` to x = ``end_x`` at stations
    STEPS_PER_CELL an element (graded as _stations), by the scene's free_surface.method: the flux
    level (flux_surface) or the least-squares surface (surface_least_squares.py, from the
    current top boundary ``top``). Returns as flux_surface."""
    scene = problem.scene
    g, step = scene.geometry, scene.discretisation.mesh_size / STEPS_PER_CELL
    if scene.free_surface.method == "least_squares":
        xs, _ = _stations(start[0], end_x, step, grading, toward_end)
        try:
            return least_squares_surface(problem.u, xs, start, top, g.axisymmetric,
                                         scene.discretisation.degree, wall)
        except StandingSurface as error:
            if error.x - start[0] > scene.discretisation.mesh_size:
                raise SurfaceNotFound(str(error)) from error
            raise SurfaceNotFound(
                f"{error}, within an element of where the contact ends (x = {start[0]:.6g})",
                "at a sticking wall's corner the velocity vanishes and its direction, which the "
                "least-squares surface takes its slope from, is noise; free_surface.method = "
                '"flux_level" takes the flux under the wall there') from error
    return flux_surface(problem.u, top, start, end_x, step, g.axisymmetric, wall, grading,
                        toward_end)


def _stations(start: float, end: float, step: float, grading: float, toward_end: bool = False
              ) -> tuple[np.ndarray, np.ndarray]:
    """Stations from ``start`` to ``end`` about ``step`` apart, the first (the last
    ``toward_end``) ``step / grading`` apart and growing by GROWTH a station to ``step`` (uniform
    for ``grading`` 1); and the spacing at each (the larger of the intervals it bounds)."""
    if toward_end:
        xs, spacings = _stations(-end, -start, step, grading)
        return -xs[::-1], spacings[::-1]
    count = max(1, math.ceil((end - start) / step))
    if grading <= 1.0:
        xs = np.linspace(start, end, count + 1)
    else:
        near, x, length = [start], start, step / grading
        while length < step and x + length < end:
            x += length
            near.append(x)
            length *= GROWTH
        rest = max(1, math.ceil((end - x) / step))
        xs = np.concatenate([near, np.linspace(x, end, rest + 1)[1:]])
    gaps = np.diff(xs)
    return xs, np.maximum(np.append(gaps, gaps[-1]), np.insert(gaps, 0, gaps[0]))


def _samples(heights: np.ndarray, cells: np.ndarray) -> np.ndarray:
    """Each station's ``cells + 1`` equally spaced samples from the axis to its height (as
    np.linspace), one station a row, the rows padded with zeros to the longest."""
    index = np.arange(int(cells.max()) + 1)
    fractions = np.where(index <= cells[:, None], index * (1.0 / cells[:, None]), 0.0)
    fractions[np.arange(len(cells)), cells] = 1.0
    return heights[:, None] * fractions


def _sections(ys: np.ndarray, along: np.ndarray, cells: np.ndarray, axisymmetric: bool
              ) -> tuple[np.ndarray, np.ndarray]:
    """F and its derivative u_x w at the stations' samples (_samples' rows, ``cells`` intervals
    each): F at the even samples by Simpson's rule from the axis, at the odd ones by the trapezoid
    rule. Past a row's last sample the values are not used."""
    integrand = along * (ys if axisymmetric else 1.0)
    spacing = ys[:, 1:2] - ys[:, 0:1]
    pairs = (integrand[:, :-2:2] + 4 * integrand[:, 1:-1:2] + integrand[:, 2::2]) / 3
    cumulative = np.zeros_like(integrand)
    cumulative[:, 2::2] = np.cumsum(pairs, axis=1) * spacing
    trapezoids = 0.5 * spacing * (integrand[:, :-1:2] + integrand[:, 1::2])
    cumulative[:, 1::2] = cumulative[:, :-1:2] + trapezoids
    return cumulative, integrand


def _hermite(t: float, h: float, f0: float, f1: float, d0: float, d1: float) -> tuple[float, float]:
    """The cubic with values f0, f1 and slopes d0, d1 at the ends of an interval of length h, and
    its slope, at the fraction t of it."""
    h00, h10, h01, h11 = (2 * t**3 - 3 * t**2 + 1, t**3 - 2 * t**2 + t, -2 * t**3 + 3 * t**2,
                          t**3 - t**2)
    value = h00 * f0 + h10 * h * d0 + h01 * f1 + h11 * h * d1
    slope = ((6 * t**2 - 6 * t) * f0 + (3 * t**2 - 4 * t + 1) * h * d0
             + (-6 * t**2 + 6 * t) * f1 + (3 * t**2 - 2 * t) * h * d1) / h
    return value, slope


def _level(y: float, ys: np.ndarray, flux: np.ndarray, rate: np.ndarray) -> float:
    """F(y) from the samples of F and of its derivative f at ys (Hermite's cubic)."""
    j = min(max(int(np.searchsorted(ys, y)) - 1, 0), len(ys) - 2)
    h = ys[j + 1] - ys[j]
    return _hermite((y - ys[j]) / h, h, flux[j], flux[j + 1], rate[j], rate[j + 1])[0]


def _roots(level: float, ys: np.ndarray, flux: np.ndarray, rate: np.ndarray, cells: np.ndarray
           ) -> np.ndarray:
    """Per station (a row of the samples ys, ``cells`` intervals) the y where F = level, F
    increasing, from the samples of F (padded with inf) and of its derivative f: Newton's method on
    Hermite's cubic in the bracketing interval, from the linear guess."""
    rows = np.arange(len(ys))
    j = np.minimum(np.maximum(np.sum(flux < level, axis=1) - 1, 0), cells - 1)
    h, low, high = ys[rows, j + 1] - ys[rows, j], flux[rows, j], flux[rows, j + 1]
    d0, d1 = rate[rows, j], rate[rows, j + 1]
    t = np.where(high > low, (level - low) / np.where(high > low, high - low, 1.0), 0.5)
    going = np.ones(len(ys), dtype=bool)
    for _ in range(8):
        value, slope = _hermite(t, h, low, high, d0, d1)
        going &= slope > 0
        t = np.where(going, np.clip(t - (value - level) / np.where(going, slope * h, 1.0), 0.0,
                                    1.0), t)
    return ys[rows, j] + t * h


def updated_stock(problem: FlowProblem, shape: FreeShape
                  ) -> tuple[np.ndarray, float, float, tuple[float, float]]:
    """The stock's surface before a drawing die made the streamline of the flow from the entry
    face's edge (x = 0, y = h0), and the contact start moved toward where that streamline meets the
    die wall (module docstring). Returns the surface, from x = 0 to the wall at the new contact
    start, that start, how far under the wall the streamline passed the old one (the flux that
    crossed the stock's surface, as a height), and the old start with how far the streamline's
    meeting point lay from it. Collective."""
    scene = problem.scene
    g, size = scene.geometry, scene.discretisation.mesh_size
    die, h0, start = g.profile(), 0.5 * g.entry_thickness, shape.wall.start[0]
    line, _ = streamline(problem, shape.height, (0.0, h0), start,
                         grading=scene.discretisation.corner_grading, toward_end=True)
    x, y = line[:, 0], np.minimum(line[:, 1], h0)  # a bulge above the stock is kept as drawn
    wall = np.array([wall_height(die, xi) for xi in x])
    gap = wall[-1] - y[-1]
    back = x[-1] - size / STEPS_PER_CELL  # the streamline's slope at the contact start, over a
    # station's nominal spacing
    slope = (y[-1] - np.interp(back, x, y)) / (x[-1] - back)
    if gap > 0:  # under the wall by the flux that crossed the stock's surface: continued at its
        # slope, the streamline meets the wall where the gap closes
        closing = slope - _wall_slope(die, start, size)
        target = start + gap / closing if closing > 0 else math.inf
    else:  # the streamline meets the wall before the contact start: there (linearly between
        # the stations)
        below = wall - y
        i = int(np.argmax((x >= die.start[0]) & (below <= 0)))
        t = below[i - 1] / (below[i - 1] - below[i]) if i > 0 and below[i - 1] > 0 else 1.0
        target = float(x[i - 1] + t * (x[i] - x[i - 1])) if i > 0 else float(x[i])
    moved = _next_start(start, target - start, shape.stock_step, size)
    moved = max(min(moved, die.land_start - size), die.start[0])
    keep = x < min(moved, start) - 1e-9 * size
    surface = np.column_stack([x[keep], np.where(x[keep] >= die.start[0],
                                                 np.minimum(y[keep], wall[keep]), y[keep])])
    join = [(moved, wall_height(die, moved))]
    if moved > start:  # Hermite's cubic from the streamline's end to the wall, tangent to both:
        # the velocity at the contact start is along the wall and along the free surface
        h, wall_slope = moved - start, _wall_slope(die, moved, size)
        ts = np.linspace(0.0, 1.0, max(2, math.ceil(h * STEPS_PER_CELL / size)) + 1)
        join = [(start + t * h, _hermite(t, h, y[-1], join[0][1], slope, wall_slope)[0])
                for t in ts]
    return np.vstack([surface, join]), moved, float(gap), (start, target - start)


def _wall_slope(die: DieProfile, x: float, size: float) -> float:
    """The die wall's slope dy/dx just after x: over half an element, or to the land's start."""
    ahead = min(x + 0.5 * size, die.land_start)
    return (wall_height(die, ahead) - wall_height(die, x)) / max(ahead - x, 1e-300)


def _next_start(start: float, residual: float, previous: tuple[float, float] | None,
                size: float) -> float:
    """The next contact start from the meeting point's offset ``residual`` at ``start`` (infinite:
    the streamline never meets the wall): the secant step on r(c) = 0 through the previous
    update's (c, r), where r falls as c rises, else STOCK_RELAXATION of the offset; at most
    MAX_SHIFT elements."""
    step = STOCK_RELAXATION * residual
    if previous is not None and previous[0] != start and math.isfinite(residual + previous[1]):
        slope = (residual - previous[1]) / (start - previous[0])
        if slope < 0:
            step = -residual / slope
    return start + min(max(step, -MAX_SHIFT * size), MAX_SHIFT * size)


def updated_shape(problem: FlowProblem, shape: FreeShape, contact_end_x: float | None
                  ) -> FreeShape:
    """The product's surface made the streamline of the problem's velocity from where the contact
    with the die ends (flux_surface, module docstring), the square die's corner for its die; a
    drawing die's stock surface and contact start updated too (updated_stock), an extrusion's
    contact start kept.
    Collective (every rank returns the same shape)."""
    scene = problem.scene
    g = scene.geometry
    size = scene.discretisation.mesh_size
    if shape.wall is None:  # the square die: the product leaves its face at the corner
        corner = tuple(shape.downstream[0])
        line, _ = streamline(problem, shape.height, corner, g.length,
                             grading=scene.discretisation.corner_grading)
        return FreeShape(None, line)
    die, disc = g.profile(), scene.discretisation
    upstream, start, gap, step = None, shape.wall.start[0], 0.0, None
    if scene.process.kind == "drawing":
        upstream, start, gap, step = updated_stock(problem, shape)
    end = min(max(contact_end_x, start), die.end[0])
    # a contact end within SNAP elements of a corner of the wall starts there (as clipped's), where
    # the mesh is graded: by corner_grading at the die's exit, by wall_grading at another corner
    corner = min([s.start[0] for s in die.segments] + [die.end[0]], key=lambda c: abs(c - end))
    grading = 1.0
    if abs(corner - end) <= SNAP * size:
        end, grading = corner, disc.corner_grading if corner == die.end[0] else disc.wall_grading
    line, last = streamline(problem, shape.height, (end, wall_height(die, end)), g.length,
                            grading, wall=die)
    if last is not None and last > end + size:  # the product would enter the die after an
        # element (within one, the penalty's own penetration): the contact goes on
        end = last
        line = line[line[:, 0] >= end]
    # the stock's contact start moves by less than an element: snapped to the die entry it would
    # not move at all
    wall = clipped(die, start, end, SNAP * size, START_SNAP * size)
    downstream = np.vstack([wall.end, line[line[:, 0] > wall.end[0] + 1e-9 * size]])
    if upstream is not None:  # the stock's surface ends where the clipped wall starts
        upstream = np.vstack([upstream[upstream[:, 0] < wall.start[0] - 1e-9 * size],
                              wall.start])
    return FreeShape(wall, downstream, upstream, abs(gap), step)


def shape_change(old: FreeShape, new: FreeShape, length: float, points: int = 2001) -> float:
    """The largest difference in y between two top boundaries over x in [0, length]."""
    x = np.linspace(0.0, length, points)
    return float(np.max(np.abs(new.height(x) - old.height(x))))

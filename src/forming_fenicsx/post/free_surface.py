"""The product's free surface made a streamline of the flow (v.n = 0), and where the contact ends.

In 2D a free surface y(x) is a streamline (x along the axis, y the half-size or radius). Since the
axis is one too, the flux between them is the same through every section: the surface is the
level F(x, y) = int_0^y u_x w dy' = F(x0, y0) of the flux from the axis (w = y' axisymmetric, 1 in
plane strain) through the point (x0, y0) where the contact ends (flux_surface). F is integrated
across each of STEPS_PER_CELL sections per element along x, and the level found on it by Newton's
method on Hermite's cubic (F and its derivative u_x w are known at the samples). Where the contact
ends at a corner toward which the mesh is graded, the first sections and their samples are as
much closer (the corner's velocity turns within its small elements: sampled at the nominal
spacing, the level there missed the flux and the product came out up to 1.3 % too thin,
docs/free_surface.md). The velocity is
evaluated by points.py. The slope dy/dx = v_y/v_x is not integrated: at a sticking wall's
corner, where the contact may end, the velocity vanishes and its direction is noise
(docs/free_surface.md).

The product's surface starts where the contact with the die ends: the last node of the die with
positive contact pressure (a contact whose pressure would be tensile has released, and the
penalty's pressure is zero where the workpiece moves away from the die). A surface that would
enter the die after that lies on the wall instead (the contact goes on), and leaves it where the
streamline from the wall turns inward. The stock's surface before a drawing die is kept as the
scene draws it (docs/free_surface.md: in the finite-element flow it dips before the die entry over
elements that shrink with the mesh, the die entry's velocity jump smeared, and moving the contact
start after it does not settle).
"""
from __future__ import annotations

import math
from typing import Callable

import dolfinx.fem
import numpy as np

from forming_fenicsx.config.die_profile import DieProfile
from forming_fenicsx.fem.forms import FlowProblem
from forming_fenicsx.mesh.free_shape import FreeShape, clipped, wall_height
from forming_fenicsx.mesh.points import PointValues

STEPS_PER_CELL = 4
# the growth of the stations' spacing from a graded corner (flux_surface)
GROWTH = 1.25
# contact ends within this fraction of an element of a wall corner are moved onto it
SNAP = 0.5


def flux_surface(u: dolfinx.fem.Function, top: Callable[[np.ndarray], np.ndarray],
                 start: tuple[float, float], end_x: float, step: float, axisymmetric: bool,
                 wall: DieProfile | None = None, grading: float = 1.0
                 ) -> tuple[np.ndarray, float | None]:
    """The surface y(x) under which the flux of u equals the flux at ``start``'s section,
    F(x, y) = int_0^y u_x w dy' = F(x0, y0) (w = y' axisymmetric, 1 in plane strain): the
    streamline through the start for a divergence-free u, at stations about ``step`` apart in x to
    x = ``end_x``. F is integrated by Simpson's rule at samples as far apart as the stations there
    (or closer) from the axis to the current top boundary ``top(x)``, and beyond it with u_x held
    at its value there. ``grading``: the mesh is that much finer at the start (a die corner graded
    by discretisation.corner_grading), and so are the first stations and their samples
    (_stations). With ``wall``, a point past the die wall is put back onto it.
    Returns the points (N, 2) and the last x put on the wall (None if none was). Collective."""
    xs, spacings = _stations(start[0], end_x, step, grading)
    heights = np.maximum(top(xs), start[1])
    # per station an even number of equal intervals (Simpson) no longer than its spacing
    cells = np.maximum(2, 2 * np.ceil(heights / np.minimum(spacings, step) / 2)).astype(int)
    ys = [height * np.linspace(0.0, 1.0, n + 1) for height, n in zip(heights, cells)]
    points = np.column_stack([np.repeat(xs, cells + 1), np.concatenate(ys)])
    values, _ = PointValues([u]).evaluate(points, outside="extend")
    along = np.split(values[:, 0], np.cumsum(cells + 1)[:-1])
    samples = [_section(y, a, axisymmetric) for y, a in zip(ys, along)]
    first = _level(start[1], ys[0], *samples[0])
    found = np.empty(len(xs))
    for i, (cumulative, integrand) in enumerate(samples):
        total = cumulative[-1]
        if total >= first:
            found[i] = _root(first, ys[i], cumulative, integrand)
        else:  # beyond the top, u_x as at the top
            rest = (first - total) / along[i][-1]
            found[i] = (math.sqrt(heights[i] ** 2 + 2 * rest) if axisymmetric
                        else heights[i] + rest)
    found[0] = start[1]
    on_wall = None
    if wall is not None:
        for i in range(1, len(xs)):
            if wall.start[0] <= xs[i] <= wall.end[0]:
                limit = wall_height(wall, xs[i])
                if found[i] > limit:
                    found[i], on_wall = limit, xs[i]
    return np.column_stack([xs, found]), on_wall


def _stations(start: float, end: float, step: float, grading: float
              ) -> tuple[np.ndarray, np.ndarray]:
    """Stations from ``start`` to ``end`` about ``step`` apart, the first ``step / grading`` apart
    and growing by GROWTH a station to ``step`` (uniform for ``grading`` 1); and the spacing at
    each (the larger of the intervals it bounds)."""
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


def _section(ys: np.ndarray, along: np.ndarray, axisymmetric: bool
             ) -> tuple[np.ndarray, np.ndarray]:
    """F and its derivative u_x w at the equally spaced samples ys of one station: F at the even
    samples by Simpson's rule from the axis, at the odd ones by the trapezoid rule."""
    integrand = along * (ys if axisymmetric else 1.0)
    spacing = ys[1] - ys[0]
    pairs = (integrand[:-2:2] + 4 * integrand[1:-1:2] + integrand[2::2]) / 3
    cumulative = np.zeros_like(integrand)
    cumulative[2::2] = np.cumsum(pairs) * spacing
    cumulative[1::2] = cumulative[:-1:2] + 0.5 * spacing * (integrand[:-1:2] + integrand[1::2])
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


def _root(level: float, ys: np.ndarray, flux: np.ndarray, rate: np.ndarray) -> float:
    """The y where F = level, F increasing, from the samples of F and of its derivative f at ys:
    Newton's method on Hermite's cubic in the bracketing interval, from the linear guess."""
    j = min(max(int(np.searchsorted(flux, level)) - 1, 0), len(ys) - 2)
    h, low, high = ys[j + 1] - ys[j], flux[j], flux[j + 1]
    t = (level - low) / (high - low) if high > low else 0.5
    for _ in range(8):
        value, slope = _hermite(t, h, low, high, rate[j], rate[j + 1])
        if slope <= 0:
            break
        t = min(max(t - (value - level) / (slope * h), 0.0), 1.0)
    return ys[j] + t * h


def updated_shape(problem: FlowProblem, shape: FreeShape, contact_end_x: float | None
                  ) -> FreeShape:
    """The product's surface made the streamline of the problem's velocity from where the contact
    with the die ends (flux_surface, module docstring), the square die's corner for its die;
    ``shape``'s contact start is kept.
    Collective (every rank returns the same shape)."""
    scene = problem.scene
    g = scene.geometry
    size = scene.discretisation.mesh_size
    if shape.wall is None:  # the square die: the product leaves its face at the corner
        corner = tuple(shape.downstream[0])
        line, _ = flux_surface(problem.u, shape.height, corner, g.length, size / STEPS_PER_CELL,
                               g.axisymmetric, grading=scene.discretisation.corner_grading)
        return FreeShape(None, line)
    die, disc = g.profile(), scene.discretisation
    end = min(max(contact_end_x, shape.wall.start[0]), die.end[0])
    # a contact end within SNAP elements of a corner of the wall starts there (as clipped's), where
    # the mesh is graded: by corner_grading at the die's exit, by wall_grading at another corner
    corner = min([s.start[0] for s in die.segments] + [die.end[0]], key=lambda c: abs(c - end))
    grading = 1.0
    if abs(corner - end) <= SNAP * size:
        end, grading = corner, disc.corner_grading if corner == die.end[0] else disc.wall_grading
    line, last = flux_surface(problem.u, shape.height, (end, wall_height(die, end)), g.length,
                              size / STEPS_PER_CELL, g.axisymmetric, die, grading)
    if last is not None and last > end + size:  # the product would enter the die after an
        # element (within one, the penalty's own penetration): the contact goes on
        end = last
        line = line[line[:, 0] >= end]
    wall = clipped(die, shape.wall.start[0], end, SNAP * size)
    downstream = np.vstack([wall.end, line[line[:, 0] > wall.end[0] + 1e-9 * size]])
    return FreeShape(wall, downstream)


def shape_change(old: FreeShape, new: FreeShape, length: float, points: int = 2001) -> float:
    """The largest difference in y between two top boundaries over x in [0, length]."""
    x = np.linspace(0.0, length, points)
    return float(np.max(np.abs(new.height(x) - old.height(x))))

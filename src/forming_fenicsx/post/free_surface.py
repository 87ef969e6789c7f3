"""The product's free surface made a streamline of the flow (v.n = 0), and where the contact ends.

In 2D a free surface y(x) is a streamline: dy/dx = v_y/v_x (x along the axis, y the half-size or
radius: the same in plane strain and axisymmetric). It is integrated by classical Runge-Kutta with
STEPS_PER_CELL steps per element along x, the finite-element velocity evaluated at the stages
(points.py; past the boundary, the nearest cell's polynomial extended).

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
# contact ends within this fraction of an element of a wall corner are moved onto it
SNAP = 0.5


def slope_field(u: dolfinx.fem.Function) -> Callable[[np.ndarray], np.ndarray]:
    """dy/dx = v_y/v_x of a 2D velocity at points (N, 2): a column of slopes (collective)."""
    values = PointValues([u])

    def slope(xy: np.ndarray) -> np.ndarray:
        v, _ = values.evaluate(np.atleast_2d(xy), outside="extend")
        return v[:, 1] / v[:, 0]

    return slope


def streamline(slope: Callable[[np.ndarray], np.ndarray], start: tuple[float, float],
               end_x: float, step: float, wall: DieProfile | None = None
               ) -> tuple[np.ndarray, float | None]:
    """The streamline from ``start`` to x = ``end_x`` (points (N, 2)) by RK4 steps of about
    ``step`` in x; with ``wall``, a point past the die wall (within its x range) is put back onto
    it (the surface slides along the die). Returns the points and the last x put on the wall
    (None if none was)."""
    count = max(1, math.ceil((end_x - start[0]) / step))
    xs = np.linspace(start[0], end_x, count + 1)
    ys = np.empty(count + 1)
    ys[0] = start[1]
    on_wall = None

    def f(x: float, y: float) -> float:
        return float(slope(np.array([[x, y]]))[0])

    for i in range(count):
        x, y, h = xs[i], ys[i], xs[i + 1] - xs[i]
        k1 = f(x, y)
        k2 = f(x + 0.5 * h, y + 0.5 * h * k1)
        k3 = f(x + 0.5 * h, y + 0.5 * h * k2)
        k4 = f(x + h, y + h * k3)
        y = y + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        if wall is not None and wall.start[0] <= xs[i + 1] <= wall.end[0]:
            limit = wall_height(wall, xs[i + 1])
            if y > limit:
                y, on_wall = limit, xs[i + 1]
        ys[i + 1] = y
    return np.column_stack([xs, ys]), on_wall


def updated_shape(problem: FlowProblem, shape: FreeShape, contact_end_x: float) -> FreeShape:
    """The product's surface made the streamline of the problem's velocity from where the contact
    with the die ends (module docstring); ``shape``'s contact start is kept.
    Collective (every rank returns the same shape)."""
    scene = problem.scene
    g = scene.geometry
    die = g.profile()
    size = scene.discretisation.mesh_size
    end = min(max(contact_end_x, shape.wall.start[0]), die.end[0])
    line, last = streamline(slope_field(problem.u), (end, wall_height(die, end)), g.length,
                            size / STEPS_PER_CELL, die)
    if last is not None and last > end + size:  # the product would enter the die after an
        # element (within one, the penalty's own penetration): the contact goes on
        end = last
        line = line[line[:, 0] >= end]
    wall = clipped(die, shape.wall.start[0], end, SNAP * size)
    downstream = np.vstack([wall.end, line[line[:, 0] > wall.end[0] + 1e-9 * size]])
    return FreeShape(wall, downstream)


def relaxed(old: FreeShape, new: FreeShape, relaxation: float) -> FreeShape:
    """``new`` with its product surface moved only ``relaxation`` of the way from ``old``'s,
    y = y_old + relaxation (y_new - y_old) at the new surface's x, from where its contact ends
    (that point stays on the wall)."""
    if relaxation == 1.0:
        return new
    downstream = new.downstream.copy()
    x = downstream[1:, 0]
    downstream[1:, 1] = old.height(x) + relaxation * (downstream[1:, 1] - old.height(x))
    return FreeShape(new.wall, downstream)


def shape_change(old: FreeShape, new: FreeShape, length: float, points: int = 2001) -> float:
    """The largest difference in y between two top boundaries over x in [0, length]."""
    x = np.linspace(0.0, length, points)
    return float(np.max(np.abs(new.height(x) - old.height(x))))

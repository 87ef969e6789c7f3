"""The top boundary of a 2D workpiece whose free surfaces the flow decides (app/free_surface.py):
the stock's free surface before a drawing die, from the entry face to where contact starts, the
die wall where the workpiece touches it, to where contact ends, then the product's free surface to
the exit face. The container (extrusion) stays as the scene draws it, and so does the square die's
face (Example 1), whose product leaves it at the die corner. mesh/geometry.py meshes it as the
scene's own blocks, the stock's and the product's nodes moved onto their surfaces (shaped_mesh).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from forming_fenicsx.config.die_profile import DieProfile, Segment
from forming_fenicsx.config.scene import Scene


@dataclass(frozen=True)
class FreeShape:
    """``wall``: the die wall in contact (None: the square die, its face as drawn);
    ``downstream`` (M, 2): the product's free surface from the end of contact to the exit face
    x = L; ``upstream`` (K, 2): the stock's free surface from the entry face x = 0 to the start of
    contact (None: level at the stock's size up to the die, as drawn); ``stock_miss``: how far the
    stock's streamline of the flow this shape was made from passed under (or over) the wall at
    that flow's contact start (post/free_surface.updated_stock), zero at a steady stock, and
    ``stock_step`` that flow's contact start with how far from it the streamline met the wall."""

    wall: DieProfile | None
    downstream: np.ndarray
    upstream: np.ndarray | None = None
    stock_miss: float = 0.0
    stock_step: tuple[float, float] | None = None

    def height(self, x: np.ndarray) -> np.ndarray:
        """The top boundary's y at x along the stock's surface, the wall and the product's surface
        (the first of them extended level before its start)."""
        stock = [] if self.upstream is None else [self.upstream]
        wall = [] if self.wall is None else [self.wall.polyline(48)]
        line = np.vstack([*stock, *wall, self.downstream])
        keep = np.concatenate([[True], np.diff(line[:, 0]) > 0])
        return np.interp(x, line[keep, 0], line[keep, 1])

    @property
    def exit_height(self) -> float:
        """The product's half-size at the exit face."""
        return float(self.downstream[-1, 1])


def fixed_shape(scene: Scene) -> FreeShape:
    """The scene's own top boundary: the whole die wall, the product level at the exit size after
    it."""
    g = scene.geometry
    if square_die(scene):
        corner = (g.die_position, 0.5 * g.exit_thickness)
        return FreeShape(None, np.array([corner, (g.length, corner[1])]))
    profile = g.profile()
    return FreeShape(profile, np.array([profile.end, (g.length, 0.5 * g.exit_thickness)]))


def square_die(scene: Scene) -> bool:
    """Whether the scene's die is Example 1's square die (no profile: a face normal to the axis)."""
    return getattr(scene.geometry, "die", "") == "square"


def wall_height(profile: DieProfile, x: float) -> float:
    """The die wall's y at x, extended level beyond its ends."""
    x = min(max(x, profile.start[0]), profile.end[0])
    return profile.radius_at(x)


def onto_wall(line: np.ndarray, wall: DieProfile) -> float | None:
    """The points of a surface (N, 2) after its first that lie past the die ``wall`` put back
    onto it (in place); returns the last x put there, None if none was."""
    on_wall = None
    for i in range(1, len(line)):
        if wall.start[0] <= line[i, 0] <= wall.end[0]:
            limit = wall_height(wall, line[i, 0])
            if line[i, 1] > limit:
                line[i, 1], on_wall = limit, float(line[i, 0])
    return on_wall


def clipped(profile: DieProfile, start: float, end: float, snap: float,
            start_snap: float | None = None) -> DieProfile:
    """The die wall from x = ``start`` to x = ``end``, the ends moved onto a corner of the wall
    (where segments meet) within ``snap`` (the start: ``start_snap``, default ``snap``) of it, so
    that no piece is much shorter than an element."""
    corners = [s.start[0] for s in profile.segments] + [profile.end[0]]

    def snapped(x: float, within: float) -> float:
        nearest = min(corners, key=lambda c: abs(c - x))
        return nearest if abs(nearest - x) <= within else x

    start = snapped(start, snap if start_snap is None else start_snap)
    end = snapped(end, snap)
    pieces = []
    for segment in profile.segments:
        a, b = max(segment.start[0], start), min(segment.end[0], end)
        if b - a <= 1e-12 * max(abs(b), 1.0):
            continue
        pieces.append(Segment((a, profile.radius_at(a)), (b, profile.radius_at(b)),
                              segment.centre))
    return DieProfile(tuple(pieces))


def wall_area(profile: DieProfile, axisymmetric: bool, per_segment: int = 200) -> float:
    """The die wall's length (plane strain) or its area over 2 pi (the integral of y ds,
    axisymmetric), by the trapezoidal rule on ``per_segment`` points of each segment."""
    total = 0.0
    for segment in profile.segments:
        points = segment.points(per_segment)
        ds = np.linalg.norm(np.diff(points, axis=0), axis=1)
        weight = 0.5 * (points[1:, 1] + points[:-1, 1]) if axisymmetric else 1.0
        total += float(np.sum(weight * ds))
    return total

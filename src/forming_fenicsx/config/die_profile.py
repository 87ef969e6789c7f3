"""The die wall of a drawing or conical extrusion die: a chain of straight lines and circular arcs.

Half-model coordinates: x along the axis (the flow direction), y the half-thickness or radius. The
chain runs from where the workpiece meets the die down to the end of the land, with y never rising
(a converging die). It is built from parameters (semi-angle, entry radius, a second angle, land)
or read from a CSV polyline of (x, y) points.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from forming_fenicsx.core.csv_table import read_rows
from forming_fenicsx.core.errors import SceneError

# relative tolerance on the end heights of a CSV profile and on a land being level
LEVEL = 1e-9


@dataclass(frozen=True)
class Segment:
    """A straight line from ``start`` to ``end``, or (``centre`` given) the circular arc between
    them about ``centre``, the shorter way round."""

    start: tuple[float, float]
    end: tuple[float, float]
    centre: tuple[float, float] | None = None

    @property
    def radius(self) -> float:
        return math.dist(self.start, self.centre)

    @property
    def sweep(self) -> float:
        """Angle the arc turns through (radians)."""
        a = np.subtract(self.start, self.centre)
        b = np.subtract(self.end, self.centre)
        return math.acos(max(-1.0, min(1.0, float(a @ b) / (self.radius**2))))

    @property
    def length(self) -> float:
        return math.dist(self.start, self.end) if self.centre is None else self.radius * self.sweep

    def points(self, count: int) -> np.ndarray:
        """``count`` + 1 points along the segment, (count + 1, 2)."""
        t = np.linspace(0.0, 1.0, count + 1)
        if self.centre is None:
            return (1 - t[:, None]) * np.array(self.start) + t[:, None] * np.array(self.end)
        return self._on_arc(t)

    def _turn(self) -> tuple[float, float]:
        """The arc's start angle about its centre and the signed angle it turns through."""
        a0 = math.atan2(self.start[1] - self.centre[1], self.start[0] - self.centre[0])
        a1 = math.atan2(self.end[1] - self.centre[1], self.end[0] - self.centre[0])
        return a0, (a1 - a0 + math.pi) % (2 * math.pi) - math.pi

    def _on_arc(self, t: np.ndarray) -> np.ndarray:
        a0, turn = self._turn()
        angle = a0 + t * turn
        return np.column_stack([self.centre[0] + self.radius * np.cos(angle),
                                self.centre[1] + self.radius * np.sin(angle)])

    def distance_along(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """For points (N, 2): their distance from the segment and the arc length from its start to
        their nearest point on it."""
        if self.centre is None:
            start, chord = np.array(self.start), np.subtract(self.end, self.start)
            t = np.clip((points - start) @ chord / (chord @ chord), 0.0, 1.0)
            foot = start + t[:, None] * chord
            return np.linalg.norm(points - foot, axis=1), t * self.length
        a0, turn = self._turn()
        relative = points - np.array(self.centre)
        angle = np.arctan2(relative[:, 1], relative[:, 0])
        along = np.clip(((angle - a0 + math.pi) % (2 * math.pi) - math.pi) / turn, 0.0, 1.0)
        return np.linalg.norm(points - self._on_arc(along), axis=1), along * self.length


@dataclass(frozen=True)
class DieProfile:
    """The die wall as segments from the die entry (where the workpiece meets it) to the land end.

    ``land_start``: x where the wall reaches the exit half-size h1 (the start of the land, or the
    die exit without one)."""

    segments: tuple[Segment, ...]

    @property
    def start(self) -> tuple[float, float]:
        return self.segments[0].start

    @property
    def end(self) -> tuple[float, float]:
        return self.segments[-1].end

    @property
    def land_start(self) -> float:
        h1 = self.end[1]
        level = [s for s in self.segments if s.centre is None
                 and abs(s.start[1] - h1) <= LEVEL * h1 and abs(s.end[1] - h1) <= LEVEL * h1]
        return min((s.start[0] for s in level), default=self.end[0])

    @property
    def effective_angle(self) -> float:
        """Semi-angle (degrees) of the chord from the die entry to the land: the die's angle for a
        straight cone, the angle a two-angle, radiused or CSV die is compared by."""
        return math.degrees(math.atan2(self.start[1] - self.end[1],
                                       self.land_start - self.start[0]))

    @property
    def length(self) -> float:
        return sum(s.length for s in self.segments)

    def coordinate(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """Arc length along the wall from its start, for points on (or next to) the wall: that of
        each point's nearest point on the nearest segment."""
        points = np.column_stack([x, y])
        offsets = np.cumsum([0.0] + [s.length for s in self.segments[:-1]])
        best = np.full(len(points), np.inf)
        s = np.zeros(len(points))
        for segment, offset in zip(self.segments, offsets, strict=True):
            distance, along = segment.distance_along(points)
            closer = distance < best
            best[closer], s[closer] = distance[closer], offset + along[closer]
        return s

    def radius_at(self, x: float) -> float:
        """The wall's y at axial position x (inside the die)."""
        for segment in self.segments:
            if segment.start[0] <= x <= segment.end[0]:
                if segment.centre is None:
                    t = (x - segment.start[0]) / max(segment.end[0] - segment.start[0], 1e-300)
                    return segment.start[1] + t * (segment.end[1] - segment.start[1])
                cx, cy = segment.centre
                return cy + math.sqrt(max(segment.radius**2 - (x - cx) ** 2, 0.0))
        raise ValueError(f"x = {x} is outside the die ({self.start[0]} to {self.end[0]})")

    def polyline(self, per_arc: int = 24) -> np.ndarray:
        """Points along the wall for plotting and for die.csv, (N, 2)."""
        parts = [s.points(1 if s.centre is None else per_arc) for s in self.segments]
        return np.vstack([parts[0]] + [p[1:] for p in parts[1:]])


def parametric_profile(die_entry: float, h0: float, h1: float, die_angle: float,
                       land_length: float, entry_radius: float = 0.0,
                       second_angle: float | None = None,
                       second_angle_length: float = 0.0) -> DieProfile:
    """The wall of a conical die: an entry cone at ``second_angle`` over the axial length
    ``second_angle_length`` from x = die_entry (optional), the working cone at ``die_angle`` down
    to h1, then the land. ``entry_radius`` rounds the corner at die_entry between the incoming
    surface y = h0 and the first cone by an arc tangent to both: it starts
    t = R tan(beta/2) before die_entry and ends t along the cone (beta the first cone's angle).
    Raises ValueError when the parts do not fit."""
    corners = [(die_entry, h0)]
    if second_angle is not None and second_angle_length > 0:
        drop = second_angle_length * math.tan(math.radians(second_angle))
        if drop >= h0 - h1:
            raise ValueError("the second (entry) cone reaches the exit size: shorten "
                             "second_angle_length")
        corners.append((die_entry + second_angle_length, h0 - drop))
    y = corners[-1][1]
    corners.append((corners[-1][0] + (y - h1) / math.tan(math.radians(die_angle)), h1))
    if land_length > 0:
        corners.append((corners[-1][0] + land_length, h1))
    lines = [Segment(a, b) for a, b in zip(corners[:-1], corners[1:], strict=True)]
    if entry_radius <= 0:
        return DieProfile(tuple(lines))
    first = lines[0]
    beta = math.atan2(first.start[1] - first.end[1], first.end[0] - first.start[0])
    t = entry_radius * math.tan(beta / 2)
    if t >= first.length:
        raise ValueError(f"the entry radius {entry_radius} does not fit on the first cone "
                         f"(tangent length {t:.4g} > {first.length:.4g})")
    arc_start = (die_entry - t, h0)
    arc_end = (die_entry + t * math.cos(beta), h0 - t * math.sin(beta))
    arc = Segment(arc_start, arc_end, (die_entry - t, h0 - entry_radius))
    return DieProfile((arc, Segment(arc_end, first.end), *lines[1:]))


def read_profile_csv(path: str | Path, key: str) -> np.ndarray:
    """The (x, y) rows of a die-profile CSV file (header ``x,y``), (N, 2). Refused, naming ``key``
    and the row: a missing file, fewer than two points, a value that is not a finite number, x not
    increasing, y rising (a diverging die) or y <= 0."""
    name = Path(path).name
    points: list[list[float]] = []
    for number, values in read_rows(path, key, ("x", "y")):
        if values[1] <= 0:
            raise SceneError(key, f"{name} row {number}: y = {values[1]} must be > 0 "
                                  "(the half-size above the axis)")
        if points and values[0] <= points[-1][0]:
            raise SceneError(key, f"{name} row {number}: x = {values[0]} must increase "
                                  f"(previous {points[-1][0]})")
        if points and values[1] > points[-1][1]:
            raise SceneError(key, f"{name} row {number}: y = {values[1]} rises above "
                                  f"{points[-1][1]}: the die must converge")
        points.append(values)
    if len(points) < 2:
        raise SceneError(key, f"{name}: needs at least two points; got {len(points)}")
    return np.array(points)


def polyline_profile(points: np.ndarray) -> DieProfile:
    """A die wall of straight segments through the points (as read_profile_csv returns them)."""
    return DieProfile(tuple(Segment(tuple(a), tuple(b))
                            for a, b in zip(points[:-1], points[1:], strict=True)))

"""Limit-analysis bounds on the frictionless drawing load (Example 2's level, docs/example2.md)."""
import math

import numpy as np
import pytest

from forming_fenicsx.verification.limit_analysis import (lower_bound, strip_triangulation,
                                                         upper_bound)
from forming_fenicsx.config.geometry import DrawingGeometry

pytestmark = pytest.mark.no_parallel_content  # numpy and scipy's linprog (tests/conftest.py)

K = 100.0
EXACT_EXIT = 1.625 * (1 - 2 * math.sin(math.radians(6)) / (1 + 2 * math.sin(math.radians(6))))
EXACT_Q = 2 * K * (1 + math.radians(6)) * EXACT_EXIT / 1.625   # Hill's field: 2k(1 + a)(1 - r)


def resolved(geometry: DrawingGeometry) -> DrawingGeometry:
    """The geometry with the lengths left out filled in (Example 2's)."""
    geometry.resolve()
    return geometry


def test_triangulation_covers_the_strip_with_crossed_diagonals():
    geometry = resolved(DrawingGeometry())
    points, triangles, edges = strip_triangulation(geometry, 0.05, 0.2)
    corners = points[triangles]
    doubled = ((corners[:, 1, 0] - corners[:, 0, 0]) * (corners[:, 2, 1] - corners[:, 0, 1])
               - (corners[:, 2, 0] - corners[:, 0, 0]) * (corners[:, 1, 1] - corners[:, 0, 1]))
    assert doubled.min() > 0   # counter-clockwise, none degenerate
    h0, h1, xa = 0.8125, 0.75, geometry.die_entry
    area = (h0 * xa + 0.5 * (h0 + h1) * geometry.cone_length
            + h1 * (geometry.length - xa - geometry.cone_length))
    assert 0.5 * doubled.sum() == pytest.approx(area, rel=1e-12)
    # the four triangles of a quadrilateral meet where its diagonals cross: the centre of the first
    # triangle lies on the line through the two opposite vertices of the quadrilateral
    n_quads = len(triangles) // 4
    a, b, centre = (points[triangles[:n_quads, i]] for i in range(3))
    c = points[triangles[2 * n_quads:3 * n_quads, 0]]
    cross = ((c[:, 0] - a[:, 0]) * (centre[:, 1] - a[:, 1])
             - (c[:, 1] - a[:, 1]) * (centre[:, 0] - a[:, 0]))
    assert np.abs(cross).max() < 1e-12
    lengths = {role: np.linalg.norm(points[e[:, 1]] - points[e[:, 0]], axis=1).sum()
               for role, e in edges.items()}
    assert lengths["exit"] == pytest.approx(h1)
    assert lengths["symmetry"] == pytest.approx(geometry.length)
    assert lengths["die"] == pytest.approx(geometry.cone_length / math.cos(math.radians(6))
                                           + geometry.land_length)


def test_bounds_bracket_the_exact_slip_line_load():
    """Where Hill's field is exact (r = 0.1729) the lower bound is within 1 % below and the upper
    bound above."""
    geometry = resolved(DrawingGeometry(exit_thickness=EXACT_EXIT))
    low = lower_bound(geometry, K, 0.1, 0.4, sides=32)
    high = upper_bound(geometry, K, 0.1, 0.4, sides=32)
    assert 0.99 * EXACT_Q < low.die_pressure <= EXACT_Q
    assert high.die_pressure > EXACT_Q
    assert low.pulling_force == pytest.approx(low.die_pressure * (0.8125 - EXACT_EXIT / 2))


def test_paper_load_lies_above_the_quoted_slip_line_value():
    """An equilibrium stress field carries a die pressure above 250 = 2.5 k: the quoted value is
    below the load of the paper's strip (docs/example2.md)."""
    low = lower_bound(resolved(DrawingGeometry()), K, 0.05, 0.2, sides=24)
    assert low.die_pressure > 1.015 * 250.0
    assert low.drawing_stress == pytest.approx(low.die_pressure * 0.0625 / 0.75)

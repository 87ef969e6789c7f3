"""Element counts and gmsh progressions of the structured blocks' edges (mesh/geometry.py, 2D;
mesh/bar3d.py, 3D)."""
from __future__ import annotations

import math


# the largest ratio of neighbouring elements on a graded edge: an edge of few elements gets less
# than the grading asked for (Example 1 with mu = 0.1 on h = 1, three elements on the graded edges:
# the friction loop (3.33) stalled with a grading of 16 to 64, ratios of 4 to 8, and converged with
# 4, a ratio of 2)
MAX_RATIO = 3.0


def graded_edge(length: float, size: float, grading: float, toward_end: bool) -> tuple[int, float]:
    """Number of elements and gmsh progression for an edge refined geometrically toward one end.

    ``grading`` is the ratio of the largest to the smallest element on the edge (1 is uniform),
    at most MAX_RATIO^(elements - 1).
    """
    elements = max(1, math.ceil(length / size - 1e-9))
    if elements == 1 or grading == 1.0:
        return elements, 1.0
    ratio = min(grading ** (1.0 / (elements - 1)), MAX_RATIO)
    return elements, 1.0 / ratio if toward_end else ratio

"""Element counts and gmsh progressions of the structured blocks' edges (mesh/geometry.py, 2D;
mesh/bar3d.py, 3D)."""
from __future__ import annotations

import math


def graded_edge(length: float, size: float, grading: float, toward_end: bool) -> tuple[int, float]:
    """Number of elements and gmsh progression for an edge refined geometrically toward one end.

    ``grading`` is the ratio of the largest to the smallest element on the edge (1 is uniform).
    """
    elements = max(1, math.ceil(length / size - 1e-9))
    if elements == 1 or grading == 1.0:
        return elements, 1.0
    ratio = grading ** (1.0 / (elements - 1))
    return elements, 1.0 / ratio if toward_end else ratio

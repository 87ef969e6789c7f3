"""The rolls of flat rolling: rigid cylinders turning at a constant surface speed.

The top roll of centre c and radius R turns so that its lowest point moves along +x at the surface
speed v_R: its surface velocity at x is w = (v_R/R) (c_y - y, x - c_x), tangent to the roll
(w . (c - x) = 0), so the contact (2.9) sees a fixed wall and friction the slip u - w.
"""
from __future__ import annotations

import ufl


def surface_velocity(x, centre, speed, radius):
    """w(x) = (v_R/R) (c_y - x_1, x_0 - c_x) of the top roll, a UFL vector (``centre``, ``speed``
    and ``radius`` UFL scalars or constants)."""
    return speed / radius * ufl.as_vector((centre[1] - x[1], x[0] - centre[0]))

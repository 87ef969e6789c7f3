"""Unilateral contact on Gamma3 by the penalty (3.4): sigma_N = -u_N^+/d_N."""
from __future__ import annotations

import ufl


def normal_velocity(u, n):
    """u_N = u.n on the boundary."""
    return ufl.dot(u, n)


def active_indicator(u_state, n):
    """1 where the state touches or penetrates the die (u_N >= 0), else 0: the active set of (3.4)."""
    return ufl.conditional(ufl.ge(normal_velocity(u_state, n), 0.0), 1.0, 0.0)


def contact_pressure(u_state, n, d_N: float):
    """-sigma_N = u_N^+/d_N of (3.4), non-negative."""
    return ufl.max_value(normal_velocity(u_state, n), 0.0) / d_N


def contact_form(u, v, active, n, d_N: float, ds_contact):
    """Penalty term (1/d_N) int u_N^+ v_N of (3.5), linearised on an active set (an indicator, e.g.
    active_indicator of the state)."""
    return active / d_N * normal_velocity(u, n) * normal_velocity(v, n) * ds_contact

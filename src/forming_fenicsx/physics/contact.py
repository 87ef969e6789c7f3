"""Unilateral contact on Gamma3: the penalty (3.4), sigma_N = -u_N^+/d_N, optionally augmented.

Augmented (penalty.augmented, the default): sigma_N = -(lambda + u_N/d_N)^+ with a multiplier
lambda >= 0 updated by lambda <- (lambda + u_N/d_N)^+ once the iterate has nearly settled (Uzawa's
method for the augmented Lagrangian, ContactMultiplier). At its fixed point lambda > 0 where
u_N = 0 and u_N <= 0 where lambda = 0: the unilateral condition (2.9) holds exactly, and d_N only
sets how fast lambda converges. The pure penalty (the paper's) lets the workpiece into the die at
u_N = d_N sigma_N, which in a confined rigid zone (the container of an extrusion) compresses it at
a spurious rate and shifts the wall pressure by a spurious stress (docs/penalties.md).
"""
from __future__ import annotations

import ufl


def normal_velocity(u, n):
    """u_N = u.n on the boundary."""
    return ufl.dot(u, n)


def active_indicator(u_state, n, d_N: float, multiplier=0.0):
    """1 where the state touches or penetrates the die (lambda d_N + u_N >= 0), else 0: the active
    set."""
    return ufl.conditional(ufl.ge(multiplier * d_N + normal_velocity(u_state, n), 0.0), 1.0, 0.0)


def contact_pressure(u_state, n, d_N: float, multiplier=0.0):
    """-sigma_N = (lambda + u_N/d_N)^+, non-negative ((3.4) for lambda = 0)."""
    return ufl.max_value(multiplier + normal_velocity(u_state, n) / d_N, 0.0)


def contact_form(u, v, active, n, d_N: float, ds_contact):
    """Penalty term (1/d_N) int u_N^+ v_N of (3.5), linearised on an active set (an indicator, e.g.
    active_indicator of the state)."""
    return active / d_N * normal_velocity(u, n) * normal_velocity(v, n) * ds_contact


def multiplier_form(v, active, multiplier, n, ds_contact):
    """int lambda v_N over the active set: the multiplier's part of the contact traction, a linear
    form."""
    return active * multiplier * normal_velocity(v, n) * ds_contact


def contact_energy(u, n, d_N: float, multiplier, ds_contact):
    """int d_N/2 ((lambda + u_N/d_N)^+)^2, whose derivative in u is int (lambda + u_N/d_N)^+ v_N."""
    return 0.5 * d_N * contact_pressure(u, n, d_N, multiplier) ** 2 * ds_contact

"""Unilateral contact on Gamma3: the penalty (3.4), sigma_N = -u_N^+/d_N, optionally augmented.

Augmented (penalty.augmented, the default): sigma_N = -(lambda + u_N/d_N)^+ with a multiplier lambda >= 0
updated by lambda <- (lambda + u_N/d_N)^+ once the iterate has nearly settled (Uzawa's method for the
augmented Lagrangian, ContactMultiplier). At its fixed point lambda > 0 where u_N = 0 and u_N <= 0 where lambda = 0: the unilateral
condition (2.9) holds exactly, and d_N only sets how fast lambda converges. The pure penalty (the
paper's) lets the workpiece into the die at u_N = d_N sigma_N, which in a confined rigid zone (the
container of an extrusion) compresses it at a spurious rate and shifts the wall pressure by a spurious
stress (docs/penalties.md).
"""
from __future__ import annotations

import dolfinx.fem
import ufl

from .compat import function_space, petsc_vec
from .projection import LumpedProjector


def normal_velocity(u, n):
    """u_N = u.n on the boundary."""
    return ufl.dot(u, n)


def active_indicator(u_state, n, d_N: float, multiplier=0.0):
    """1 where the state touches or penetrates the die (lambda d_N + u_N >= 0), else 0: the active set."""
    return ufl.conditional(ufl.ge(multiplier * d_N + normal_velocity(u_state, n), 0.0), 1.0, 0.0)


def contact_pressure(u_state, n, d_N: float, multiplier=0.0):
    """-sigma_N = (lambda + u_N/d_N)^+, non-negative ((3.4) for lambda = 0)."""
    return ufl.max_value(multiplier + normal_velocity(u_state, n) / d_N, 0.0)


def contact_form(u, v, active, n, d_N: float, ds_contact):
    """Penalty term (1/d_N) int u_N^+ v_N of (3.5), linearised on an active set (an indicator, e.g.
    active_indicator of the state)."""
    return active / d_N * normal_velocity(u, n) * normal_velocity(v, n) * ds_contact


def multiplier_form(v, active, multiplier, n, ds_contact):
    """int lambda v_N over the active set: the multiplier's part of the contact traction, a linear form."""
    return active * multiplier * normal_velocity(v, n) * ds_contact


def contact_energy(u, n, d_N: float, multiplier, ds_contact):
    """int d_N/2 ((lambda + u_N/d_N)^+)^2, whose derivative in u is int (lambda + u_N/d_N)^+ v_N."""
    return 0.5 * d_N * contact_pressure(u, n, d_N, multiplier) ** 2 * ds_contact


class ContactMultiplier:
    """The augmented Lagrangian's multiplier lambda on the traces of P1 on Gamma3 (zero elsewhere).

    Uzawa's update sets lambda to the nodal mean (lumped projection, non-negative) of (lambda + u_N/d_N)^+
    over the die at the velocity ``state``. The solvers update it once their iterate has nearly settled
    (``settled``): an inexact augmented Lagrangian; updating after every iterate lets lambda grow while a
    damped iteration barely moves u, and diverges."""

    WINDOW = 100.0  # update once the iterate's increment is below WINDOW * delta; end once the update
    #                 would change lambda by less than WINDOW * delta (relative, nodal values)

    def __init__(self, state: dolfinx.fem.Function, n, d_N: float, ds_contact, degree: int):
        self.value = dolfinx.fem.Function(function_space(state.function_space.mesh, "P", 1), name="contact_multiplier")
        self._projector = LumpedProjector(contact_pressure(state, n, d_N, self.value), self.value, degree, ds_contact)
        self._before = petsc_vec(self.value).duplicate()
        self.updates = 0

    def update(self, keep_below: float = 0.0) -> float:
        """lambda <- (lambda + u_N/d_N)^+ at the current state, unless that changes lambda by less than
        ``keep_below``; returns the relative change ||lambda_new - lambda|| / ||lambda_new||."""
        vector, before = petsc_vec(self.value), self._before
        vector.copy(before)
        self._projector.project()
        norm = vector.norm()
        before.axpy(-1.0, vector)
        change = before.norm() / norm if norm > 0 else 0.0
        if change < keep_below:  # before held lambda_old - lambda_new: restore lambda_old
            vector.axpy(1.0, before)
            self.value.x.scatter_forward()
        else:
            self.updates += 1
        return change

    def settled(self, increment: float, delta: float) -> bool:
        """Called after every iterate (increment: its relative change, taken in full): updates lambda once
        the increment is below WINDOW * delta; True when lambda needs no update (a change below WINDOW *
        delta), so that the iteration may end."""
        if increment >= self.WINDOW * delta:
            return False
        return self.update(keep_below=self.WINDOW * delta) < self.WINDOW * delta

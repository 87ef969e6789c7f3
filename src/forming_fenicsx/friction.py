"""Coulomb friction on Gamma3, regularised by d_T as in Remark 3.2 / (3.11).

j_dT(w, v) = int tau_f(w) sqrt(|v_T|^2 + d_T^2), with Gateaux derivative
tau_f(w) v_T / sqrt(|v_T|^2 + d_T^2); the secant-modulus methods linearise it with the slip
coefficient tau_f / sqrt(|u_n,T|^2 + d_T^2) of the current state.
"""
from __future__ import annotations

import ufl


def tangential(u, n):
    """u_T = u - u_N n."""
    return u - ufl.dot(u, n) * n


def friction_bound(mu: float, normal_pressure):
    """Coulomb bound tau_f = mu * sigma_N-bar (section 2), sigma_N-bar >= 0 the normal pressure."""
    return mu * normal_pressure


def slip_coefficient(tau_f, u_state, n, d_T: float):
    """tau_f / sqrt(|u_T|^2 + d_T^2): the secant of the regularised friction traction."""
    slip = tangential(u_state, n)
    return tau_f / ufl.sqrt(ufl.dot(slip, slip) + d_T**2)


def friction_form(u, v, coefficient, n, ds_contact):
    """int c_T u_T . v_T over Gamma3: the linearised <j'_dT(w, u), v> of (3.12)."""
    return coefficient * ufl.dot(tangential(u, n), tangential(v, n)) * ds_contact


def friction_traction(coefficient, u_state, n):
    """Friction stress on the workpiece, sigma_T = -c_T u_T (opposes the slip)."""
    return -coefficient * tangential(u_state, n)

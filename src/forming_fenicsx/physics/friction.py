"""Friction on Gamma3, regularised by d_T as in Remark 3.2 / (3.11): Coulomb's law of the paper,
the friction factor law (the "shear friction" of bulk-forming codes, Chen and Kobayashi), or
sticking.

The bound tau_f(w) is Coulomb's mu sigma_N-bar (2.9), or m k with k = sigma_p(rate)/sqrt(3) the
shear flow stress of the workpiece where it slides. j_dT(w, v) = int tau_f(w) sqrt(|v_T|^2 + d_T^2),
with Gateaux derivative tau_f(w) v_T / sqrt(|v_T|^2 + d_T^2); the secant-modulus methods linearise
it with the slip coefficient tau_f / sqrt(|u_n,T|^2 + d_T^2) of the current state. Sticking has no
bound: j(v) = int k0/(2 d_T) |v_T|^2 penalises the slip (sticking_coefficient), linear in v.
"""
from __future__ import annotations

import ufl


def tangential(u, n):
    """u_T = u - u_N n."""
    return u - ufl.dot(u, n) * n


def coulomb_bound(mu: float, normal_pressure):
    """Coulomb bound tau_f = mu * sigma_N-bar (section 2), sigma_N-bar >= 0 the normal pressure."""
    return mu * normal_pressure


def factor_bound(m: float, flow_stress):
    """Friction factor bound tau_f = m k, k = sigma_p / sqrt(3) (0 <= m <= 1; m = 1 is sticking at
    the shear flow stress): with the regularisation, tau = m k |u_T| / sqrt(|u_T|^2 + d_T^2), the
    (2/pi) arctan(|u_T|/v_0) of Chen and Kobayashi with another smooth step."""
    return m * flow_stress / 3.0**0.5


# rolling's factor law carries its bound's rate derivative into Newton's step from this rate
# sensitivity d ln sigma_p / d ln rate up (docs/rolling.md): frozen, a rate-sensitive bound made the
# last steps converge linearly (a steel slab at m = 1, n = 0.15: 30 solves, its roll force 0.2 %
# off); with the derivative the near rate-independent law of the slab grid (alpha = 1e-3) took six
# of its sticking rows above 20 solves instead of two
RATE_SENSITIVE = 0.01
# rolling's factor law at m = 1 is solved as sticking from this rate sensitivity on, midway between
# the measured: at n = 0.1 to 0.3 (rate^n) its roll force lay 1.8 to 3.5 % below its d_T -> 0
# limit and took up to 279 solves, where sticking lies 0.07 to 0.6 % above it; at n = 0.05 and
# 0.011 the factor law lay 0.3 and 0.05 % below in 14 and 18 solves, and sticking's mesh error
# (0.2 to 0.4 % a halving) is the larger (docs/rolling.md)
STICKING_RATE_SENSITIVITY = 0.075
# a friction stress within this fraction of k is "at the metal's shear strength" (post/rolls.py)
STRENGTH_MARGIN = 0.01


def sticking_coefficient(flow_stress: float, d_T: float) -> float:
    """c_T = k0 / d_T, k0 = sigma_0/sqrt(3) the shear flow stress at the reference rate: sticking's
    slip penalty, tau = -c_T u_T, the factor law's stiffness at zero slip with m = 1 and no bound.
    The metal under the surface bounds the friction stress at its shear strength k, so the slip
    stays at d_T |tau| / k0. On a metal that does not harden it is the factor law's limit m = 1,
    d_T -> 0, where the law's bound leaves the split of the slip between the interface and the
    metal under it nearly free, which Newton's steps creep along; a hardening metal's held surface
    layer hardens by its shear, and sticking lies above that limit (docs/rolling.md#sticking)."""
    return flow_stress / 3.0**0.5 / d_T


def sticking_functional(coefficient, u, n):
    """Integrand of sticking's j(u) = int c_T/2 |u_T|^2, whose derivative is friction_form."""
    slip = tangential(u, n)
    return 0.5 * coefficient * ufl.dot(slip, slip)


def shear_limited(bound, flow_stress):
    """tau_f = min(bound, k), k = sigma_p / sqrt(3): a Coulomb bound capped at the shear flow
    stress, beyond which the metal under the surface shears instead of the surface slipping."""
    return ufl.min_value(bound, flow_stress / 3.0**0.5)


def slip_coefficient(tau_f, u_state, n, d_T: float):
    """tau_f / sqrt(|u_T|^2 + d_T^2): the secant of the regularised friction traction."""
    slip = tangential(u_state, n)
    return tau_f / ufl.sqrt(ufl.dot(slip, slip) + d_T**2)


def friction_form(u, v, coefficient, n, ds_contact):
    """int c_T u_T . v_T over Gamma3: the linearised <j'_dT(w, u), v> of (3.12)."""
    return coefficient * ufl.dot(tangential(u, n), tangential(v, n)) * ds_contact


SLOW_SLIP = 1e-2  # Newton's operator takes the secant where |u_T| < SLOW_SLIP * process velocity


def regularised_functional(tau_f, u, n, d_T: float):
    """Integrand of j_dT(w, u) = int tau_f(w) sqrt(|u_T|^2 + d_T^2) of (3.11)."""
    slip = tangential(u, n)
    return tau_f * ufl.sqrt(ufl.dot(slip, slip) + d_T**2)


def newton_form(du, v, u, tau_f, n, d_T: float, slow_slip: float, ds_contact):
    """Friction's part of Newton's operator at u (tau_f fixed): the secant form of (3.13) where the
    die point slips slower than ``slow_slip`` or sticks, the tangent of (3.11) where it slips
    faster. Near zero slip the tangent's curvature is about tau_f/d_T, which made Newton's line
    search cut the steps (docs/solvers.md); in fast slip the tangent keeps the steps quadratic."""
    slip = tangential(u, n)
    coefficient = slip_coefficient(tau_f, u, n, d_T)
    fast = ufl.conditional(ufl.gt(ufl.dot(slip, slip), slow_slip**2), 1.0, 0.0)
    du_T, v_T = tangential(du, n), tangential(v, n)
    return (friction_form(du, v, coefficient, n, ds_contact)
            - fast * coefficient * ufl.dot(slip, du_T) * ufl.dot(slip, v_T)
            / (ufl.dot(slip, slip) + d_T**2) * ds_contact)


def friction_traction(coefficient, u_state, n):
    """Friction stress on the workpiece, sigma_T = -c_T u_T (opposes the slip)."""
    return -coefficient * tangential(u_state, n)

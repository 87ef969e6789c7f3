"""What flat rolling's users read: the roll force and torque, the strip's speeds and forward slip,
the neutral point where the strip's slip on the roll changes sign, and the power balance.

All on the half model (the top roll and the strip above its mid-plane), per unit width; the
summary makes the powers the whole strip's (forces.whole_product). The traction on the strip over
the arc is t = -p n + tau with tau = -c_T (u - w)_T (the friction stress against the slip relative
to the roll, physics/roll.py); the roll's surface velocity w is tangent to it, so the power the
roll puts into the strip is int t . w = omega T, omega = v_R/R.
"""
from __future__ import annotations

import math
from typing import Any

import numpy as np
import ufl

from forming_fenicsx.core.roles import ROLES
from forming_fenicsx.fem.forms import FlowProblem
from forming_fenicsx.physics.friction import STRENGTH_MARGIN, tangential
from forming_fenicsx.post.forces import pressure_free_friction, unpressed
from forming_fenicsx.post.integrals import integrate


def roll_direction(problem: FlowProblem):
    """The unit tangent w/|w| along which the roll's surface moves (a UFL vector)."""
    w = problem.tool_velocity
    return w / ufl.sqrt(ufl.dot(w, w))


def slip_along(problem: FlowProblem):
    """(u - w) . w/|w|: the strip's slip on the roll along its motion, < 0 where the roll drags the
    strip forward (before the neutral point), > 0 where the strip runs ahead of it (after)."""
    return ufl.dot(problem.slip(problem.u), roll_direction(problem))


def shear_along(problem: FlowProblem):
    """tau . w/|w|: the friction stress on the strip along the roll's motion (> 0 drags it
    forward)."""
    if not problem.has_friction:
        return 0.0 * problem.u[0]
    return ufl.dot(problem.friction_traction(), roll_direction(problem))


def _face_mean_speed(problem: FlowProblem, role: str) -> float:
    """The mean x-velocity over the end face of ``role`` (its facets normal to x)."""
    face = ufl.conditional(ufl.gt(abs(problem.n[0]), 0.5), 1.0, 0.0)
    ds = problem.ds(ROLES[role])
    return integrate(problem, problem.u[0] * face * ds) / integrate(problem, face * ds)


def strip_speeds(problem: FlowProblem) -> tuple[float, float]:
    """(v_0, v_1): the strip's mean speed at the entry face and at the exit face."""
    exit_role = "gamma5_force" if "gamma5_force" in problem.roles else "gamma4_free"
    return _face_mean_speed(problem, "gamma1_velocity"), _face_mean_speed(problem, exit_role)


def power_balance(problem: FlowProblem) -> dict[str, float]:
    """The powers of the half model per unit width: the roll's int t . w, the tensions' f(u), the
    deformation's int s : e (the plastic dissipation of the model's secant stress) and
    int sigma_H div u (the volumetric part), the friction's int c_T |(u - w)_T|^2 and the contact's
    int p (u - w) . n; ``residual``: (roll + tensions - the rest)/the rest, zero at a converged
    answer (the discrete balance is the residual of (3.12) tested with u)."""
    n, ds, dx = problem.n, problem.ds_contact, problem.dx
    c = problem.coordinates
    pressure = problem.contact_pressure(problem.u)
    traction = -pressure * n
    friction = 0.0
    if problem.has_friction:
        traction = traction + problem.friction_traction()
        slip_T = tangential(problem.slip(problem.u), n)
        friction = integrate(problem, problem.friction_coefficient() * ufl.dot(slip_T, slip_T) * ds)
    e = problem.strain_rate(problem.u)
    deviatoric = 2.0 / 3.0 * problem.secant_coefficient() * c.deviatoric_product(e, e)
    volumetric = (-problem.pressure * problem.divergence(problem.u) * dx if problem.mixed else
                  problem.divergence(problem.u) ** 2 / problem.scene.penalty.d * problem.dx_vol)
    powers = {
        "roll_power": integrate(problem, ufl.dot(traction, problem.tool_velocity) * ds),
        "tension_power": (integrate(problem, ufl.action(problem.load(ufl.TestFunction(problem.V)),
                                                        problem.u)) if problem.has_force else 0.0),
        "plastic_power": integrate(problem, deviatoric * dx),
        "volumetric_power": integrate(problem, volumetric),
        "friction_power": friction,
        "contact_power": integrate(problem, pressure * ufl.dot(problem.slip(problem.u), n) * ds),
    }
    supplied = powers["roll_power"] + powers["tension_power"]
    spent = sum(powers[key] for key in ("plastic_power", "volumetric_power", "friction_power",
                                        "contact_power"))
    powers["residual"] = (supplied - spent) / spent
    return powers


def neutral_point(x: np.ndarray, slip: np.ndarray) -> float:
    """The x where the slip along the roll's motion at the arc's nodes (ordered along it) changes
    sign from negative to positive, linearly interpolated; NaN without such a change (the strip
    slides one way over the whole arc)."""
    change = np.flatnonzero((slip[:-1] < 0) & (slip[1:] >= 0))
    if len(change) == 0:
        return math.nan
    i = change[-1]
    return float(x[i] + (x[i + 1] - x[i]) * -slip[i] / (slip[i + 1] - slip[i]))


def strength_share(problem: FlowProblem) -> float:
    """int |tau . w| over the arc where |tau| >= (1 - STRENGTH_MARGIN) k, k = sigma_p/sqrt(3) as the
    factor law reads it (at the rate floor in a rigid zone), over int |tau . w|: the share of the
    friction's torque, before and after the neutral point alike, given at the metal's shear
    strength. There the slip splits between the interface and the metal under it as the slip
    regularisation d_T decides (docs/rolling.md)."""
    tau = problem.friction_traction()
    torque = abs(ufl.dot(tau, problem.tool_velocity))
    k = problem.yield_stress(problem.u) / 3.0**0.5
    at = ufl.conditional(ufl.ge(ufl.sqrt(ufl.dot(tau, tau)), (1.0 - STRENGTH_MARGIN) * k), 1.0,
                         0.0)
    total = integrate(problem, torque * problem.ds_contact)
    return integrate(problem, torque * at * problem.ds_contact) / total if total > 0 else 0.0


def roll_scalars(problem: FlowProblem, profile: dict[str, np.ndarray] | None) -> dict[str, Any]:
    """Roll force (the separating force on each roll, per unit width), torque per roll and the
    rolls' power, the strip's entry and exit speeds, the forward slip S = v_1/v_R - 1, the neutral
    point (x, and its angle from the line of the roll centres), the bite angle and the power
    balance. ``profile``: die.die_profile on rank 0 with
    the slip column (collective; None on the other ranks)."""
    g, process = problem.scene.geometry, problem.scene.process
    v_R, R = process.velocity, g.roll_radius
    balance = power_balance(problem)
    v0, v1 = strip_speeds(problem)
    neutral = None
    if profile is not None:
        neutral = neutral_point(profile["x"], profile["slip"])
    neutral = problem.comm.bcast(neutral, root=0)
    x_gap = g.die_exit
    angle = (math.degrees(math.asin(min(1.0, (x_gap - neutral) / R))) if math.isfinite(neutral)
             else math.nan)
    # the friction factor's share of the torque where the strip does not press on the roll
    unpressed_torque = {} if not pressure_free_friction(problem) else {
        "unpressed_friction_torque": integrate(problem, ufl.dot(
            problem.friction_traction(), problem.tool_velocity) * unpressed(problem)
            * problem.ds_contact) * R / v_R}
    at_strength = {} if not problem.bound_reaches_strength else {
        "friction_at_strength_share": strength_share(problem)}
    return {"roll_torque": balance["roll_power"] * R / v_R, **unpressed_torque, **at_strength,
            "roll_power": balance["roll_power"],
            "entry_speed": v0, "exit_speed": v1, "forward_slip": v1 / v_R - 1.0,
            "neutral_x": neutral, "neutral_angle": angle,
            "bite_angle": g.die_angle,
            "power_balance": balance}

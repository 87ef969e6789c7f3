"""The slab (von Karman) solution of plane-strain flat rolling between rigid rolls: the reference
the finite-element rolling model is compared with (issue 39).

x runs from the rolls' line of centres (the exit, x = 0) toward the entry, x_a = R sin(alpha);
the strip of thickness h(x) = h1 + 2 (R - sqrt(R^2 - x^2)) moves toward -x, and the roll surface
at angle phi (sin(phi) = x/R) slopes by tan(phi). A slice in equilibrium, with F = sigma_x h the
horizontal force per unit width (tension positive), the roll pressure p and the friction stress
tau on both surfaces:

    dF/dx = -2 p tan(phi) + 2 tau   (entry zone: the roll is faster and drags the strip in)
    dF/dx = -2 p tan(phi) - 2 tau   (exit zone: the strip is faster)

with the homogeneous plane-strain yield condition sigma_x + p = 2k (k the shear flow stress), and
tau = min(mu p, k) (Coulomb, capped at sticking) or tau = k (sticking throughout). The entry zone
is integrated from the entry (sigma_x = back tension), the exit zone from the exit (sigma_x =
front tension). They meet at the neutral point x_n, where the pressures agree (the friction
hill's peak). A friction too low to draw the strip in has no such point: ValueError. The strip
moves at the roll's surface speed at x_n, so the forward slip is S = h(x_n) cos(phi_n)/h1 - 1.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

FRICTIONS = ("coulomb", "sticking")


@dataclass(frozen=True)
class SlabRolling:
    """The slab solution (per unit width): ``roll_force`` and ``torque`` on one roll (the vertical
    force and the moment of the friction about its axis), the ``neutral_angle`` phi_n (radians)
    and x_n, the ``forward_slip`` S, the ``bite_angle`` alpha and the projected ``contact_length``
    x_a; x, the roll pressure p and the friction stress tau along the arc (the friction hill)."""

    roll_force: float
    torque: float
    neutral_angle: float
    neutral_x: float
    forward_slip: float
    bite_angle: float
    contact_length: float
    x: np.ndarray
    pressure: np.ndarray
    friction: np.ndarray


def _zone(x: np.ndarray, h: np.ndarray, slope: np.ndarray, k: float, start: float,
          friction: str, mu: float, sign: float) -> np.ndarray:
    """F = sigma_x h along the nodes x (in the order of integration) from F(x[0]) = ``start``:
    dF/dx = -2 p tan(phi) + sign 2 tau, by classical Runge-Kutta on the linear interpolants of h
    and tan(phi) between nodes."""
    def rate(i: int, t: float, F: float) -> float:
        hh = h[i] + t * (h[i + 1] - h[i])
        tan = slope[i] + t * (slope[i + 1] - slope[i])
        p = 2 * k - F / hh
        tau = k if friction == "sticking" else min(mu * p, k)
        return -2 * p * tan + sign * 2 * tau

    F = np.empty(len(x))
    F[0] = start
    for i in range(len(x) - 1):
        dx = x[i + 1] - x[i]
        k1 = rate(i, 0.0, F[i])
        k2 = rate(i, 0.5, F[i] + 0.5 * dx * k1)
        k3 = rate(i, 0.5, F[i] + 0.5 * dx * k2)
        k4 = rate(i, 1.0, F[i] + dx * k3)
        F[i + 1] = F[i] + dx / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
    return F


def slab_rolling(radius: float, entry_thickness: float, exit_thickness: float, k: float,
                 mu: float = 0.0, friction: str = "coulomb", back_tension: float = 0.0,
                 front_tension: float = 0.0, steps: int = 4000) -> SlabRolling:
    """The slab solution for rolls of ``radius`` reducing a strip from ``entry_thickness`` to
    ``exit_thickness`` (the roll gap), shear flow stress ``k``, Coulomb ``mu`` (capped at k) or
    ``friction`` = "sticking", tensions as stresses (module docstring); ``steps`` intervals
    across the arc."""
    if friction not in FRICTIONS:
        raise ValueError(f"friction must be one of {', '.join(FRICTIONS)}; got {friction!r}")
    if not 0 < exit_thickness < entry_thickness:
        raise ValueError("the exit thickness must lie between 0 and the entry thickness")
    draft = entry_thickness - exit_thickness
    if draft >= 2 * radius:
        raise ValueError("the draft must be less than the roll diameter")
    alpha = math.acos(1 - draft / (2 * radius))
    x = radius * np.sin(np.linspace(0.0, alpha, steps + 1))
    h = exit_thickness + 2 * (radius - np.sqrt(radius**2 - x**2))
    slope = x / np.sqrt(radius**2 - x**2)
    exit_F = _zone(x, h, slope, k, front_tension * exit_thickness, friction, mu, -1.0)
    entry_F = _zone(x[::-1], h[::-1], slope[::-1], k, back_tension * entry_thickness, friction,
                    mu, 1.0)[::-1]
    gap = entry_F - exit_F  # > 0: the entry zone's pressure below the exit zone's
    crossing = np.flatnonzero(np.diff(np.sign(gap)) != 0)
    if friction == "coulomb" and not len(crossing):
        raise ValueError(f"no neutral point: mu = {mu:g} cannot draw the strip through the bite "
                         f"(bite angle {math.degrees(alpha):.3g} degrees, tan = "
                         f"{math.tan(alpha):.3g}); the rolls slip on the strip")
    i = int(crossing[-1]) if len(crossing) else 0
    t = gap[i] / (gap[i] - gap[i + 1]) if gap[i] != gap[i + 1] else 0.0
    x_n = float(x[i] + t * (x[i + 1] - x[i]))
    F_n = float(exit_F[i] + t * (exit_F[i + 1] - exit_F[i]))
    # the neutral point as a node of both zones, so that the integrals switch zones there
    x = np.concatenate([x[:i + 1], [x_n], x[i + 1:]])
    F = np.concatenate([exit_F[:i + 1], [F_n], entry_F[i + 1:]])
    h = exit_thickness + 2 * (radius - np.sqrt(radius**2 - x**2))
    pressure = 2 * k - F / h
    tau = np.full_like(pressure, k) if friction == "sticking" else np.minimum(mu * pressure, k)
    phi = np.arcsin(x / radius)
    phi_n = math.asin(x_n / radius)
    exit_side = np.arange(len(x)) <= i + 1
    entry_side = np.arange(len(x)) >= i + 1
    # per roll: the vertical force of the pressure and the friction on the arc ds = R dphi, and
    # the friction's moment, driving in the entry zone and braking in the exit zone
    force = radius * (_trapezoid((pressure * np.cos(phi) - tau * np.sin(phi))[exit_side],
                                 phi[exit_side])
                      + _trapezoid((pressure * np.cos(phi) + tau * np.sin(phi))[entry_side],
                                   phi[entry_side]))
    torque = radius**2 * (_trapezoid(tau[entry_side], phi[entry_side])
                          - _trapezoid(tau[exit_side], phi[exit_side]))
    h_n = exit_thickness + 2 * radius * (1 - math.cos(phi_n))
    return SlabRolling(roll_force=force, torque=torque, neutral_angle=phi_n, neutral_x=x_n,
                       forward_slip=h_n * math.cos(phi_n) / exit_thickness - 1,
                       bite_angle=alpha, contact_length=float(x[-1]), x=x, pressure=pressure,
                       friction=tau)


def forward_slip_estimate(radius: float, entry_thickness: float, exit_thickness: float, k: float,
                          mu: float, back_tension: float, front_tension: float) -> float:
    """The Coulomb slab solution's forward slip S on 400 intervals (within 1e-5 of 4000's), or 0
    where it has no neutral point: the finite-element model's first entry speed v_R (1 + S) h1/h0
    (fem/forms.py)."""
    try:
        return slab_rolling(radius, entry_thickness, exit_thickness, k, mu,
                            back_tension=back_tension, front_tension=front_tension,
                            steps=400).forward_slip
    except ValueError:
        return 0.0


def _trapezoid(values: np.ndarray, at: np.ndarray) -> float:
    return float(np.sum(0.5 * (values[1:] + values[:-1]) * np.diff(at)))


def bite_limit(radius: float, entry_thickness: float, exit_thickness: float,
               back_tension: float = 0.0, front_tension: float = 0.0, k: float = 1.0,
               steps: int = 1000) -> float:
    """The smallest Coulomb mu at which the slab solution has a neutral point (steady rolling),
    to 1e-3 relative, by bisection; about tan(alpha/2) without tensions, alpha the bite angle."""
    def rolls(mu: float) -> bool:
        try:
            slab_rolling(radius, entry_thickness, exit_thickness, k, mu,
                         back_tension=back_tension, front_tension=front_tension, steps=steps)
        except ValueError:
            return False
        return True

    low, high = 0.0, 0.05
    while not rolls(high):
        low, high = high, 2 * high
        if high > 10:
            return math.inf
    while high - low > 1e-3 * high:
        middle = 0.5 * (low + high)
        low, high = (low, middle) if rolls(middle) else (middle, high)
    return high


@dataclass(frozen=True)
class SimsRolling:
    """Sims' roll force for sticking friction (hot rolling): ``force_factor`` Q_p = P/(2k L) with
    L = sqrt(R dh), and the ``neutral_angle`` phi_n (radians)."""

    force_factor: float
    neutral_angle: float


def sims_sticking(radius: float, entry_thickness: float, exit_thickness: float) -> SimsRolling:
    """R. B. Sims, The calculation of roll force and torque in hot rolling mills, Proc. Inst. Mech.
    Eng. 168 (1954) 191: Orowan's inhomogeneous theory with sticking friction (p/2k = pi/4 (1 +
    ln(h/h_1)) + sqrt(R/h_1) arctan(sqrt(R/h_1) phi) on the exit side, its mirror from the entry),
    small angles, in closed form. With r the reduction and a = sqrt((1 - r)/r):
        Q_p = pi/2 a arctan(1/a) - pi/4 - a sqrt(R/h_1) ln(h_n/h_1) + a/2 sqrt(R/h_1) ln(1/(1-r)),
        phi_n = sqrt(h_1/R) tan(pi/8 sqrt(h_1/R) ln(1 - r) + arctan(1/a)/2),
    h_n = h_1 + R phi_n^2. The shear stress's share of the yield condition (the pi/4) is what sets
    it below the homogeneous slab solution with sticking."""
    r = 1.0 - exit_thickness / entry_thickness
    if not 0 < r < 1 or radius <= 0:
        raise ValueError("need 0 < exit thickness < entry thickness and a radius > 0")
    a, ratio = math.sqrt((1 - r) / r), math.sqrt(radius / exit_thickness)
    phi_n = math.tan(math.pi / 8 / ratio * math.log(1 - r) + 0.5 * math.atan(1 / a)) / ratio
    h_n = exit_thickness + radius * phi_n**2
    force = (math.pi / 2 * a * math.atan(1 / a) - math.pi / 4
             - a * ratio * math.log(h_n / exit_thickness) + 0.5 * a * ratio * math.log(1 / (1 - r)))
    return SimsRolling(force, phi_n)

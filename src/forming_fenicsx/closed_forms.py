"""Closed-form drawing and extrusion loads through conical dies, for orientation and verification
(round-products reference, sections 2 and 5). Angles in degrees; r = 1 - A1/A0 the reduction (of area
for a round bar, of thickness for a strip)."""
from __future__ import annotations

import math


def sachs_drawing_stress(reduction: float, semi_angle: float, mu: float, back_tension: float = 0.0) -> float:
    """Sachs' slab method with Coulomb friction (Dieter, Mechanical Metallurgy): sigma_d / Y =
    ((1 + B)/B)(1 - (A1/A0)^B) + (sigma_b/Y)(A1/A0)^B, B = mu cot(alpha), Y the mean flow stress of a
    round bar (2k for a strip, thicknesses for areas); mu -> 0 gives ln(A0/A1) + sigma_b/Y."""
    ratio = 1.0 - reduction
    b = mu / math.tan(math.radians(semi_angle))
    if b < 1e-12:
        return -math.log(ratio) + back_tension
    return (1 + b) / b * (1 - ratio**b) + back_tension * ratio**b


def avitzur_f(alpha: float) -> float:
    """Avitzur's f(alpha) of the internal power of the spherical velocity field (alpha in radians)."""
    s2 = math.sin(alpha) ** 2
    q = math.sqrt(1 - 11 / 12 * s2)
    return (1 - math.cos(alpha) * q + 1 / math.sqrt(132) * math.log(
        (1 + math.sqrt(11 / 12)) / (math.sqrt(11 / 12) * math.cos(alpha) + q))) / s2


def avitzur_drawing_stress(reduction: float, semi_angle: float, m: float, land: float = 0.0,
                           back_tension: float = 0.0) -> float:
    """Avitzur's upper bound for wire drawing (and conical-die extrusion) with a friction factor m
    (tau = m sigma0/sqrt3; J. Eng. Ind. 85 (1963) 89): sigma_xf/sigma0 = sigma_xb/sigma0
    + 2 f(alpha) ln(R0/Rf) + (2/sqrt3)[alpha/sin^2 alpha - cot alpha] + (2/sqrt3) m [cot alpha
    ln(R0/Rf) + L/Rf], ``land`` = L/Rf."""
    alpha = math.radians(semi_angle)
    log_ratio = -0.5 * math.log(1.0 - reduction)  # ln(R0/Rf)
    shear = 2 / math.sqrt(3) * (alpha / math.sin(alpha) ** 2 - 1 / math.tan(alpha))
    return (back_tension + 2 * avitzur_f(alpha) * log_ratio + shear
            + 2 / math.sqrt(3) * m * (log_ratio / math.tan(alpha) + land))


def avitzur_optimum_angle(reduction: float, m: float, land: float = 0.0) -> float:
    """The semi-angle (degrees) minimising avitzur_drawing_stress: golden-section search on [0.5, 45]."""
    lower, upper = 0.5, 45.0
    golden = (math.sqrt(5) - 1) / 2
    for _ in range(80):
        a, b = upper - golden * (upper - lower), lower + golden * (upper - lower)
        if avitzur_drawing_stress(reduction, a, m, land) < avitzur_drawing_stress(reduction, b, m, land):
            upper = b
        else:
            lower = a
    return 0.5 * (lower + upper)


def avitzur_optimum_angle_approx(reduction: float, m: float) -> float:
    """Avitzur's approximation alpha_opt = sqrt(1.5 m ln(R0/Rf)) (radians), in degrees."""
    return math.degrees(math.sqrt(1.5 * m * -0.5 * math.log(1.0 - reduction)))


def central_burst_indicator(reduction: float, semi_angle: float, axisymmetric: bool) -> float:
    """Delta = mean thickness / contact length of the pass: (alpha/r)(1 + sqrt(1 - r))^2 for a round
    bar, (alpha/r)(2 - r) for a strip (alpha in radians); large Delta (small reductions through wide
    dies) favours central bursts and redundant work."""
    alpha = math.radians(semi_angle)
    if axisymmetric:
        return alpha / reduction * (1 + math.sqrt(1 - reduction)) ** 2
    return alpha / reduction * (2 - reduction)

"""Closed-form and semi-analytic drawing and extrusion loads through conical and wedge dies, for
orientation and verification (round-products reference, sections 1, 2 and 5), and through dies of
plane faces for rectangular bars (3D, derived here: the slab method and an upper bound).

Angles are in degrees at the API (radians inside); r = 1 - A1/A0 is the reduction (of area for a
round bar, of thickness for a strip). Stresses are dimensionless: over the flow stress sigma0 (or
Ybar) of a round bar or a rectangular one, over 2k = 2 sigma0/sqrt3 of a strip, unless a function
takes K.
"""
from __future__ import annotations

import math
from typing import Callable, NamedTuple

import numpy as np

SYMMETRIES = ("axisymmetric", "plane_strain")
SQRT3 = math.sqrt(3.0)


def _is_axisymmetric(symmetry: str) -> bool:
    """True for "axisymmetric", False for "plane_strain"; anything else is refused."""
    if symmetry not in SYMMETRIES:
        raise ValueError(f"symmetry must be one of {SYMMETRIES}; got {symmetry!r}")
    return symmetry == "axisymmetric"


def _expm1_over(x: float) -> float:
    """(e^x - 1)/x, 1 at x = 0 (no cancellation for small x)."""
    return math.expm1(x) / x if x != 0.0 else 1.0


def _gauss_legendre(fun: Callable[[np.ndarray], np.ndarray], a: float, b: float,
                    nodes: int = 24) -> float:
    """Gauss-Legendre quadrature of a smooth integrand on [a, b]."""
    x, w = np.polynomial.legendre.leggauss(nodes)
    return float(0.5 * (b - a) * np.dot(w, fun(0.5 * (b - a) * x + 0.5 * (a + b))))


def _root(fun: Callable[[float], float], lower: float, upper: float, tol: float = 1e-13) -> float:
    """A root of fun in a bracket [lower, upper] (signs differ) by the Illinois false position."""
    f_lower, f_upper = fun(lower), fun(upper)
    if f_lower * f_upper > 0:
        raise ValueError(f"no sign change on [{lower}, {upper}]")
    side = 0
    x = lower
    for _ in range(200):
        x = (lower * f_upper - upper * f_lower) / (f_upper - f_lower)
        fx = fun(x)
        if fx == 0.0 or upper - lower < tol * (1.0 + abs(x)):
            return x
        if fx * f_upper > 0:
            upper, f_upper = x, fx
            if side == -1:
                f_lower /= 2
            side = -1
        else:
            lower, f_lower = x, fx
            if side == 1:
                f_upper /= 2
            side = 1
    return x


def _bracket_decreasing(fun: Callable[[float], float], guess: float) -> tuple[float, float]:
    """(lower, upper) with fun(lower) > 0 > fun(upper), for fun decreasing on (1, inf), from a
    guess of the root."""
    upper = guess
    while fun(upper) > 0:
        upper = 1 + 2 * (upper - 1)
    lower = 1 + 0.5 * (upper - 1)
    while fun(lower) < 0:
        lower = 1 + 0.5 * (lower - 1)
    return lower, upper


# --- Section 2: slab method and upper bounds ------------------------------------------------------

def sachs_drawing_stress(reduction: float, semi_angle: float, mu: float,
                         symmetry: str = "axisymmetric", back_tension: float = 0.0) -> float:
    """Sachs' slab method with Coulomb friction (Dieter, Mechanical Metallurgy, wire and strip
    drawing): sigma_d/Ybar = ((1 + B)/B)(1 - (A1/A0)^B) + (sigma_b/Ybar)(A1/A0)^B, B = mu cot alpha.

    "axisymmetric": sigma_d/Ybar of a round bar (areas); "plane_strain": sigma_d/(2k) of a strip
    (thicknesses), the same expression. Written as (1 + B) L (e^(BL) - 1)/(BL) e^(-BL),
    L = ln(A0/A1), so mu = 0 gives ln(A0/A1) + sigma_b/Ybar exactly.
    """
    _is_axisymmetric(symmetry)
    log_ratio = -math.log1p(-reduction)
    b = mu / math.tan(math.radians(semi_angle))
    decay = math.exp(-b * log_ratio)  # (A1/A0)^B
    return (1 + b) * log_ratio * _expm1_over(b * log_ratio) * decay + back_tension * decay


def avitzur_f(alpha: float) -> float:
    """Avitzur's f(alpha) (alpha in radians), the internal power of his cone-zone field
    v = -v0 R0^2 cos(theta)/rho^2 per sigma0 ln(A0/A1) (Avitzur 1963):
    f = [1 - cos a sqrt(1 - (11/12) sin^2 a)
         + ln((1 + sqrt(11/12))/(sqrt(11/12) cos a + sqrt(1 - (11/12) sin^2 a)))/sqrt132]
        / sin^2 a."""
    s2 = math.sin(alpha) ** 2
    q = math.sqrt(1 - 11 / 12 * s2)
    return (1 - math.cos(alpha) * q + 1 / math.sqrt(132) * math.log(
        (1 + math.sqrt(11 / 12)) / (math.sqrt(11 / 12) * math.cos(alpha) + q))) / s2


def avitzur_cone_factor(semi_angle: float, m: float) -> float:
    """The factor of sigma0 ln(A0/A1) in Avitzur's bound (Avitzur 1963):
    f(alpha) + m cot(alpha)/sqrt3, the cone zone's internal power plus the die friction
    tau = m sigma0/sqrt3."""
    alpha = math.radians(semi_angle)
    return avitzur_f(alpha) + m / (SQRT3 * math.tan(alpha))


def avitzur_drawing_stress(reduction: float, semi_angle: float, m: float,
                           land_over_exit_radius: float = 0.0, back_tension: float = 0.0) -> float:
    """Avitzur's upper bound for wire drawing and conical-die extrusion with a friction factor m
    (J. Eng. Ind. 85 (1963) 89): sigma_xf/sigma0 = sigma_xb/sigma0 + 2 f(alpha) ln(R0/Rf)
    + (2/sqrt3)[alpha/sin^2 alpha - cot alpha] + (2/sqrt3) m [cot alpha ln(R0/Rf) + L/Rf]."""
    alpha = math.radians(semi_angle)
    shear = 2 / SQRT3 * (alpha / math.sin(alpha) ** 2 - 1 / math.tan(alpha))
    return (back_tension + avitzur_cone_factor(semi_angle, m) * -math.log1p(-reduction) + shear
            + 2 / SQRT3 * m * land_over_exit_radius)


def upper_bound_wedge_factor(semi_angle: float, m: float) -> float:
    """Plane-strain analogue of avitzur_cone_factor, derived here with Avitzur's method (field
    v_r = -v0 r0 cos(theta)/r between circular arcs), the factor of 2k ln(h0/h1):
    E(alpha | 3/4)/sin(alpha) + (m/2) cot(alpha), E(a | 3/4) = int_0^a sqrt(1 - (3/4) sin^2 t) dt.
    """
    alpha = math.radians(semi_angle)
    elliptic = _gauss_legendre(lambda t: np.sqrt(1 - 0.75 * np.sin(t) ** 2), 0.0, alpha)
    return elliptic / math.sin(alpha) + 0.5 * m / math.tan(alpha)


def upper_bound_strip_drawing_stress(reduction: float, semi_angle: float, m: float,
                                     land_over_exit_half_thickness: float = 0.0,
                                     back_tension: float = 0.0) -> float:
    """Upper bound for strip drawing through a wedge die (sigma/2k), derived here with Avitzur's
    method (not a printed formula): sigma_xf/2k = sigma_xb/2k + upper_bound_wedge_factor ln(h0/hf)
    + tan(alpha/2) (shear on the entry and exit arcs) + (m/2) L/(hf/2) (land of length L)."""
    alpha = math.radians(semi_angle)
    return (back_tension + upper_bound_wedge_factor(semi_angle, m) * -math.log1p(-reduction)
            + math.tan(alpha / 2) + 0.5 * m * land_over_exit_half_thickness)


def optimum_angle(stress: Callable[[float], float], lower: float = 0.5,
                  upper: float = 45.0) -> float:
    """The semi-angle (degrees) minimising a unimodal ``stress(angle)``: golden section on
    [lower, upper]."""
    golden = (math.sqrt(5) - 1) / 2
    for _ in range(80):
        a, b = upper - golden * (upper - lower), lower + golden * (upper - lower)
        if stress(a) < stress(b):
            upper = b
        else:
            lower = a
    return 0.5 * (lower + upper)


def avitzur_optimum_angle(reduction: float, m: float, land_over_exit_radius: float = 0.0) -> float:
    """The semi-angle (degrees) minimising avitzur_drawing_stress."""
    return optimum_angle(
        lambda angle: avitzur_drawing_stress(reduction, angle, m, land_over_exit_radius))


def strip_optimum_angle(reduction: float, m: float,
                        land_over_exit_half_thickness: float = 0.0) -> float:
    """The semi-angle (degrees) minimising upper_bound_strip_drawing_stress (Avitzur's method for a
    wedge die)."""
    return optimum_angle(lambda angle: upper_bound_strip_drawing_stress(
        reduction, angle, m, land_over_exit_half_thickness))


def avitzur_optimum_angle_approx(reduction: float, m: float) -> float:
    """Avitzur's approximation alpha_opt = sqrt(1.5 m ln(R0/Rf)) (radians), in degrees."""
    return math.degrees(math.sqrt(1.5 * m * -0.5 * math.log1p(-reduction)))


# --- Section 2: Shield's cone flow and Nadai's wedge flow (rigid-perfectly plastic, friction m) ---

class RadialFlow(NamedTuple):
    """A radial flow v = -U f(theta)/rho^2 (cone) or -Q f(theta)/r (wedge) with f(0) = 1.

    factor: the rise of the mean axial stress per sigma0 ln(A0/A1) (cone, Shield's c/2) or per
    2k ln(h0/h1) (wedge, Hill's c); theta, shear = sin psi = tau/k, speed = f, on a grid of psi
    (of theta when m = 0).
    """

    factor: float
    theta: np.ndarray
    shear: np.ndarray
    speed: np.ndarray


def _radial_flow_integrate(factor: float, psi_wall: float, cone: bool, steps: int
                           ) -> tuple[list[float], list[float]]:
    """theta(psi) and ln f(psi) on psi_i = i psi_wall/steps by RK4, for a given factor lambda.

    With S = sin psi = tau/k, the von Mises flow rule and equilibrium give (kappa = sqrt3, j = 1 for
    the cone, Shield 1955; kappa = 1, j = 0 for the wedge, Hill ch. VIII)
        dS/dtheta + j S cot(theta) = 2 kappa (lambda - cos psi),  d ln f/dtheta = -2 kappa tan psi,
    integrated in psi (regular up to a sticking wall psi = pi/2): dtheta/dpsi = cos psi / S',
    d ln f/dpsi = -2 kappa sin psi / S'. At theta = 0 the series S = a theta + b theta^3,
    a = 2 kappa (lambda - 1)/(1 + j), b = (kappa a^2 + j a/3)/(3 + j), starts the cone's singular
    point. A run that leaves 0 < theta < pi/2 or S' > 0 is cut short (theta_end = pi/2).
    """
    kappa, j = (SQRT3, 1.0) if cone else (1.0, 0.0)
    a = 2 * kappa * (factor - 1) / (1 + j)
    b = (kappa * a**2 + j * a / 3) / (3 + j)
    h = psi_wall / steps

    def rhs(psi: float, theta: float) -> tuple[float, float]:
        if not 0 < theta < math.pi / 2:
            raise ArithmeticError
        slope = 2 * kappa * (factor - math.cos(psi)) - j * math.sin(psi) / math.tan(theta)
        if not slope > 0:
            raise ArithmeticError
        return math.cos(psi) / slope, -2 * kappa * math.sin(psi) / slope

    theta, log_f = [0.0, h / a - (1 / (6 * a) + b / a**4) * h**3], [0.0, -kappa * h**2 / a]
    try:
        for i in range(1, steps):
            psi, t, g = i * h, theta[-1], log_f[-1]
            k1 = rhs(psi, t)
            k2 = rhs(psi + h / 2, t + h / 2 * k1[0])
            k3 = rhs(psi + h / 2, t + h / 2 * k2[0])
            k4 = rhs(psi + h, t + h * k3[0])
            theta.append(t + h / 6 * (k1[0] + 2 * k2[0] + 2 * k3[0] + k4[0]))
            log_f.append(g + h / 6 * (k1[1] + 2 * k2[1] + 2 * k3[1] + k4[1]))
    except ArithmeticError:
        theta.append(math.pi / 2)
    return theta, log_f


def radial_flow(semi_angle: float, m: float, symmetry: str, steps: int = 400) -> RadialFlow:
    """Shield's cone flow ("axisymmetric", J. Mech. Phys. Solids 3 (1955)) or Nadai's wedge flow
    ("plane_strain", Hill ch. VIII) of a rigid-perfectly plastic von Mises material between walls
    with friction factor m (tau = m k), by shooting on the eigenvalue lambda:
    S(0) = 0, S(alpha) = m for the equations of _radial_flow_integrate (with lambda = c/2 the
    cone's is the reference's dS/dtheta + S cot theta = sqrt3 c - 2 sqrt3 sqrt(1 - S^2)); the mean
    axial stress rises by lambda sigma0 ln(A0/A1) (cone) or lambda 2k ln(h0/h1) (wedge).
    """
    cone = _is_axisymmetric(symmetry)
    alpha = math.radians(semi_angle)
    if not (0 < alpha < math.pi / 2 and 0 <= m <= 1):
        raise ValueError(f"need 0 < semi_angle < 90 and 0 <= m <= 1; got {semi_angle}, {m}")
    psi_wall = math.asin(m)
    if psi_wall == 0.0:
        grid = np.linspace(0.0, alpha, steps + 1)
        return RadialFlow(1.0, grid, np.zeros_like(grid), np.ones_like(grid))

    def miss(factor: float) -> float:
        return _radial_flow_integrate(factor, psi_wall, cone, steps)[0][-1] - alpha

    kappa, j = (SQRT3, 1.0) if cone else (1.0, 0.0)
    factor = _root(miss, *_bracket_decreasing(miss, 1 + (1 + j) * m / (2 * kappa * alpha)))
    theta, log_f = _radial_flow_integrate(factor, psi_wall, cone, steps)
    return RadialFlow(factor, np.array(theta), np.sin(np.linspace(0.0, psi_wall, steps + 1)),
                      np.exp(log_f))


def shield_cone_factor(semi_angle: float, m: float) -> float:
    """c/2 of Shield's cone flow (radial_flow, axisymmetric): the cone zone's mean axial stress
    rises by (c/2) sigma0 ln(A0/A1); 1 for m = 0 (homogeneous radial flow)."""
    return radial_flow(semi_angle, m, "axisymmetric").factor


def nadai_wedge_factor(semi_angle: float, m: float) -> float:
    """Nadai's wedge flow in closed form (Hill, The Mathematical Theory of Plasticity, ch. VIII):
    tau = k sin 2psi, theta = -psi + c/sqrt(c^2 - 1) arctan(sqrt((c + 1)/(c - 1)) tan psi), c from
    theta = alpha at the wall sin 2psi = m; the mean axial stress rises by c 2k ln(h0/h1)."""
    alpha = math.radians(semi_angle)
    psi = 0.5 * math.asin(m)
    if psi == 0.0:
        return 1.0

    def miss(c: float) -> float:
        root = math.sqrt(c * c - 1)
        return -psi + c / root * math.atan(math.sqrt((c + 1) / (c - 1)) * math.tan(psi)) - alpha

    return _root(miss, *_bracket_decreasing(miss, 1 + m / alpha))


# --- 3D: a rectangular bar through a die of plane faces (derived here) ---------------------------

class RectangularDie(NamedTuple):
    """The quarter of a rectangular bar's pass (half-sizes): half-heights h0 -> h1 and half-widths
    w0 -> w1 over the cone length, the height faces' slope tan(alpha) (die_angle), the width faces'
    tan(beta) = (w0 - w1)/length (the same cone length, as geometry.width_angle), and a land."""

    h0: float
    h1: float
    w0: float
    w1: float
    tan_alpha: float
    tan_beta: float
    length: float
    land: float

    @classmethod
    def of(cls, entry_height: float, exit_height: float, entry_width: float, exit_width: float,
           semi_angle: float, land_length: float = 0.0) -> RectangularDie:
        """From the scene's full sizes and the height faces' semi-angle (degrees)."""
        if not (0 < exit_height < entry_height and 0 < exit_width <= entry_width
                and 0 < semi_angle < 90 and land_length >= 0):
            raise ValueError("need 0 < exit < entry height, 0 < exit <= entry width, "
                             f"0 < semi_angle < 90, land >= 0; got {entry_height}, {exit_height}, "
                             f"{entry_width}, {exit_width}, {semi_angle}, {land_length}")
        tan_alpha = math.tan(math.radians(semi_angle))
        length = 0.5 * (entry_height - exit_height) / tan_alpha
        return cls(0.5 * entry_height, 0.5 * exit_height, 0.5 * entry_width, 0.5 * exit_width,
                   tan_alpha, 0.5 * (entry_width - exit_width) / length, length, land_length)

    @property
    def width_angle(self) -> float:
        """The width faces' semi-angle beta (degrees)."""
        return math.degrees(math.atan(self.tan_beta))

    @property
    def log_area_ratio(self) -> float:
        """ln(A0/A1), the ideal work over sigma0."""
        return math.log(self.h0 * self.w0 / (self.h1 * self.w1))

    def sections(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Half-height and half-width at x from the die entry (0 <= x <= length)."""
        return self.h0 - x * self.tan_alpha, self.w0 - x * self.tan_beta

    def effective_angle(self, x: float) -> float:
        """The semi-angle (degrees) of the round die whose slab equation has the same
        coefficient at x: tan(alpha_e) = (w tan alpha + h tan beta)/(h + w), the faces' slopes
        weighted by their widths (the area's decrease per perimeter, -dA/dx = P tan alpha_e)."""
        h, w = self.sections(np.asarray(x, dtype=float))
        return math.degrees(math.atan(float((w * self.tan_alpha + h * self.tan_beta) / (h + w))))


def sachs_rectangular_drawing_stress(die: RectangularDie, mu: float) -> float:
    """Sachs' slab method for a rectangular bar through a die of plane faces with Coulomb friction
    (derived here, Dieter's slab assumptions for the round die: plane sections, sigma_x + p = Ybar,
    the die pressure p on every face), sigma_d/Ybar. The axial balance of a slice of the quarter
    (area A = h w, the faces' slopes and widths) gives, with s = sigma_x/Ybar,

        ds/dx = -d ln A/dx + mu (1/h + 1/w)(1 - s),   -d ln A/dx = tan(alpha)/h + tan(beta)/w,

    linear in s, integrated exactly with its integrating factor E(x) = exp(int mu (1/h + 1/w));
    over a land (A constant) s_f = 1 - (1 - s_d) exp(-mu L (1/h1 + 1/w1)). For a square (and any
    die whose faces share one slope) it is Sachs' round-die formula of the same area reduction and
    semi-angle (sachs_drawing_stress); mu = 0 gives ln(A0/A1) exactly.
    """
    def friction_log(x: np.ndarray) -> np.ndarray:  # int_0^x mu (1/h + 1/w)
        h, w = die.sections(x)
        width = (np.log(die.w0 / w) / die.tan_beta if die.tan_beta > 0 else x / die.w0)
        return mu * (np.log(die.h0 / h) / die.tan_alpha + width)

    end = float(friction_log(np.array(die.length)))

    def source(x: np.ndarray) -> np.ndarray:
        h, w = die.sections(x)
        rate = die.tan_alpha / h + die.tan_beta / w + mu * (1 / h + 1 / w)
        return rate * np.exp(friction_log(x) - end)

    cone = _gauss_legendre(source, 0.0, die.length, nodes=48)
    land = math.exp(-mu * die.land * (1 / die.h1 + 1 / die.w1))
    return 1 - (1 - cone) * land


def _corner_distance_mean(a: float, b: float) -> float:
    """int_0^1 int_0^1 sqrt(a^2 s^2 + b^2 t^2) ds dt, the mean speed of the shear at an entry or
    exit plane: int_0^a int_0^b sqrt(x^2 + y^2) dy dx / (a b), whose closed form is
    [2 a b d + a^3 ln((b + d)/a) + b^3 ln((a + d)/b)]/6, d = sqrt(a^2 + b^2)."""
    if a == 0.0 or b == 0.0:
        return 0.5 * (a + b)
    d = math.hypot(a, b)
    return (2 * a * b * d + a**3 * math.log((b + d) / a) + b**3 * math.log((a + d) / b)) / (
        6 * a * b)


def _face_slip_mean(c: float, t: float) -> float:
    """int_0^1 sqrt(c^2 + t^2 s^2) ds = [sqrt(c^2 + t^2) + (c^2/t) asinh(t/c)]/2 (c at t = 0)."""
    if t == 0.0:
        return c
    return 0.5 * (math.hypot(c, t) + c * c / t * math.asinh(t / c))


class BoundParts(NamedTuple):
    """An upper bound's parts, each over sigma0 (the power per unit flux): the zone's internal
    power, the shear at the entry and exit planes, the friction on the converging faces, the
    friction on the land."""

    internal: float
    shear: float
    friction: float
    land: float

    @property
    def total(self) -> float:
        return self.internal + self.shear + self.friction + self.land


def rectangular_upper_bound(die: RectangularDie, m: float, nodes: int = 24) -> BoundParts:
    """An upper bound on sigma_d/sigma0 for a rectangular bar through a die of plane faces with the
    friction factor m (tau = m k), derived here: the homogeneous-compression field in which every
    section stays a rectangle and each point keeps its place in it (y/h, z/w fixed),

        u_x = U(x) = Q/(4 h w),   u_y = U y h'/h,   u_z = U z w'/w,

    incompressible and tangent to every face, rigid before the entry plane and after the exit
    plane (velocity jumps U sqrt((y/h)^2 tan^2 alpha + (z/w)^2 tan^2 beta) there). With
    p = tan(alpha)/h, q = tan(beta)/w its strain rates are e_yy = -U p, e_zz = -U q,
    e_xx = U (p + q), e_xy = -(U/2)(y/h) tan(alpha)(2p + q), e_xz = -(U/2)(z/w) tan(beta)(p + 2q),
    e_yz = 0, and the power per unit flux and sigma0 is

        internal: int_0^L dx int int sqrt((2/3)(e:e))/U d(y/h) d(z/w)   (Gauss-Legendre),
        shear:    (2/sqrt3) J(tan alpha, tan beta),  J the mean of sqrt(tan^2 alpha s^2
                  + tan^2 beta t^2) over the unit square (closed form, two planes),
        friction: (m/sqrt3)[sec(alpha) G(sec alpha, tan beta) ln(h0/h1)/tan(alpha)
                  + sec(beta) G(sec beta, tan alpha) int_0^L dx/w],  G(c, t) the mean of
                  sqrt(c^2 + t^2 s^2) over [0, 1] (the slip speed over U on a face),
        land:     (m/sqrt3) L_land (1/h1 + 1/w1).

    Where the faces converge to one apex (similar sections: a square) its streamlines are the rays
    toward it (a radial flow), with plane (not spherical, as Avitzur's) discontinuities. Without
    width reduction and w -> infinity it is the plane-strain parallel field's bound; frictionless
    and at small angles (a square) it tends to the ideal work ln(A0/A1).
    """
    a, b = die.tan_alpha, die.tan_beta
    g, wg = np.polynomial.legendre.leggauss(nodes)
    s, ws = 0.5 * (g + 1), 0.5 * wg  # on [0, 1]
    x = die.length * s
    h, w = die.sections(x)
    p, q = (a / h)[:, None, None], (b / w)[:, None, None]
    eta, zeta = s[None, :, None], s[None, None, :]
    squares = ((p + q) ** 2 + p**2 + q**2 + 0.5 * (eta * a * (2 * p + q)) ** 2
               + 0.5 * (zeta * b * (p + 2 * q)) ** 2)
    rate = np.sqrt(2 / 3 * squares)  # over U
    internal = die.length * float(np.einsum("i,j,k,ijk->", ws, ws, ws, rate))
    shear = 2 / SQRT3 * _corner_distance_mean(a, b)
    sec_a, sec_b = math.hypot(1, a), math.hypot(1, b)
    width_log = math.log(die.w0 / die.w1) / b if b > 0 else die.length / die.w0
    friction = m / SQRT3 * (sec_a * _face_slip_mean(sec_a, b) * math.log(die.h0 / die.h1) / a
                            + sec_b * _face_slip_mean(sec_b, a) * width_log)
    land = m / SQRT3 * die.land * (1 / die.h1 + 1 / die.w1)
    return BoundParts(internal, shear, friction, land)


# --- Section 5: central burst --------------------------------------------------------------------

def central_burst_indicator(reduction: float, semi_angle: float, symmetry: str) -> float:
    """Delta = mean thickness / contact length of the pass: (alpha/r)(1 + sqrt(1 - r))^2 for a round
    bar ("axisymmetric"), (alpha/r)(2 - r) for a strip ("plane_strain"), alpha in radians; large
    Delta (small reductions through wide dies) favours central bursts and redundant work."""
    alpha = math.radians(semi_angle)
    if _is_axisymmetric(symmetry):
        return alpha / reduction * (1 + math.sqrt(1 - reduction)) ** 2
    return alpha / reduction * (2 - reduction)


# --- Section 1: exact radial flows through smooth dies -------------------------------------------

def radial_flow_strain(r0: float, r1: float, symmetry: str) -> float:
    """Equivalent strain gained from radius r0 to r1 in the smooth-die radial flow: 2 ln(r0/r1)
    = ln(A0/A1) in the cone, (2/sqrt3) ln(r0/r1) in the wedge."""
    return (2.0 if _is_axisymmetric(symmetry) else 2 / SQRT3) * math.log(r0 / r1)


def radial_flow_stress_rise(r0: float, r1: float, K: float, n: float, flux: float,
                            symmetry: str) -> float:
    """sigma_rr(r1) - sigma_rr(r0) of the smooth-die radial flow of a Norton law sigma = K rate^n.

    Cone, v = -(U/rho^2) e_rho, flux = U, rate = 2U/rho^3, d sigma_rr/d rho = -2 sigma/rho:
    (2K/(3n)) (2U)^n (r1^(-3n) - r0^(-3n)). Wedge, v = -(Q/r) e_r, flux = Q, rate = (2/sqrt3) Q/r^2,
    d sigma_rr/dr = -(2/sqrt3) sigma/r: (K/(sqrt3 n)) (2Q/sqrt3)^n (r1^(-2n) - r0^(-2n)).
    Both written with (e^x - 1)/x, so n = 0 gives K ln(A0/A1) and 2 (K/sqrt3) ln(r0/r1) exactly.
    """
    log_ratio = math.log(r0 / r1)
    if _is_axisymmetric(symmetry):
        return 2 * K * (2 * flux / r0**3) ** n * log_ratio * _expm1_over(3 * n * log_ratio)
    return 2 / SQRT3 * K * (2 / SQRT3 * flux / r0**2) ** n * log_ratio * _expm1_over(
        2 * n * log_ratio)


def swift_stress_rise(strain0: float, strain1: float, K: float, n: float,
                      prestrain: float = 0.0) -> float:
    """int sigma d(strain) from strain0 to strain1 for Swift's law K (prestrain + strain)^n
    (Hollomon for prestrain = 0): K [(e0 + e1)^(n+1) - (e0 + e)^(n+1)]/(n + 1), the stress rise of
    any smooth-die radial flow between the strains of radial_flow_strain."""
    return K * ((prestrain + strain1) ** (n + 1) - (prestrain + strain0) ** (n + 1)) / (n + 1)


def voce_stress_rise(strain0: float, strain1: float, saturation: float, initial: float,
                     scale: float) -> float:
    """int sigma d(strain) from strain0 to strain1 for Voce's law
    sigma_s - (sigma_s - sigma_y) exp(-strain/eps_c): sigma_s (e1 - e0)
    - (sigma_s - sigma_y) eps_c (exp(-e0/eps_c) - exp(-e1/eps_c))."""
    return saturation * (strain1 - strain0) - (saturation - initial) * scale * (
        math.exp(-strain0 / scale) - math.exp(-strain1 / scale))

"""Rigid-plastic flow-stress laws sigma_p(rate[, strain]) and their secant coefficient.

Each law gives the uniaxial yield limit sigma_p and the secant coefficient G = sigma_p/rate used by
a(w; u, v) of (3.2); every law satisfies (2.10) (eta_1 <= d sigma_p/d rate <= sigma_p/rate <= eta_2)
in the rate on the parameters its ``check`` accepts. The paper's (4.5) and the rate power law depend
on the rate only; Hollomon, Swift and Voce harden with the equivalent strain, times a rate factor.
"""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import ClassVar, Self

import numpy as np
import ufl

from forming_fenicsx.core.errors import SceneError
from forming_fenicsx.core.relative import resolve_pair

RATE_FLOOR_RELATIVE = 1e-6  # the default rate floor, relative to the process strain rate


class _RateFloor:
    """A law linear in the rate below ``rate_floor``, absolute or ``rate_floor_relative`` times
    the process strain rate: the floor keeps the secant bounded at rate 0, as (2.10) needs."""

    def resolve(self, process_rate: float) -> Self:
        """The law with its rate floor absolute (and relative to the process strain rate)."""
        floor, relative = resolve_pair("material", self, "rate_floor", process_rate,
                                       RATE_FLOOR_RELATIVE)
        return dataclasses.replace(self, rate_floor=floor, rate_floor_relative=relative)


@dataclass(frozen=True)
class PiecewisePowerLaw:
    """The paper's law (4.5): linear below rate1, A*rate**alpha on [rate1, rate2], linear above
    rate2."""

    A: float = math.sqrt(3.0)
    alpha: float = 1e-3
    rate1: float = 1e-3
    rate2: float = 1e3
    law: str = "piecewise_power"
    hardens: ClassVar[bool] = False
    heats: ClassVar[bool] = False  # reads the temperature

    def check(self, section: str = "material") -> None:
        """Reject parameters that break (2.10)."""
        if not self.A > 0:
            raise SceneError(f"{section}.A",
                             f"must be > 0 (a positive flow stress scale); got {self.A}")
        if not 0 < self.alpha <= 1:
            raise SceneError(f"{section}.alpha",
                             "must lie in (0, 1] for (2.10) (sigma_p' <= sigma_p/rate); "
                             f"got {self.alpha}")
        if not self.rate1 > 0:
            raise SceneError(f"{section}.rate1",
                             f"must be > 0 for (2.10) (bounded secant); got {self.rate1}")
        if not self.rate2 > self.rate1:
            raise SceneError(f"{section}.rate2",
                             f"must be > material.rate1 ({self.rate1}); got {self.rate2}")

    def resolve(self, process_rate: float) -> PiecewisePowerLaw:
        """The law with every value absolute: (4.5)'s constants are the material's own."""
        return self

    def flow_stress(self, rate: np.ndarray) -> np.ndarray:
        """sigma_p(rate) of (4.5)."""
        return self.secant(rate) * np.asarray(rate, dtype=float)

    def secant(self, rate: np.ndarray) -> np.ndarray:
        """G(rate) = sigma_p(rate)/rate of (4.5); bounded by eta_2 = A*rate1**(alpha-1)."""
        clipped = np.clip(np.asarray(rate, dtype=float), self.rate1, self.rate2)
        return self.A * clipped ** (self.alpha - 1.0)

    @property
    def rate_floor(self) -> float:
        """The rate below which the secant is constant (rate1 of (4.5))."""
        return self.rate1

    def secant_ufl(self, rate, strain=None, temperature=None):
        """G(rate) of (4.5) as a UFL expression, for evaluation at quadrature points (no strain
        dependence: ``strain`` is accepted as every law's is)."""
        clipped = ufl.min_value(ufl.max_value(rate, self.rate1), self.rate2)
        return self.A * clipped ** (self.alpha - 1.0)

    def potential_ufl(self, rate, strain=None, temperature=None):
        """W(rate) = int_0^rate sigma_p(s) ds of (4.5), whose derivative is sigma_p: the dissipation
        potential minimised by the solution (the energy of the Newton line search)."""
        g1 = self.A * self.rate1 ** (self.alpha - 1.0)
        g2 = self.A * self.rate2 ** (self.alpha - 1.0)
        w1 = g1 * self.rate1**2 / 2

        def power(r):
            return (self.A * (r ** (self.alpha + 1.0) - self.rate1 ** (self.alpha + 1.0))
                    / (self.alpha + 1.0))

        w2 = w1 + power(self.rate2)
        return ufl.conditional(ufl.lt(rate, self.rate1), g1 * rate**2 / 2,
                               ufl.conditional(ufl.lt(rate, self.rate2), w1 + power(rate),
                                               w2 + g2 * (rate**2 - self.rate2**2) / 2))


@dataclass(frozen=True)
class PowerLaw(_RateFloor):
    """The strain-rate power law sigma_p = A*rate**n (``law = "rate_power"``: no strain hardening;
    Hollomon's K eps^n is ``law = "hollomon"``), with a floor rate_floor below which the secant is
    constant.

    Without the floor the secant A*rate**(n-1) is unbounded at rate -> 0 and (2.10) fails; with it,
    (2.10) holds on every bounded range of rates. The floor is a regularisation, not a material
    constant: absolute, or ``rate_floor_relative`` times the process strain rate (default
    RATE_FLOOR_RELATIVE).
    """

    A: float = math.sqrt(3.0)
    n: float = 0.5
    rate_floor: float | None = None
    rate_floor_relative: float | None = None
    law: str = "rate_power"
    hardens: ClassVar[bool] = False
    heats: ClassVar[bool] = False

    def check(self, section: str = "material") -> None:
        """Reject parameters that break (2.10)."""
        if not self.A > 0:
            raise SceneError(f"{section}.A",
                             f"must be > 0 (a positive flow stress scale); got {self.A}")
        if not 0 < self.n <= 1:
            raise SceneError(f"{section}.n", "must lie in (0, 1] for (2.10) "
                             f"(sigma_p' <= sigma_p/rate); got {self.n}")
        if not (self.rate_floor is not None and self.rate_floor > 0):
            raise SceneError(f"{section}.rate_floor", "must be > 0: it bounds the secant at zero "
                             f"rate (2.10); got {self.rate_floor}")

    def flow_stress(self, rate: np.ndarray) -> np.ndarray:
        """sigma_p(rate), linear below rate_floor."""
        return self.secant(rate) * np.asarray(rate, dtype=float)

    def secant(self, rate: np.ndarray) -> np.ndarray:
        """G(rate) = sigma_p/rate = A*max(rate, rate_floor)**(n-1)."""
        return self.A * np.maximum(np.asarray(rate, dtype=float), self.rate_floor) ** (self.n - 1.0)

    def secant_ufl(self, rate, strain=None, temperature=None):
        """G(rate) as a UFL expression, for evaluation at quadrature points (no strain
        dependence)."""
        return self.A * ufl.max_value(rate, self.rate_floor) ** (self.n - 1.0)

    def potential_ufl(self, rate, strain=None, temperature=None):
        """W(rate) = int_0^rate sigma_p(s) ds (quadratic below rate_floor)."""
        g = self.A * self.rate_floor ** (self.n - 1.0)
        w1 = g * self.rate_floor**2 / 2
        return ufl.conditional(ufl.lt(rate, self.rate_floor), g * rate**2 / 2,
                               w1 + self.A * (rate ** (self.n + 1.0)
                                              - self.rate_floor ** (self.n + 1.0))
                               / (self.n + 1.0))


# The exponent that stands for rate independence: (2.10) needs sigma_p to rise with the rate; this
# one changes it by 1.4 % over six decades (the paper's alpha of (4.5)).
RATE_INDEPENDENT_EXPONENT = 1e-3
RATE_FACTORS = ("none", "power", "log")
# Gauss-Legendre points per smooth piece of a hardening curve, for its mean over a pass
MEAN_POINTS = 32


@dataclass(frozen=True)
class _Hardening(_RateFloor):
    """sigma_p(rate, eps) = H(eps) r(rate): a hardening curve H of the equivalent strain times a
    rate factor r with r(reference_rate) = 1:
    - ``rate_factor = "none"``: r = (rate/ref)^1e-3 (rate-independent up to the exponent (2.10)
      needs),
    - ``"power"``: r = (rate/ref)^m, 0 < m <= 1,
    - ``"log"``: r = 1 + C ln(rate/ref) above ref (Johnson-Cook), (rate/ref)^C below, 0 < C <= 1,
    each linear in the rate below ``rate_floor`` (absolute, or ``rate_floor_relative`` times the
    process strain rate), where the secant G = sigma_p/rate stays bounded (2.10).
    ``strain`` is the equivalent strain as a UFL expression (the transported field); left out, H is
    taken at ``initial_strain``, which also gives the scene's reference flow stress. The strain
    flowing in is ``initial_strain``, or a profile across the entry section read from
    ``initial_strain_file`` (strain_profile.py: a previous pass's exit_strain.csv). With
    ``softening`` (1/K) and ``softening_temperature`` (K) the law reads the [thermal] temperature
    through exp(-softening (T - softening_temperature)), Hensel-Spittel's e^(m1 T) (without
    [thermal] the factor is 1)."""

    rate_factor: str = "none"
    m: float | None = None
    C: float | None = None
    reference_rate: float = 1.0
    rate_floor: float | None = None
    rate_floor_relative: float | None = None
    initial_strain: float = 0.0
    initial_strain_file: str | None = None
    softening: float | None = None
    softening_temperature: float | None = None
    name: str | None = None
    hardens: ClassVar[bool] = True

    @property
    def heats(self) -> bool:
        """Whether the law reads the temperature: with a softening factor."""
        return self.softening is not None

    def check(self, section: str = "material") -> None:
        """The rate factor's parameters (2.10), then the hardening curve's (_check_curve)."""
        if self.rate_factor not in RATE_FACTORS:
            raise SceneError(f"{section}.rate_factor",
                             f"must be one of {', '.join(RATE_FACTORS)}; got {self.rate_factor!r}")
        needed = {"none": None, "power": "m", "log": "C"}[self.rate_factor]
        for key in ("m", "C"):
            value = getattr(self, key)
            if key != needed and value is not None:
                raise SceneError(f"{section}.{key}", f"does not apply to rate_factor = "
                                 f"{self.rate_factor!r}; leave it out")
            if key == needed and not (value is not None and 0 < value <= 1):
                raise SceneError(f"{section}.{key}", "must lie in (0, 1] for (2.10) (sigma_p "
                                 f"rising with the rate, sigma_p/rate falling); got {value}")
        for key in ("reference_rate", "rate_floor"):
            if not (getattr(self, key) is not None and getattr(self, key) > 0):
                raise SceneError(f"{section}.{key}",
                                 f"must be a finite number > 0; got {getattr(self, key)}")
        if (self.softening is None) != (self.softening_temperature is None):
            raise SceneError(f"{section}.softening", "give softening (1/K) and "
                             "softening_temperature (K, where the factor is 1) together, or "
                             "neither")
        if self.softening is not None:
            if not self.softening >= 0:
                raise SceneError(f"{section}.softening", f"must be a finite number >= 0 (1/K); got "
                                 f"{self.softening}")
            _check_positive(section, "softening_temperature", self.softening_temperature)
        if not self.initial_strain >= 0:
            raise SceneError(f"{section}.initial_strain",
                             f"must be a finite number >= 0; got {self.initial_strain}")
        if self.initial_strain_file is not None:
            if self.initial_strain != 0:
                raise SceneError(f"{section}.initial_strain", "give the inflow strain as a number "
                                 f"or as {section}.initial_strain_file (a profile), not both")
        self._check_curve(section)

    def _thermal(self, temperature, lib):
        """The softening factor exp(-softening (T - softening_temperature)) (Hensel-Spittel's
        e^(m1 T)); 1 without softening or without a temperature."""
        if self.softening is None or temperature is None:
            return 1.0
        return lib.exp(-self.softening * (temperature - self.softening_temperature))

    @property
    def _exponent(self) -> float:
        return {"none": RATE_INDEPENDENT_EXPONENT, "power": self.m, "log": self.C}[self.rate_factor]

    def _factor(self, rate, lib):
        """r(rate) at rate >= rate_floor (``lib``: numpy or the UFL namespace below)."""
        ratio = rate / self.reference_rate
        power = ratio ** self._exponent
        if self.rate_factor != "log":
            return power
        return lib.where(ratio > 1.0, 1.0 + self.C * lib.log(lib.maximum(ratio, 1.0)), power)

    def rate_factor_value(self, rate: np.ndarray) -> np.ndarray:
        """r(rate) (linear below the floor)."""
        rate = np.asarray(rate, dtype=float)
        floored = np.maximum(rate, self.rate_floor)
        return self._factor(floored, np) * np.minimum(rate / self.rate_floor, 1.0)

    def kinks(self) -> tuple[float, ...]:
        """The strains where H has a kink (Hollomon's floor): mean_flow_stress integrates
        piecewise between them."""
        return ()

    def mean_flow_stress(self, rate: float, low: float, high: float) -> float:
        """(1/(high - low)) int_low^high sigma_p(rate, eps) d eps: the mean flow stress of a pass
        that takes the strain from ``low`` to ``high`` (sigma_p(rate, low) when they are equal),
        by Gauss-Legendre (MEAN_POINTS) on the pieces between the curve's kinks."""
        if not high > low:
            return float(self.flow_stress([rate], low)[0])
        inner = [k for k in self.kinks() if low < k < high]
        cuts = [low, *inner, high]
        points, weights = np.polynomial.legendre.leggauss(MEAN_POINTS)
        integral = sum(0.5 * (b - a) * float(weights @ self.hardening(
            0.5 * (b - a) * points + 0.5 * (a + b), np)) for a, b in zip(cuts, cuts[1:]))
        return integral / (high - low) * float(self.rate_factor_value(np.array([rate]))[0])

    def flow_stress(self, rate: np.ndarray, strain: np.ndarray | float | None = None,
                    temperature=None) -> np.ndarray:
        """sigma_p(rate, strain[, T]), the strain ``initial_strain`` when not given."""
        strain = self.initial_strain if strain is None else strain
        return (self.hardening(np.asarray(strain, dtype=float), np) * self.rate_factor_value(rate)
                * self._thermal(temperature, np))

    def secant(self, rate: np.ndarray, strain: np.ndarray | float | None = None,
               temperature=None) -> np.ndarray:
        """G = sigma_p/rate, bounded by its value at the rate floor."""
        rate = np.maximum(np.asarray(rate, dtype=float), self.rate_floor)
        return self.flow_stress(rate, strain, temperature) / rate

    def secant_ufl(self, rate, strain=None, temperature=None):
        """G(rate, strain[, T]) as a UFL expression (the strain a UFL expression, e.g. the
        transported field, or the initial strain; T the [thermal] field when the law softens)."""
        strain = self.initial_strain if strain is None else strain
        floored = ufl.max_value(rate, self.rate_floor)
        return (self.hardening(strain, UFL) * self._factor(floored, UFL) / floored
                * self._thermal(temperature, UFL))

    def potential_ufl(self, rate, strain=None, temperature=None):
        """W(rate) = int_0^rate sigma_p(s, strain) ds at the (frozen) strain: H(strain) times the
        integral of the rate factor, quadratic below the floor."""
        strain = self.initial_strain if strain is None else strain
        f, ref, k = self.rate_floor, self.reference_rate, self._exponent
        below = self._factor(f, np) / f * rate**2 / 2  # the linear part's integral
        at_floor = self._factor(f, np) * f / 2

        def power_integral(a, b):  # int_a^b (s/ref)^k ds
            return ref * ((b / ref) ** (k + 1) - (a / ref) ** (k + 1)) / (k + 1)

        if self.rate_factor == "log" and f < ref:
            upper = ufl.conditional(
                ufl.lt(rate, ref), power_integral(f, rate),
                power_integral(f, ref) + (rate - ref)
                + self.C * (rate * ufl.ln(rate / ref) - rate + ref))
        elif self.rate_factor == "log":  # the floor above ref: only the logarithmic branch
            upper = (rate - f) + self.C * (rate * ufl.ln(rate / ref) - rate
                                           - f * math.log(f / ref) + f)
        else:
            upper = power_integral(f, rate)
        return self.hardening(strain, UFL) * self._thermal(temperature, UFL) * ufl.conditional(
            ufl.lt(rate, f), below, at_floor + upper)


class _UflMath:
    """The numpy functions the laws use, for UFL expressions."""

    exp = staticmethod(ufl.exp)
    log = staticmethod(ufl.ln)
    sqrt = staticmethod(ufl.sqrt)
    maximum = staticmethod(ufl.max_value)

    @staticmethod
    def where(condition, a, b):
        return ufl.conditional(condition, a, b)


UFL = _UflMath()


@dataclass(frozen=True)
class HollomonLaw(_Hardening):
    """Hollomon: H = K max(eps, strain_floor)^n; the floor (default 0.002, the 0.2 % offset strain)
    keeps the yield stress of undeformed material positive, as (2.10) needs."""

    K: float | None = None
    n: float | None = None
    strain_floor: float = 0.002
    law: str = "hollomon"

    def _check_curve(self, section: str) -> None:
        _check_positive(section, "K", self.K)
        if not (self.n is not None and 0 <= self.n < 1):
            raise SceneError(f"{section}.n",
                             f"must lie in [0, 1) (Hollomon's exponent); got {self.n}")
        _check_positive(section, "strain_floor", self.strain_floor)

    def hardening(self, strain, lib):
        return self.K * lib.maximum(strain, self.strain_floor) ** self.n

    def kinks(self) -> tuple[float, ...]:
        return (self.strain_floor,)


@dataclass(frozen=True)
class SwiftLaw(_Hardening):
    """Swift: H = K (prestrain + eps)^n, prestrain > 0."""

    K: float | None = None
    n: float | None = None
    prestrain: float | None = None
    law: str = "swift"

    def _check_curve(self, section: str) -> None:
        _check_positive(section, "K", self.K)
        _check_positive(section, "prestrain", self.prestrain)
        if not (self.n is not None and 0 <= self.n < 1):
            raise SceneError(f"{section}.n", f"must lie in [0, 1) (Swift's exponent); got {self.n}")

    def hardening(self, strain, lib):
        return self.K * (self.prestrain + lib.maximum(strain, 0.0)) ** self.n


@dataclass(frozen=True)
class VoceLaw(_Hardening):
    """Voce: H = saturation - (saturation - initial) exp(-eps/scale), 0 < initial <= saturation."""

    initial: float | None = None
    saturation: float | None = None
    scale: float | None = None
    law: str = "voce"

    def _check_curve(self, section: str) -> None:
        _check_positive(section, "initial", self.initial)
        _check_positive(section, "scale", self.scale)
        if not (self.saturation is not None and self.saturation >= self.initial):
            raise SceneError(f"{section}.saturation", "must be >= material.initial "
                             f"({self.initial}): Voce's curve rises to it; got {self.saturation}")

    def hardening(self, strain, lib):
        return self.saturation - (self.saturation - self.initial) * lib.exp(
            -lib.maximum(strain, 0.0) / self.scale)


R_GAS = 8.314  # J/(mol K)
# Gauss-Legendre points of the Sellars-Tegart potential (the line search's merit)
POTENTIAL_POINTS = 8


@dataclass(frozen=True)
class SellarsTegartLaw(_RateFloor):
    """Sellars-Tegart (Zener-Hollomon), the hot-working law of reference section 4:
    sigma_p = (1/alpha_s) asinh((Z/A)^(1/n)), Z = rate exp(Q/(R T)), R = 8.314 J/(mol K), T in
    kelvin, linear in the rate below ``rate_floor`` (absolute, or ``rate_floor_relative`` times the
    process strain rate) where (2.10) needs a bounded secant; n >= 1 keeps sigma_p/rate falling.
    ``alpha_s`` in 1/stress, ``A`` in 1/time, ``Q`` in J/mol. The temperature is the scene's
    [thermal] field (coupled to the flow), or ``temperature``, the workpiece's, isothermal; with
    [thermal] it is the inflow temperature, for the scene's scales. Its dissipation potential has no
    closed form: Newton's line search evaluates it by Gauss-Legendre quadrature in ln(rate) (its
    residual is exact)."""

    alpha_s: float | None = None
    n: float | None = None
    Q: float | None = None
    A: float | None = None
    temperature: float | None = None
    rate_floor: float | None = None
    rate_floor_relative: float | None = None
    name: str | None = None
    law: str = "sellars_tegart"
    hardens: ClassVar[bool] = False
    heats: ClassVar[bool] = True

    def check(self, section: str = "material") -> None:
        for key in ("alpha_s", "A", "temperature", "rate_floor"):
            _check_positive(section, key, getattr(self, key))
        if not (self.n is not None and self.n >= 1):
            raise SceneError(f"{section}.n", f"must be >= 1 for (2.10) (sigma_p/rate falling with "
                             f"the rate); got {self.n}")
        if not (self.Q is not None and self.Q >= 0):
            raise SceneError(f"{section}.Q", f"must be a finite number >= 0 (J/mol); got {self.Q}")

    def _sigma(self, rate, temperature, lib):
        """sigma_p at rate >= rate_floor; asinh(x) = ln(x + sqrt(x^2 + 1))."""
        x = (rate * lib.exp(self.Q / (R_GAS * temperature)) / self.A) ** (1.0 / self.n)
        return lib.log(x + lib.sqrt(x * x + 1.0)) / self.alpha_s

    def flow_stress(self, rate: np.ndarray, strain=None, temperature=None) -> np.ndarray:
        """sigma_p(rate, T) (T the law's ``temperature`` when not given), linear below the floor."""
        rate = np.asarray(rate, dtype=float)
        floored = np.maximum(rate, self.rate_floor)
        with np.errstate(over="ignore"):  # an infinite stress: the scene check names the law
            temperature = self.temperature if temperature is None else temperature
            value = self._sigma(floored, temperature, np)
        return value * np.minimum(rate / self.rate_floor, 1.0)

    def secant(self, rate: np.ndarray, strain=None, temperature=None) -> np.ndarray:
        """G = sigma_p/rate, bounded by its value at the rate floor."""
        rate = np.maximum(np.asarray(rate, dtype=float), self.rate_floor)
        return self.flow_stress(rate, temperature=temperature) / rate

    def secant_ufl(self, rate, strain=None, temperature=None):
        """G(rate, T) as a UFL expression (T a UFL field, or the law's temperature)."""
        temperature = self.temperature if temperature is None else temperature
        floored = ufl.max_value(rate, self.rate_floor)
        return self._sigma(floored, temperature, UFL) / floored

    def potential_ufl(self, rate, strain=None, temperature=None):
        """W(rate) = int_0^rate sigma_p ds: quadratic below the floor, above it
        W(f) + ln(rate/f) int_0^1 sigma_p(s) s dt, s = f (rate/f)^t, by Gauss-Legendre."""
        temperature = self.temperature if temperature is None else temperature
        f = self.rate_floor
        at_floor = self._sigma(f, temperature, UFL)
        upper = ufl.max_value(rate, f)
        span = ufl.ln(upper / f)
        nodes, weights = np.polynomial.legendre.leggauss(POTENTIAL_POINTS)
        integral = sum(0.5 * weight * self._sigma(f * (upper / f) ** t, temperature, UFL)
                       * f * (upper / f) ** t for t, weight in zip(0.5 * (nodes + 1), weights))
        return ufl.conditional(ufl.lt(rate, f), at_floor / f * rate**2 / 2,
                               at_floor * f / 2 + span * integral)


def rate_sensitivity(law, rate: float) -> float:
    """m = d ln sigma_p / d ln rate at ``rate`` (the law's own strain and temperature), a central
    difference over a factor 1.1 either side: 0 for a rate-independent law above its floor, alpha of
    (4.5) between rate1 and rate2, n of the rate power law."""
    low, high = law.flow_stress(np.array([rate / 1.1, rate * 1.1]))
    return float(np.log(high / low) / np.log(1.21))


def _check_positive(section: str, key: str, value: float | None) -> None:
    if not (value is not None and value > 0):
        raise SceneError(f"{section}.{key}", f"must be a finite number > 0; got {value}")


LAWS = {"piecewise_power": PiecewisePowerLaw, "rate_power": PowerLaw, "hollomon": HollomonLaw,
        "swift": SwiftLaw, "voce": VoceLaw, "sellars_tegart": SellarsTegartLaw}
FlowLaw = PiecewisePowerLaw | PowerLaw | HollomonLaw | SwiftLaw | VoceLaw | SellarsTegartLaw

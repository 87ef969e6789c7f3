"""Rigid-plastic, strain-rate dependent flow-stress laws and their secant coefficient.

Each law gives the uniaxial yield limit sigma_p(rate) and the secant coefficient
G(rate) = sigma_p(rate)/rate used by a(w; u, v) of (3.2). Both laws satisfy (2.10)
(eta_1 <= sigma_p' <= sigma_p/rate <= eta_2) on the parameters their ``check`` accepts.
"""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np
import ufl

from .errors import SceneError
from .relative import resolve_pair

RATE_FLOOR_RELATIVE = 1e-6  # the power law's default rate floor, relative to the process strain rate


@dataclass(frozen=True)
class PiecewisePowerLaw:
    """The paper's law (4.5): linear below rate1, A*rate**alpha on [rate1, rate2], linear above rate2."""

    A: float = math.sqrt(3.0)
    alpha: float = 1e-3
    rate1: float = 1e-3
    rate2: float = 1e3
    law: str = "piecewise_power"

    def check(self, section: str = "material") -> None:
        """Reject parameters that break (2.10)."""
        if not self.A > 0:
            raise SceneError(f"{section}.A", f"must be > 0 (a positive flow stress scale); got {self.A}")
        if not 0 < self.alpha <= 1:
            raise SceneError(f"{section}.alpha",
                             f"must lie in (0, 1] for (2.10) (sigma_p' <= sigma_p/rate); got {self.alpha}")
        if not self.rate1 > 0:
            raise SceneError(f"{section}.rate1", f"must be > 0 for (2.10) (bounded secant); got {self.rate1}")
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

    def secant_ufl(self, rate):
        """G(rate) of (4.5) as a UFL expression, for evaluation at quadrature points."""
        clipped = ufl.min_value(ufl.max_value(rate, self.rate1), self.rate2)
        return self.A * clipped ** (self.alpha - 1.0)

    def potential_ufl(self, rate):
        """W(rate) = int_0^rate sigma_p(s) ds of (4.5), whose derivative is sigma_p: the dissipation
        potential minimised by the solution (the energy of the Newton line search)."""
        g1, g2 = self.A * self.rate1 ** (self.alpha - 1.0), self.A * self.rate2 ** (self.alpha - 1.0)
        w1 = g1 * self.rate1**2 / 2

        def power(r):
            return self.A * (r ** (self.alpha + 1.0) - self.rate1 ** (self.alpha + 1.0)) / (self.alpha + 1.0)

        w2 = w1 + power(self.rate2)
        return ufl.conditional(ufl.lt(rate, self.rate1), g1 * rate**2 / 2,
                               ufl.conditional(ufl.lt(rate, self.rate2), w1 + power(rate),
                                               w2 + g2 * (rate**2 - self.rate2**2) / 2))


@dataclass(frozen=True)
class PowerLaw:
    """Pure power law sigma_p = A*rate**n with a floor rate_floor below which the secant is constant.

    Without the floor the secant A*rate**(n-1) is unbounded at rate -> 0 and (2.10) fails; with it,
    (2.10) holds on every bounded range of rates. The floor is a regularisation, not a material
    constant: absolute, or ``rate_floor_relative`` times the process strain rate (default
    RATE_FLOOR_RELATIVE).
    """

    A: float = math.sqrt(3.0)
    n: float = 0.5
    rate_floor: float | None = None
    rate_floor_relative: float | None = None
    law: str = "power"

    def resolve(self, process_rate: float) -> PowerLaw:
        """The law with its rate floor absolute (and relative to the process strain rate)."""
        floor, relative = resolve_pair("material", self, "rate_floor", process_rate, RATE_FLOOR_RELATIVE)
        return dataclasses.replace(self, rate_floor=floor, rate_floor_relative=relative)

    def check(self, section: str = "material") -> None:
        """Reject parameters that break (2.10)."""
        if not self.A > 0:
            raise SceneError(f"{section}.A", f"must be > 0 (a positive flow stress scale); got {self.A}")
        if not 0 < self.n <= 1:
            raise SceneError(f"{section}.n", f"must lie in (0, 1] for (2.10) (sigma_p' <= sigma_p/rate); got {self.n}")
        if not (self.rate_floor is not None and self.rate_floor > 0):
            raise SceneError(f"{section}.rate_floor",
                             f"must be > 0: it bounds the secant at zero rate (2.10); got {self.rate_floor}")

    def flow_stress(self, rate: np.ndarray) -> np.ndarray:
        """sigma_p(rate), linear below rate_floor."""
        return self.secant(rate) * np.asarray(rate, dtype=float)

    def secant(self, rate: np.ndarray) -> np.ndarray:
        """G(rate) = sigma_p/rate = A*max(rate, rate_floor)**(n-1)."""
        return self.A * np.maximum(np.asarray(rate, dtype=float), self.rate_floor) ** (self.n - 1.0)

    def secant_ufl(self, rate):
        """G(rate) as a UFL expression, for evaluation at quadrature points."""
        return self.A * ufl.max_value(rate, self.rate_floor) ** (self.n - 1.0)

    def potential_ufl(self, rate):
        """W(rate) = int_0^rate sigma_p(s) ds (quadratic below rate_floor)."""
        g = self.A * self.rate_floor ** (self.n - 1.0)
        w1 = g * self.rate_floor**2 / 2
        return ufl.conditional(ufl.lt(rate, self.rate_floor), g * rate**2 / 2,
                               w1 + self.A * (rate ** (self.n + 1.0) - self.rate_floor ** (self.n + 1.0))
                               / (self.n + 1.0))


LAWS = {"piecewise_power": PiecewisePowerLaw, "power": PowerLaw}
FlowLaw = PiecewisePowerLaw | PowerLaw

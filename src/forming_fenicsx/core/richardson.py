"""Richardson extrapolation of a quantity computed on meshes of decreasing sizes, any size ratios,
and the guarded estimate of the finest value's error (docs/accuracy.md measures it against the
true error).

From the last three meshes h1 > h2 > h3 with values f1, f2, f3 and f(h) = F + C h^p: the observed
order p solves (f1 - f2)/(f2 - f3) = (h1^p - h2^p)/(h2^p - h3^p), the extrapolated value is
F = f3 - (f2 - f3) h3^p/(h2^p - h3^p) and the error of the finest value is estimated as
FACTOR |f3 - F|. A sequence outside its asymptotic range is guarded against: when the differences
change sign (an oscillation) the estimate is FACTOR |f3 - f2| and nothing is extrapolated; when
the observed order lies outside [MIN_ORDER, k + 1] (k the element degree) it is clipped to that
range and the estimate is FACTOR times the larger of the clipped Richardson error and |f3 - f2|.
FACTOR = 1.25 is Roache's factor of safety of the grid convergence index for three meshes.

The extrapolated value's own error, from four meshes or more: |F_n - F_(n-1)|, the change of the
limit when the finest mesh was added (F_(n-1) from the three meshes before it), when both limits
come from Richardson's rule (an asymptotic sequence). It is the error of F_(n-1) rather than of
F_n: on the side of safety wherever the limits converge.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

FACTOR = 1.25      # the estimate over Richardson's error (Roache's grid convergence index)
# below this order the sequence is taken as not yet asymptotic: on halved meshes the limit would
# lie more than 1/(2^0.5 - 1) = 2.4 times the last change beyond the finest value
MIN_ORDER = 0.5
# above k + 1 for Qk (ABOVE_DEGREE) neither: no sequence of the exact cases observed more than 2.1
# with Q2 (docs/accuracy.md), and a steel rod's three adapted meshes with 3.37 gave 0.0072 % where
# the next mesh moved the value by 0.08 % (under 2(k + 1) = 6, the bound before, Richardson's)
ABOVE_DEGREE = 1


@dataclass
class Estimate:
    """The error estimate of the finest value of a sequence: the extrapolated limit (NaN when none),
    the estimated absolute error of the finest value (FACTOR times the rule's), the observed order
    (NaN when none) and which rule gave the estimate."""

    extrapolated: float
    error: float
    order: float
    kind: str


def observed_order(sizes: list[float], values: list[float]) -> float:
    """p with (f1 - f2)/(f2 - f3) = (h1^p - h2^p)/(h2^p - h3^p) for the last three meshes, by
    bisection (the right side grows with p from ln(h1/h2)/ln(h2/h3) at p = 0); 0 when the ratio lies
    below that (the differences do not shrink: no convergence seen), NaN when the differences change
    sign."""
    (h1, h2, h3), (f1, f2, f3) = sizes[-3:], values[-3:]
    if (f1 - f2) * (f2 - f3) <= 0:
        return math.nan
    ratio = (f1 - f2) / (f2 - f3)

    def model(p: float) -> float:
        return (h1**p - h2**p) / (h2**p - h3**p)

    if ratio <= math.log(h1 / h2) / math.log(h2 / h3):
        return 0.0
    low, high = 1e-9, 1.0
    while model(high) < ratio:
        low, high = high, 2 * high
        if high > 64:
            return high
    for _ in range(100):
        middle = 0.5 * (low + high)
        low, high = (middle, high) if model(middle) < ratio else (low, middle)
    return 0.5 * (low + high)


def richardson_error(sizes: list[float], values: list[float], order: float) -> tuple[float, float]:
    """The extrapolated value and the finest value's error for an order p (last three meshes)."""
    (h2, h3), (f2, f3) = sizes[-2:], values[-2:]
    correction = (f2 - f3) * h3**order / (h2**order - h3**order)
    return f3 - correction, abs(correction)


def richardson(sizes: list[float], values: list[float]) -> tuple[float, float]:
    """The extrapolated value and the observed order of the last three meshes, unguarded; NaN for
    both when the differences change sign or do not shrink (no convergence seen)."""
    order = observed_order(sizes, values)
    if not order > 0:
        return math.nan, math.nan
    return richardson_error(sizes, values, order)[0], order


def estimate(sizes: list[float], values: list[float], degree: int) -> Estimate:
    """The error estimate of the finest of at least three values on meshes of decreasing sizes
    (module docstring): Richardson's when the observed order lies in [MIN_ORDER, degree + 1],
    else the guarded, less optimistic one."""
    if len(values) < 3:
        raise ValueError("an observed order needs three meshes")
    last = abs(values[-1] - values[-2])
    if last == 0:
        return Estimate(values[-1], 0.0, math.nan, "the last two values agree")
    order = observed_order(sizes, values)
    if math.isnan(order):
        return Estimate(math.nan, FACTOR * last, math.nan,
                        "oscillating: the last two values' difference, no extrapolation")
    highest = float(degree + ABOVE_DEGREE)
    if MIN_ORDER <= order <= highest:
        limit, error = richardson_error(sizes, values, order)
        return Estimate(limit, FACTOR * error, order, "richardson")
    clipped = min(max(order, MIN_ORDER), highest)
    limit, error = richardson_error(sizes, values, clipped)
    return Estimate(limit, FACTOR * max(error, last), order,
                    f"observed order {order:.3g} outside [{MIN_ORDER:g}, {highest:g}] (not "
                    f"asymptotic): the larger of Richardson's with order {clipped:g} and the last "
                    "two values' difference")


def extrapolation_error(sizes: list[float], values: list[float], degree: int) -> float:
    """The estimated absolute error of the extrapolated value of the last three meshes: the change
    of the limit when the finest mesh was added (module docstring); NaN with fewer than four
    meshes or when either limit is not Richardson's (no asymptotic sequence)."""
    if len(values) < 4:
        return math.nan
    last, before = estimate(sizes, values, degree), estimate(sizes[:-1], values[:-1], degree)
    if last.kind != "richardson" or before.kind != "richardson":
        return math.nan
    return abs(last.extrapolated - before.extrapolated)


def relative(found: Estimate, value: float) -> float:
    """The estimated error relative to the extrapolated value (to the finest when none)."""
    reference = found.extrapolated if math.isfinite(found.extrapolated) else value
    return found.error / abs(reference) if reference != 0 else math.inf

"""Richardson extrapolation of a quantity computed on meshes of decreasing sizes, any size ratios,
and the guarded estimate of the finest value's error (docs/accuracy.md measures it against the
true error).

From the last three meshes h1 > h2 > h3 with values f1, f2, f3 and f(h) = F + C h^p: the observed
order p solves (f1 - f2)/(f2 - f3) = (h1^p - h2^p)/(h2^p - h3^p), the extrapolated value is
F = f3 - (f2 - f3) h3^p/(h2^p - h3^p) and the error of the finest value is estimated as
FACTOR |f3 - F|. A sequence outside its asymptotic range is guarded against: when the differences
change sign (an oscillation) the estimate is FACTOR |f3 - f2| and nothing is extrapolated; when
the observed order lies below MIN_ORDER the estimate is FACTOR times the larger of Richardson's
error at MIN_ORDER and |f3 - f2|; above HIGHEST_ORDER the sequence's order is unknown and the
estimate is FACTOR times the larger of Richardson's error at SLOWEST_ORDER and |f3 - f2|.
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
# above this neither, for Q1 and Q2: the asymptotic sequences of the exact cases observed at most
# 1.84 (adapted, singular corners) and 2.1 (the smooth cone flow), while three scenes of users
# observed 2.37, 3.11 and 3.37 on their first adapted meshes and Richardson's estimate was a half
# to a tenth of their error (docs/accuracy.md; the bound was 2(k + 1) = 6 for Q2)
HIGHEST_ORDER = 2.0
# such a sequence is taken to converge no faster than uniform meshes do at the die's singular
# corners (order 1 on every exact case, docs/accuracy.md): a strip's four adapted meshes observed
# 3.11 with a last step of h 1.64 times smaller, and 1.25 |f3 - f2| was 0.149 % where the error
# was about 0.2 %
SLOWEST_ORDER = 1.0


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


def estimate(sizes: list[float], values: list[float]) -> Estimate:
    """The error estimate of the finest of at least three values on meshes of decreasing sizes
    (module docstring): Richardson's when the observed order lies in [MIN_ORDER, HIGHEST_ORDER],
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
    if MIN_ORDER <= order <= HIGHEST_ORDER:
        limit, error = richardson_error(sizes, values, order)
        return Estimate(limit, FACTOR * error, order, "richardson")
    assumed = MIN_ORDER if order < MIN_ORDER else SLOWEST_ORDER
    limit, error = richardson_error(sizes, values, assumed)
    return Estimate(limit, FACTOR * max(error, last), order,
                    f"observed order {order:.3g} outside [{MIN_ORDER:g}, {HIGHEST_ORDER:g}] (not "
                    f"asymptotic): the larger of Richardson's with order {assumed:g} and the last "
                    "two values' difference")


def extrapolation_error(sizes: list[float], values: list[float]) -> float:
    """The estimated absolute error of the extrapolated value of the last three meshes: the change
    of the limit when the finest mesh was added (module docstring); NaN with fewer than four
    meshes or when either limit is not Richardson's (no asymptotic sequence)."""
    if len(values) < 4:
        return math.nan
    last, before = estimate(sizes, values), estimate(sizes[:-1], values[:-1])
    if last.kind != "richardson" or before.kind != "richardson":
        return math.nan
    return abs(last.extrapolated - before.extrapolated)


def relative(found: Estimate, value: float) -> float:
    """The estimated error relative to the extrapolated value (to the finest when none)."""
    reference = found.extrapolated if math.isfinite(found.extrapolated) else value
    return found.error / abs(reference) if reference != 0 else math.inf

"""The step lengths of Newton's line search on the energy Phi (newton.py): pure functions of the
lengths tried and their energies, and the constants of the search."""
from __future__ import annotations

ARMIJO = 1e-4       # sufficient decrease of the energy, as a fraction of the first-order decrease
MAX_HALVINGS = 12   # smallest step 2**-12
REFINEMENTS = 6     # energy evaluations that move a cut step towards the minimum of Phi ...
BRACKET = 0.1       # ... until the bracket around that minimum is this small relative to the step
GOLDEN = 0.381966   # (3 - sqrt(5))/2: golden-section fraction


def parabola_vertex(a: float, fa: float, b: float, fb: float, c: float, fc: float) -> float | None:
    """The minimiser of the parabola through (a, fa), (b, fb), (c, fc), a < b < c; None when it is
    not convex."""
    left, right = (b - a) * (fb - fc), (b - c) * (fb - fa)
    if not right - left > 0:  # (b - a)(c - b)(c - a) times the leading coefficient
        return None
    return b - 0.5 * ((b - a) * left - (b - c) * right) / (left - right)


def parabola_step(energy0: float, energy1: float, energy2: float) -> float | None:
    """The minimiser, strictly between 1 and 2, of the parabola through Phi(0), Phi(1) and Phi(2)
    along a Newton direction; None when the parabola is not convex or its minimiser lies outside
    (1, 2)."""
    fitted = parabola_vertex(0.0, energy0, 1.0, energy1, 2.0, energy2)
    return fitted if fitted is not None and 1.0 < fitted < 2.0 else None


def next_trial(energies: dict[float, float]) -> float | None:
    """The next step length at which to evaluate Phi when minimising it along a Newton direction
    (Phi is convex there), from the lengths tried so far and their energies: the vertex of the
    parabola through the lowest point and its neighbours, or a golden-section point of the wider
    side when the vertex lies near the ends or the lowest point (Brent's safeguard). None when the
    lowest point has no neighbour on one side (no bracket) or the bracket is within BRACKET of its
    size."""
    lengths = sorted(energies)
    lowest = min(range(len(lengths)), key=lambda k: energies[lengths[k]])
    if lowest in (0, len(lengths) - 1):
        return None
    a, b, c = lengths[lowest - 1:lowest + 2]
    if c - a < BRACKET * b:
        return None
    vertex = parabola_vertex(a, energies[a], b, energies[b], c, energies[c])
    if vertex is not None and a + BRACKET * (b - a) < vertex < c - BRACKET * (c - b) \
            and abs(vertex - b) > 0.5 * BRACKET * (c - a):
        return vertex
    return b + GOLDEN * (c - b) if c - b > b - a else b - GOLDEN * (b - a)

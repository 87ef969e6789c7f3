"""What an iteration of the flow records: one row per linear solve (history.csv) and the result of
a run (its reason, counts and time split)."""
from __future__ import annotations

import math
from dataclasses import dataclass, field

from forming_fenicsx.fem.linear_problem import Timings


@dataclass
class IterationRecord:
    """One linear solve: outer index m, inner index n, relative increment, elapsed seconds, the
    estimated relative error of the linear solve itself (LinearSolver.error_estimate; NaN on the
    solves that are not sampled, see SecantSolver.sampled_error), and for Newton steps the norm of
    the residual F(u) the step was computed from (at its start), the line-search step length, and
    how many Gauss points changed the branch of the flow-stress law (constant secant or not, G' = 0
    or not) and how many die nodes changed the contact active set since the previous Newton
    operator (-1: none before, or no contact): the semismooth switches that keep Newton's
    convergence from being quadratic; an iterative solve's (outer) Krylov iterations and the
    velocity block's (inner) iterations in it (1 and 0 for a direct solve)."""

    outer: int
    inner: int
    increment: float
    elapsed: float
    solve_error: float = math.nan
    residual: float = math.nan
    step: float = 1.0
    law_switches: int = -1
    contact_switches: int = -1
    krylov_iterations: int = 1
    velocity_iterations: int = 0


# why an iteration stops unconverged (SolveResult.cause)
# "slow": the increments met delta but fell too slowly to bound the distance to the answer
STOP_CAUSES = ("stop", "ill_conditioned", "non_finite", "diverging", "stalled", "max_iterations",
               "slow")


@dataclass
class SolveResult:
    converged: bool
    reason: str
    linear_solves: int = 0
    outer_iterations: int = 0
    history: list[IterationRecord] = field(default_factory=list)
    force_balance_checks: list[float] = field(default_factory=list)
    timings: Timings = field(default_factory=Timings)
    iteration_time: float = 0.0
    cause: str = ""  # why an iteration stopped unconverged: one of STOP_CAUSES
    fallback: str | None = None  # what failed before a fallback method took over (newton.py)

    @property
    def solve_error(self) -> float:
        """The largest estimated relative error of the run's sampled linear solves."""
        return max((r.solve_error for r in self.history if not math.isnan(r.solve_error)),
                   default=0.0)

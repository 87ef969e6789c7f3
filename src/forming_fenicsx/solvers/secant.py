"""Secant-modulus iterations: the direct method (3.13) and the modified method (3.33).

Each iterate solves the linear system K(u_n, u_{0,m}) u_{n+1} = F of (4.4) (linear.py) and stops
when ||u_{n+1} - u_n|| / ||u_{n+1}|| < delta.
"""
from __future__ import annotations

import logging
import math
import time
from collections.abc import Callable
from typing import Any

import dolfinx.fem
import dolfinx.fem.petsc

from forming_fenicsx.core.compat import petsc_vec
from forming_fenicsx.core.errors import LinearSolveError
from forming_fenicsx.fem.forms import FlowProblem
from forming_fenicsx.fem.linear_problem import Timings
from forming_fenicsx.solvers import messages
from forming_fenicsx.config.sections import DIRECT_OPTIONS
from forming_fenicsx.fem.saddle_point import OPTIONS as ITERATIVE_OPTIONS
from forming_fenicsx.solvers.linear import LinearSolver, iterative, saddle_point_of
from forming_fenicsx.solvers.records import IterationRecord, SolveResult

log = logging.getLogger(__package__)  # the solvers' one logger (app/cli.py sets its level)
# a run warns when a linear solve's estimated error reaches ILL_CONDITIONED times delta, and stops
# at once when it reaches UNSOLVABLE times delta
ILL_CONDITIONED = 0.01
UNSOLVABLE = 10.0


def stalled(increments: list[float], window: int) -> bool:
    """True when the last ``window`` increments brought no new smallest one (stall or
    oscillation)."""
    if len(increments) <= window:
        return False
    return min(increments[-window:]) >= min(increments[:-window])


def diverging(increments: list[float], run: int = 5, factor: float = 5.0) -> bool:
    """True when the last ``run`` increments each grew and the last is ``factor`` times the
    smallest."""
    if len(increments) <= run:
        return False
    tail = increments[-run - 1:]
    return (all(b > a for a, b in zip(tail, tail[1:], strict=False))
            and increments[-1] > factor * min(increments))


class SecantSolver:
    """The direct (3.13) or modified (3.33) secant-modulus method for a FlowProblem.

    The default pc_type (under a scene's or the caller's) is ``factorisation(problem)``."""

    def __init__(self, problem: FlowProblem, petsc_options: dict[str, Any] | None = None,
                 balance: Callable[[], float] | None = None,
                 stop: Callable[[], str | None] | None = None):
        """``balance`` returns the force balance residual at the current state; with
        solver.force_tolerance set, convergence also needs it below that tolerance. ``stop`` returns
        a reason to stop (e.g. a signal) or None; it is polled on every rank after every linear
        solve."""
        self.problem = problem
        self.balance = balance
        self.stop = stop
        settings = problem.scene.solver
        self.settings = settings
        saddle_point = saddle_point_of(problem) if iterative(problem) else None
        if saddle_point is None:
            options = {"pc_type": self.factorisation(problem), **settings.petsc_options}
        else:  # the direct solver's defaults left out
            options = {**ITERATIVE_OPTIONS, **{key: value for key, value in
                                               settings.petsc_options.items()
                                               if DIRECT_OPTIONS.get(key) != value}}
        options.update(petsc_options or {})
        self.linear = LinearSolver(problem, options, positive_definite=(
            options.get("pc_type") == "cholesky" and not problem.mixed),
            saddle_point=saddle_point)
        self._previous = problem.u.copy()
        self._state_is_current = False
        self._difference = petsc_vec(problem.u).duplicate()
        self._estimate: Callable[[], float] = self.linear.error_estimate  # of the last linear solve

    @staticmethod
    def factorisation(problem: FlowProblem) -> str:
        """b(w; u, v) of (3.5) is symmetric in u and v and, with the penalty, positive definite:
        Cholesky (MUMPS L L^T, about half the work and memory of LU). The mixed formulation's saddle
        point is factorised by LU: an L D L^T with pivoting there needs ever more delayed pivots as
        contact and friction stiffen it."""
        return "lu" if problem.mixed else "cholesky"

    def destroy(self) -> None:
        self.linear.destroy()
        self._difference.destroy()

    def _step(self, result: SolveResult, outer: int, inner: int, start: float) -> float:
        """One linear solve from the current state; records and returns the relative increment.

        A failed solve restores the previous iterate and returns NaN with the reason in ``result``.
        """
        u, previous = petsc_vec(self.problem.u), petsc_vec(self._previous)
        u.copy(previous)
        inner_before = self.linear.velocity_iterations
        try:
            self.linear.solve()
        except LinearSolveError as error:
            previous.copy(u)
            self.problem.u.x.scatter_forward()
            result.reason = messages.linear_solve_failed(outer, inner, error)
            return math.nan
        result.linear_solves += 1
        self._estimate = self.linear.error_estimate
        solve_error = self.sampled_error(result)
        norm = u.norm()
        difference = self._difference
        previous.copy(difference)
        difference.axpy(-1.0, u)
        increment = difference.norm() / norm if norm > 0 else math.inf
        if not math.isfinite(increment):  # keep the last finite iterate for the results
            previous.copy(u)
            self.problem.u.x.scatter_forward()
        record = IterationRecord(outer, inner, increment, time.perf_counter() - start, solve_error,
                                 krylov_iterations=self.linear.krylov_iterations,
                                 velocity_iterations=(self.linear.velocity_iterations
                                                      - inner_before))
        self.linear.follow(increment)
        result.history.append(record)
        if self.problem.comm.rank == 0:
            log.info("outer %d inner %3d  ||du||/||u|| = %.3e  (%.1f s)", outer, inner, increment,
                     record.elapsed)
        return increment

    def sampled_error(self, result: SolveResult) -> float:
        """The estimated error of the last linear solve (``self._estimate``) on the run's solves 1,
        2, 4, 8, ... and NaN on the others; solve() adds it for the last solve of a converged run.
        Each estimate costs a pair of triangular solves, which scale worst of a run's parts on more
        ranks; the systems' conditioning changes slowly from iterate to iterate, and the first
        solves (where a hopeless penalty shows) are all sampled."""
        count = result.linear_solves
        return self._estimate() if count & (count - 1) == 0 else math.nan

    def _must_stop(self, result: SolveResult, increments: list[float], outer: int, inner: int,
                   friction_note: str) -> bool:
        """The checks after every linear solve; True (with result.reason) when the run must stop: a
        stop request, ill-conditioned solves, a non-finite iterate, divergence, a stall."""
        scene, settings = self.problem.scene, self.settings
        delta, increment = settings.tolerance, increments[-1]
        stop = self._stop_reason()
        if stop:
            result.reason = messages.stop_requested(stop, outer, inner)
            result.cause = "stop"
            return True
        solve_error = next((r.solve_error for r in reversed(result.history)
                            if not math.isnan(r.solve_error)), 0.0)
        if math.isfinite(increment) and solve_error > UNSOLVABLE * delta:
            result.reason = messages.ill_conditioned(solve_error, UNSOLVABLE, delta, outer, inner,
                                                     scene)
            result.cause = "ill_conditioned"
            return True
        if solve_error > ILL_CONDITIONED * delta:
            friction_note += messages.ill_conditioned_note(solve_error, scene)
        if not math.isfinite(increment):
            result.reason = result.reason or messages.non_finite(outer, inner)
            result.cause = "non_finite"
            return True
        if diverging(increments):
            less_friction = self.problem.has_friction and not self.problem.rolling
            result.reason = messages.diverging(increments, outer, inner, friction_note,
                                               settings.method, less_friction)
            result.cause = "diverging"
            return True
        if stalled(increments, self._stall_window()):
            result.reason = messages.stalled(settings.stall_window, increments, outer, inner,
                                             friction_note)
            result.cause = "stalled"
            return True
        return False

    def _stall_window(self) -> int:
        """The iterations without a new smallest increment that make a stall."""
        return self.settings.stall_window

    def _stop_reason(self) -> str | None:
        """The stop request of any rank, agreed on by all (a collective call)."""
        local = self.stop() if self.stop is not None else None
        reasons = [r for r in self.problem.comm.allgather(local) if r]
        return reasons[0] if reasons else None

    def force_tolerance(self) -> float:
        """The force-balance criterion's tolerance (solver.force_tolerance; 0: none)."""
        return self.settings.force_tolerance

    def _balanced(self, result: SolveResult) -> bool:
        """The force-balance criterion, evaluated with every coefficient at the iterate."""
        tolerance = self.force_tolerance()
        if tolerance == 0 or self.balance is None:
            return True
        self.problem.update_state(self.problem.u, frozen_too=True)
        self._state_is_current = True  # the next inner iterate needs no update of its own
        residual = self.balance()
        result.force_balance_checks.append(residual)
        if self.problem.comm.rank == 0:
            log.info("force balance residual %.3e (tolerance %.1e)", residual, tolerance)
        return residual < tolerance

    def _balance_note(self, result: SolveResult) -> str:
        return messages.balance_note(result.force_balance_checks, self.force_tolerance())

    def _start(self, initial: dolfinx.fem.Function | None, result: SolveResult,
               start: float, near_answer: bool = True) -> bool:
        """u_{0,0}: ``initial`` (a restart, the last flow of a free surface's update: with
        ``near_answer`` the frozen coefficients start there too, frozen.py's start_at) or the
        solution with a uniform modulus; False if that failed."""
        problem = self.problem
        if initial is not None:
            petsc_vec(initial).copy(petsc_vec(problem.u))
            problem.fields.start_from_velocity()  # the mixed formulation's solution from u
            dolfinx.fem.petsc.set_bc(petsc_vec(problem.solution), problem.bcs)
            problem.fields.after_solve()  # u (and the pressure) from the solution
            if near_answer:
                problem.start_at(problem.u)
            return True
        problem.set_uniform_secant(problem.scene.reference_strain_rate)
        if math.isfinite(self._step(result, 0, 0, start)):
            return True
        result.reason = result.reason or messages.FIRST_SOLVE_NON_FINITE
        return False

    def _may_end(self, outer: int, inner: int) -> bool:
        """Whether the iteration may end at this iterate: a start carried from another shape's
        flow not on its first (FlowProblem.first_iterates)."""
        return outer > 0 or inner >= self.problem.first_iterates

    def _contact_settled(self, increment: float, increments: list[float]) -> bool:
        """The augmented contact's multiplier step after an iterate (FlowProblem.contact_settled);
        when it moves lambda, ``increments`` starts afresh: the divergence and stall checks then
        judge the new problem's iterates, not the jump the update causes."""
        problem = self.problem
        updates = problem.contact_updates
        settled = problem.contact_settled(increment)
        if problem.contact_updates != updates:
            increments.clear()
        return settled

    def solve(self, initial: dolfinx.fem.Function | None = None) -> SolveResult:
        """Iterate until the stopping rule of (4.4) holds, from ``initial`` (a restart: u_{0,0} of
        the method) or else from the solution with a uniform modulus; with the time split of the
        run."""
        start = time.perf_counter()
        result = self._iterate(initial)
        if result.converged and math.isnan(result.history[-1].solve_error):
            # the answer's own linear solve, whose factors are still the current ones (after a
            # failed solve they would not be)
            result.history[-1].solve_error = self._estimate()
        result.iteration_time = time.perf_counter() - start
        result.timings = self.timings()
        return result

    def timings(self) -> Timings:
        return self.linear.timings

    def _iterate(self, initial: dolfinx.fem.Function | None, near_answer: bool = True
                 ) -> SolveResult:
        """The secant-modulus iteration (3.13) or (3.33), from ``initial`` as _start takes it."""
        problem, settings = self.problem, self.settings
        delta, method = settings.tolerance, settings.method
        start = time.perf_counter()
        result = SolveResult(converged=False, reason="")
        if not self._start(initial, result, start, near_answer):
            return result
        # the modified method's outer loop over the frozen coefficients (the friction bound, ...)
        outer_limit = settings.max_outer_iterations if (method == "modified" and problem.frozen) \
            else 1
        outer_increments: list[float] = []
        friction_note = messages.secant_friction_note(problem.scene, delta, method) \
            if problem.has_friction else ""
        for outer in range(outer_limit):
            result.outer_iterations = outer + 1
            if method == "modified":
                problem.freeze(problem.u)
            increments: list[float] = []
            for inner in range(1, settings.max_iterations + 1):
                if not self._state_is_current:
                    problem.update_state(problem.u, frozen_too=(method == "direct"))
                self._state_is_current = False
                increment = self._step(result, outer, inner, start)
                increments.append(increment)
                if self._must_stop(result, increments, outer, inner, friction_note):
                    return result
                # with an outer loop, the force balance is checked when that loop converges
                settled = self._contact_settled(increment, increments)
                if outer_limit == 1:  # the direct method: the coupled fields froze every iterate
                    settled = settled and problem.coupled_settled(problem.u,
                                                                  settings.coupling_tolerance)
                if increment < delta and settled and self._may_end(outer, inner) and (
                        outer_limit > 1 or self._balanced(result)):
                    break
            else:
                result.reason = messages.no_convergence(settings.max_iterations, increment, delta,
                                                        self._balance_note(result))
                result.cause = "max_iterations"
                return result
            if outer_limit == 1:
                break
            outer_increment = problem.frozen_change(problem.u)  # ||u0,m+1 - u0,m||/||u0,m+1||
            outer_increments.append(outer_increment)
            if problem.comm.rank == 0:
                log.info("outer %d done: frozen coefficients' change %.3e (%s)", outer,
                         outer_increment, ", ".join(c.name for c in problem.frozen))
            if outer_increment < delta and self._balanced(result):
                break
            if stalled(outer_increments, max(2, settings.stall_window // 5)):
                result.reason = messages.outer_stalled(outer_increments)
                return result
        else:
            result.reason = messages.outer_not_converged(settings.max_outer_iterations,
                                                         outer_increment, delta,
                                                         self._balance_note(result))
            return result
        result.converged = True
        result.reason = "increment below tolerance"
        return result

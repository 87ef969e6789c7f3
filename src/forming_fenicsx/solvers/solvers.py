"""Secant-modulus iterations: the direct method (3.13) and the modified method (3.33).

Each iterate solves the linear system K(u_n, u_{0,m}) u_{n+1} = F of (4.4) with a PETSc KSP (MUMPS
Cholesky for the penalty formulation, LU for the mixed one, by default) and stops when
||u_{n+1} - u_n|| / ||u_{n+1}|| < delta.
"""
from __future__ import annotations

import logging
import math
import time
from dataclasses import dataclass, field
from typing import Any, Callable

import dolfinx.fem
import dolfinx.fem.petsc
from petsc4py import PETSc

from forming_fenicsx.core.compat import petsc_vec
from forming_fenicsx.core.errors import LinearSolveError
from forming_fenicsx.fem.forms import FlowProblem
from forming_fenicsx.core.petsc_options import PrefixedOptions

log = logging.getLogger(__name__)
ILL_CONDITIONED = 0.01  # a run warns when a linear solve's estimated error reaches this fraction of delta
UNSOLVABLE = 10.0       # and stops at once when it reaches this multiple of delta


class LinearSolver:
    """Matrix, right-hand side and KSP of one bilinear form, created once and reused by every iterate
    (the secant system b(u_n; ., .) of the problem by default, or another form such as a Jacobian).

    ``matrix_of``: another LinearSolver whose matrix and KSP this one assembles into and factorises, for
    a form on the same space (hence the same sparsity): MUMPS' symbolic analysis is then done once for
    both, and one set of factors is held (Newton's operator after the secant start's matrix); its
    ``petsc_options`` and ``positive_definite`` are then those of that KSP and matrix, and the arguments
    are not read. ``name``: the prefix of its PETSc options (petsc_options.py)."""

    def __init__(self, problem: FlowProblem, petsc_options: dict[str, Any], bilinear: Any = None,
                 linear: Any = None, matrix_of: LinearSolver | None = None, positive_definite: bool = False,
                 name: str = "flow"):
        self.problem = problem
        self.positive_definite = matrix_of.positive_definite if matrix_of is not None else positive_definite
        self.a = bilinear if bilinear is not None else problem.a
        self.b = dolfinx.fem.petsc.create_vector(linear if linear is not None else problem.system_vector)
        self._owner = matrix_of is None
        if matrix_of is not None:
            self.A, self.ksp = matrix_of.A, matrix_of.ksp
        else:
            self.A = dolfinx.fem.petsc.create_matrix(self.a)
            self.ksp = PETSc.KSP().create(problem.comm)
            self._options = PrefixedOptions(name, petsc_options)  # released by destroy
            self.ksp.setOptionsPrefix(self._options.prefix)
            self.ksp.setFromOptions()
            self.A.setOptionsPrefix(self._options.prefix)
            self.A.setFromOptions()
            self.ksp.setOperators(self.A)
        self._residual = self.b.duplicate()
        self._correction = self.b.duplicate()
        self._x: PETSc.Vec | None = None
        self.timings = Timings()

    def assemble_matrix(self) -> None:
        start = time.perf_counter()
        self.A.zeroEntries()
        dolfinx.fem.petsc.assemble_matrix(self.A, self.a, bcs=self.problem.bcs)
        self.A.assemble()
        if self.positive_definite:  # MUMPS then factorises L L^T, without pivoting (read at the first factorisation)
            self.A.setOption(PETSc.Mat.Option.SPD, True)
        self.timings.assembly += time.perf_counter() - start

    def solve(self) -> None:
        """Assemble K and F at the problem's current state and solve for problem.u (and the pressure)."""
        problem = self.problem
        self.assemble_matrix()
        start = time.perf_counter()
        with self.b.localForm() as local:
            local.set(0.0)
        if problem.L is not None:
            dolfinx.fem.petsc.assemble_vector(self.b, problem.L)
        dolfinx.fem.petsc.apply_lifting(self.b, [problem.a], bcs=[problem.bcs])
        self.b.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        dolfinx.fem.petsc.set_bc(self.b, problem.bcs)
        self.timings.assembly += time.perf_counter() - start
        self.solve_system(petsc_vec(problem.solution))
        problem.after_solve()

    def solve_system(self, x: PETSc.Vec) -> None:
        """x = A^-1 b with the assembled A and b (the factorisation, in PCSetUp, timed apart from the
        solve); a failed solve raises LinearSolveError."""
        try:
            start = time.perf_counter()
            self.ksp.setUp()
            self.ksp.getPC().setUp()  # refactorises when A changed (KSPSetUp alone does so only once)
            factorised = time.perf_counter()
            self.ksp.solve(self.b, x)
            self.timings.factorisation += factorised - start
            self.timings.solve += time.perf_counter() - factorised
        except PETSc.Error as error:  # e.g. a zero pivot or a MUMPS failure: the same on every rank
            raise LinearSolveError(f"PETSc error {error.ierr} in KSPSolve") from None
        reason = self.ksp.getConvergedReason()
        if reason < 0:
            raise LinearSolveError(f"KSP diverged (reason {reason})")
        self._x = x

    def error_estimate(self) -> float:
        """Relative forward error of the last solve, ||A^-1 (b - A x)|| / ||x||: one step of iterative
        refinement with the factors already computed (a matrix-vector product and a pair of triangular
        solves, no new factorisation). A backward-stable LU leaves a residual of rounding size, so the
        estimate is about the condition number of K times the machine precision: it shows when a small
        penalty parameter (1/d, 1/d_N, 1/d_T in K) makes the linear systems ill-conditioned."""
        x = self._x
        start = time.perf_counter()
        self.A.mult(x, self._residual)
        self._residual.aypx(-1.0, self.b)
        self.ksp.solve(self._residual, self._correction)
        self.timings.solve += time.perf_counter() - start
        norm = x.norm()
        return self._correction.norm() / norm if norm > 0 else 0.0

    def destroy(self) -> None:
        """Free the PETSc objects and the options set under this solver's prefix."""
        owned = (self.ksp, self.A) if self._owner else ()
        for item in (*owned, self.b, self._residual, self._correction):
            item.destroy()
        if self._owner:
            self._options.release()


@dataclass
class Timings:
    """Seconds spent in assembly, in the factorisation (PCSetUp) and in the solves (with the
    iterative-refinement estimate) of a run's linear systems."""

    assembly: float = 0.0
    factorisation: float = 0.0
    solve: float = 0.0

    def __add__(self, other: "Timings") -> "Timings":
        return Timings(self.assembly + other.assembly, self.factorisation + other.factorisation,
                       self.solve + other.solve)


def stalled(increments: list[float], window: int) -> bool:
    """True when the last ``window`` increments brought no new smallest one (stall or oscillation)."""
    if len(increments) <= window:
        return False
    return min(increments[-window:]) >= min(increments[:-window])


def diverging(increments: list[float], run: int = 5, factor: float = 5.0) -> bool:
    """True when the last ``run`` increments each grew and the last is ``factor`` times the smallest."""
    if len(increments) <= run:
        return False
    tail = increments[-run - 1:]
    return all(b > a for a, b in zip(tail, tail[1:], strict=False)) and increments[-1] > factor * min(increments)


def _recent(increments: list[float], count: int = 6) -> str:
    return ", ".join(f"{value:.2e}" for value in increments[-count:])


@dataclass
class IterationRecord:
    """One linear solve: outer index m, inner index n, relative increment, elapsed seconds, the
    estimated relative error of the linear solve itself (LinearSolver.error_estimate; NaN on the solves
    that are not sampled, see SecantSolver.sampled_error), and for Newton steps the norm of the residual
    F(u) the step was computed from (at its start), the line-search step length, and how many Gauss points
    changed the branch of the flow-stress law (constant secant or not, G' = 0 or not) and how many die
    nodes changed the contact active set since the previous Newton operator (-1: none before, or no
    contact): the semismooth switches that keep Newton's convergence from being quadratic."""

    outer: int
    inner: int
    increment: float
    elapsed: float
    solve_error: float = math.nan
    residual: float = math.nan
    step: float = 1.0
    law_switches: int = -1
    contact_switches: int = -1


# why an iteration stops unconverged (SolveResult.cause)
STOP_CAUSES = ("stop", "ill_conditioned", "non_finite", "diverging", "stalled", "max_iterations")


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
        return max((r.solve_error for r in self.history if not math.isnan(r.solve_error)), default=0.0)


class SecantSolver:
    """The direct (3.13) or modified (3.33) secant-modulus method for a FlowProblem.

    The default pc_type (under a scene's or the caller's) is ``factorisation(problem)``."""

    def __init__(self, problem: FlowProblem, petsc_options: dict[str, Any] | None = None,
                 balance: Callable[[], float] | None = None, stop: Callable[[], str | None] | None = None):
        """``balance`` returns the force balance residual at the current state; with
        solver.force_tolerance set, convergence also needs it below that tolerance. ``stop`` returns a
        reason to stop (e.g. a signal) or None; it is polled on every rank after every linear solve."""
        self.problem = problem
        self.balance = balance
        self.stop = stop
        settings = problem.scene.solver
        self.settings = settings
        options = {"pc_type": self.factorisation(problem), **settings.petsc_options, **(petsc_options or {})}
        self.linear = LinearSolver(problem, options,
                                   positive_definite=options["pc_type"] == "cholesky" and not problem.mixed)
        self._previous = problem.u.copy()
        self._state_is_current = False
        self._difference = petsc_vec(problem.u).duplicate()
        self._estimate: Callable[[], float] = self.linear.error_estimate  # of the last linear solve

    @staticmethod
    def factorisation(problem: FlowProblem) -> str:
        """b(w; u, v) of (3.5) is symmetric in u and v and, with the penalty, positive definite: Cholesky
        (MUMPS L L^T, about half the work and memory of LU). The mixed formulation's saddle point is
        factorised by LU: an L D L^T with pivoting there needs ever more delayed pivots as contact and
        friction stiffen it."""
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
        try:
            self.linear.solve()
        except LinearSolveError as error:
            previous.copy(u)
            self.problem.u.x.scatter_forward()
            result.reason = (f"linear solve failed at outer {outer}, inner {inner}: {error}; the results are the "
                             "previous iterate. Try a larger penalty parameter (penalty.d, penalty.d_N) or "
                             "friction.d_T, or MUMPS LU (solver.petsc_options.pc_type = \"lu\")")
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
        record = IterationRecord(outer, inner, increment, time.perf_counter() - start, solve_error)
        result.history.append(record)
        if self.problem.comm.rank == 0:
            log.info("outer %d inner %3d  ||du||/||u|| = %.3e  (%.1f s)", outer, inner, increment, record.elapsed)
        return increment

    def sampled_error(self, result: SolveResult) -> float:
        """The estimated error of the last linear solve (``self._estimate``) on the run's solves 1, 2, 4,
        8, ... and NaN on the others; solve() adds it for the last solve of a converged run. Each
        estimate costs a pair of triangular solves, which scale worst of a run's parts on more ranks; the
        systems' conditioning changes slowly from iterate to iterate, and the first solves (where a
        hopeless penalty shows) are all sampled."""
        count = result.linear_solves
        return self._estimate() if count & (count - 1) == 0 else math.nan

    def _must_stop(self, result: SolveResult, increments: list[float], outer: int, inner: int,
                   friction_note: str) -> bool:
        """The checks after every linear solve; True (with result.reason) when the run must stop: a
        stop request, ill-conditioned solves, a non-finite iterate, divergence, a stall."""
        settings, delta, increment = self.settings, self.settings.tolerance, increments[-1]
        stop = self._stop_reason()
        if stop:
            result.reason = f"{stop} at outer {outer}, inner {inner}; the last completed iterate is written"
            result.cause = "stop"
            return True
        solve_error = next((r.solve_error for r in reversed(result.history) if not math.isnan(r.solve_error)), 0.0)
        if math.isfinite(increment) and solve_error > UNSOLVABLE * delta:
            result.reason = (f"ill-conditioned linear systems: the estimated relative error of the linear "
                             f"solve, {solve_error:.2e} (one step of iterative refinement), is {UNSOLVABLE:g} times "
                             f"delta {delta:g} or more at outer {outer}, inner {inner}, so the increment cannot "
                             f"fall below delta; {self._penalties()}")
            result.cause = "ill_conditioned"
            return True
        if solve_error > ILL_CONDITIONED * delta:
            friction_note += (f"; the linear systems are ill-conditioned (estimated solve error {solve_error:.1e}): "
                              f"{self._penalties()}")
        if not math.isfinite(increment):
            result.reason = result.reason or (f"non-finite iterate (NaN or Inf) at outer {outer}, inner "
                                              f"{inner}; the results are the previous iterate. Try a larger "
                                              "penalty parameter (penalty.d, penalty.d_N)")
            result.cause = "non_finite"
            return True
        if diverging(increments):
            others = " or ".join(m for m in ("direct", "modified") if m != settings.method)
            friction = ", a smaller friction coefficient" if self.problem.has_friction else ""
            result.reason = (f"diverging: the increment grew for 5 iterations to {increment:.3e} (outer "
                             f"{outer}, inner {inner}; last increments {_recent(increments)}){friction_note}. "
                             f"Try the {others} method{friction} or larger penalty parameters; see "
                             "history.csv")
            result.cause = "diverging"
            return True
        if stalled(increments, settings.stall_window):
            result.reason = (f"stalled or oscillating: no smaller increment in the last "
                             f"{settings.stall_window} iterations (outer {outer}, inner {inner}; last "
                             f"increments {_recent(increments)}){friction_note}; see history.csv")
            result.cause = "stalled"
            return True
        return False

    def _contact_note(self) -> str:
        """Why friction may not settle with a stiff contact penalty: an increment delta*U of the velocity
        moves the penalty normal stress u_N/d_N of (3.4), and with it the friction bound, by delta*U/d_N;
        when that exceeds the flow stress the iteration cannot resolve tau_f (measured on Example 2)."""
        scene = self.problem.scene
        flow = scene.reference_flow_stress
        noise = self.settings.tolerance * abs(scene.process.velocity) / scene.penalty.d_N
        if noise < flow:
            return ""
        return (f"; with penalty.d_N = {scene.penalty.d_N:g} an increment of delta times the process velocity "
                f"moves the contact normal stress by {noise:.2g}, {noise / flow:.2g} times the flow stress, so "
                f"the friction bound cannot settle: use penalty.d_N >= "
                f"{self.settings.tolerance * abs(scene.process.velocity) / flow:.2g}"
                + (" or the modified method" if self.settings.method == "direct" else ""))

    def _penalties(self) -> str:
        scene = self.problem.scene
        return (f"the penalties make K stiff (penalty.d = {scene.penalty.d:g}, penalty.d_N = {scene.penalty.d_N:g}, "
                f"friction.d_T = {scene.friction.d_T:g}); use larger ones")

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
        if not result.force_balance_checks:
            return ""
        return (f"; force balance residual {result.force_balance_checks[-1]:.3e} above "
                f"the force tolerance {self.force_tolerance():g}")

    def _start(self, initial: dolfinx.fem.Function | None, result: SolveResult, start: float) -> bool:
        """u_{0,0}: ``initial`` (a restart) or the solution with a uniform modulus; False if that failed."""
        problem = self.problem
        if initial is not None:
            petsc_vec(initial).copy(petsc_vec(problem.u))
            dolfinx.fem.petsc.set_bc(petsc_vec(problem.u), problem.bcs)
            problem.u.x.scatter_forward()
            return True
        problem.set_uniform_secant(problem.scene.reference_strain_rate)
        if math.isfinite(self._step(result, 0, 0, start)):
            return True
        result.reason = result.reason or ("the first solve, with the uniform modulus G(reference strain rate), "
                                          "gave a non-finite velocity: check the material constants and "
                                          "solver.reference_strain_rate")
        return False

    def _contact_settled(self, increment: float, increments: list[float]) -> bool:
        """The augmented contact's multiplier step after an iterate (FlowProblem.contact_settled); when
        it moves lambda, ``increments`` starts afresh: the divergence and stall checks then judge the
        new problem's iterates, not the jump the update causes."""
        problem = self.problem
        updates = problem.contact_updates
        settled = problem.contact_settled(increment)
        if problem.contact_updates != updates:
            increments.clear()
        return settled

    def solve(self, initial: dolfinx.fem.Function | None = None) -> SolveResult:
        """Iterate until the stopping rule of (4.4) holds, from ``initial`` (a restart: u_{0,0} of the
        method) or else from the solution with a uniform modulus; with the time split of the run."""
        start = time.perf_counter()
        result = self._iterate(initial)
        if result.converged and math.isnan(result.history[-1].solve_error):
            # the answer's own linear solve, whose factors are still the current ones (after a failed
            # solve they would not be)
            result.history[-1].solve_error = self._estimate()
        result.iteration_time = time.perf_counter() - start
        result.timings = self.timings()
        return result

    def timings(self) -> Timings:
        return self.linear.timings

    def _iterate(self, initial: dolfinx.fem.Function | None) -> SolveResult:
        """The secant-modulus iteration (3.13) or (3.33)."""
        problem, settings = self.problem, self.settings
        delta, method = settings.tolerance, settings.method
        start = time.perf_counter()
        result = SolveResult(converged=False, reason="")
        if not self._start(initial, result, start):
            return result
        # the modified method's outer loop over the frozen coefficients (the friction bound, ...)
        outer_limit = settings.max_outer_iterations if (method == "modified" and problem.frozen) else 1
        outer_increments: list[float] = []
        friction_note = (f"; at this friction coefficient the solution may not be unique{self._contact_note()}"
                         if problem.has_friction else "")
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
                if outer_limit == 1:  # the direct method: the coupled fields froze with every iterate
                    settled = settled and problem.coupled_settled(problem.u, settings.coupling_tolerance)
                if increment < delta and settled and (outer_limit > 1 or self._balanced(result)):
                    break
            else:
                result.reason = (f"no convergence in {settings.max_iterations} iterations "
                                 f"(last increment {increment:.3e}, delta {delta:g}{self._balance_note(result)})")
                result.cause = "max_iterations"
                return result
            if outer_limit == 1:
                break
            outer_increment = problem.frozen_change(problem.u)  # ||u0,m+1 - u0,m||/||u0,m+1||
            outer_increments.append(outer_increment)
            if problem.comm.rank == 0:
                log.info("outer %d done: frozen coefficients' change %.3e (%s)", outer, outer_increment,
                         ", ".join(c.name for c in problem.frozen))
            if outer_increment < delta and self._balanced(result):
                break
            if stalled(outer_increments, max(2, settings.stall_window // 5)):
                result.reason = (f"the friction (outer) loop stalls or oscillates: outer changes "
                                 f"{_recent(outer_increments)}; at this friction coefficient the solution may "
                                 "not be unique; see history.csv")
                return result
        else:
            if outer_increment < delta:
                result.reason = (f"the force balance did not converge in {settings.max_outer_iterations} outer "
                                 f"iterations{self._balance_note(result)}, though the outer change "
                                 f"{outer_increment:.3e} is below delta")
            else:
                result.reason = (f"no convergence of the friction (outer) loop in {settings.max_outer_iterations} "
                                 f"iterations (last change {outer_increment:.3e}); at this friction coefficient "
                                 "the solution may not be unique")
            return result
        result.converged = True
        result.reason = "increment below tolerance"
        return result

"""Newton's method with a backtracking line search for the regularised problem (3.10)-(3.12).

The secant-modulus methods (3.13)/(3.33) converge linearly; Newton's method on the same residual
(newton_forms.py) converges fast once near the answer. Its tangent is only about alpha times
as stiff as the secant along the flow direction, so the iteration starts from the uniform-modulus
solution and ``solver.secant_start`` direct secant iterates (the dual stress then starts at
``solver.dual_start`` times tau(u)), and every Newton step is damped by a backtracking (Armijo)
line search on the energy Phi that the solution minimises (the residual is its derivative) and then
moved towards the minimum of Phi along the direction, or lengthened while Phi keeps falling when a
full step would not yet meet delta (line_search.py). It stops with the rule of (4.4) on the full
Newton step, ||du|| / ||u|| < delta (on the step taken when that was longer) after a step taken in
full, and the force balance if solver.force_tolerance is set; in rolling with the friction bound's
derivative in the step, only once the last steps' rate bounds the distance to the answer
(_rate_settled). The history counts the semismooth switches of each step (flow-law branch at the
Gauss points, contact set at the die nodes), which keep the convergence from being quadratic on
fine meshes.
"""
from __future__ import annotations

import dataclasses
import logging
import math
import sys
import time

from collections.abc import Callable
from typing import Any

import dolfinx.fem
import dolfinx.fem.petsc
import numpy as np
from mpi4py import MPI
from petsc4py import PETSc

from forming_fenicsx.core.compat import petsc_vec, set_at_quadrature_points
from forming_fenicsx.core.errors import LinearSolveError
from forming_fenicsx.coupled.strain_tangent import StrainTangent
from forming_fenicsx.fem.forms import FlowProblem
from forming_fenicsx.fem.friction_tangent import FrictionTangent
from forming_fenicsx.fem.linear_problem import Timings
from forming_fenicsx.fem.newton_forms import newton_forms
from forming_fenicsx.fem.tangent_gmres import TangentGMRES
from forming_fenicsx.solvers import messages
from forming_fenicsx.solvers.line_search import (ARMIJO, MAX_HALVINGS, REFINEMENTS, next_trial,
                                                 parabola_step)
from forming_fenicsx.solvers.linear import LinearSolver
from forming_fenicsx.solvers.records import IterationRecord, SolveResult
from forming_fenicsx.solvers.secant import SecantSolver

log = logging.getLogger(__package__)  # the solvers' one logger (app/cli.py sets its level)

ROUNDING = 1e-12    # a relative Newton step below this is rounding
# a full step whose predicted decrease F.du is below this times |Phi| changes Phi by its rounding
# (measured: differences of 1e-16 of Phi = 0.15 for slopes of 1e-21): the line search cannot judge
# it, and halving it only stalls the iteration
ENERGY_ROUNDING = 1e-13
# with the strain in the tangent a run stops only once the x forces balance to this (unless
# solver.force_tolerance is set): the increment can meet delta while the penalty pressure is still
# far out of balance (docs/hardening.md)
COUPLED_BALANCE = 1e-3
# the increments that estimate the rate of convergence in rolling (_rate_settled)
RATE_RUN = 3
# a step through the friction bound's derivative cut below this gives way to the frozen step
FROZEN_STEP_BELOW = 0.125
# Newton's stops after which the direct method goes on (not a stop request, nor ill-conditioned
# systems, which the direct method's would share)
FALL_BACK_ON = ("non_finite", "diverging", "stalled", "max_iterations")


class NewtonSolver(SecantSolver):
    """Newton's method (solver.method = "newton") after a few direct secant iterates.

    Its operator (symmetrised primal-dual, FlowProblem.newton_forms) is assembled into the secant
    start's matrix and shares its factorisation: Cholesky with the penalty, LU for the mixed saddle
    point."""

    def __init__(self, problem: FlowProblem, petsc_options: dict[str, Any] | None = None,
                 balance: Callable[[], float] | None = None,
                 stop: Callable[[], str | None] | None = None):
        super().__init__(problem, petsc_options, balance, stop)
        self.forms = newton_forms(problem)
        # the secant start's matrix: one symbolic analysis
        self.newton = LinearSolver(problem, {}, bilinear=self.forms.operator,
                                   linear=self.forms.residual.parts, matrix_of=self.linear)
        self._velocity = problem.u.copy()  # the velocity before the current step
        self._change = petsc_vec(problem.u).duplicate()
        self._contact_set = None if self.forms.contact_set is None else \
            dolfinx.fem.petsc.create_vector(self.forms.contact_set)
        self._newton_start: dolfinx.fem.Function | None = None  # u when the Newton steps began
        self._solve_failure = ""  # how Newton's linear solve failed, if it did
        self._residual_norm = math.inf  # ||F|| at the current step's start
        self._newton_first = 0  # the history's index of the first Newton step
        self._coupled_start: list[object] = []  # the coupled fields' values then (snapshot)
        # G' = 0 at the owned Gauss points, and the die nodes in contact, at the last operator
        self._branches: np.ndarray | None = None
        self._active: np.ndarray | None = None
        # the frozen coefficients' derivatives in the step (tangent_gmres.py): a coupled field's
        # once the coupling has settled (the transported strain's, strain_tangent.py), and in
        # rolling, whose strip friction alone holds along x, the friction bound's after the first
        # full step (friction_tangent.py; docs/rolling.md: in drawing and extrusion its share of
        # the step is a few per cent and the lengthened steps it forgoes matter more, Example 1 at
        # mu = 0.1 took 17 solves instead of 14): Coulomb's, and the factor law's m k on a
        # rate-sensitive metal (FlowProblem.factor_bound_moves; on the slab grid's nearly
        # rate-independent law it took a sticking roll gap from 35 solves to a divergence); not
        # with the iterative solver, where each GMRES iteration would be a whole Krylov solve (the
        # coupling is then staggered, as before it settles, and the bound frozen at each step)
        carried = [field for field in problem.frozen if field.tangent]
        direct = self.linear.saddle_point is None
        self.coupled_tangent = StrainTangent(problem, carried[0], self.forms.residual.ufl) \
            if carried and direct else None
        self.friction_tangent = None
        coulomb = problem.scene.friction.law == "coulomb"
        if problem.rolling and problem.has_friction and (coulomb or problem.factor_bound_moves) \
                and direct:
            self.friction_tangent = FrictionTangent(problem, self.forms.residual.ufl)
            if not self.friction_tangent.terms:  # a bound the step does not move
                self.friction_tangent.destroy()
                self.friction_tangent = None
        self.tangent = TangentGMRES(self.newton.A, self.newton.ksp) \
            if self.coupled_tangent or self.friction_tangent else None
        self._friction_in_tangent = False
        # each Newton step's kind: frozen (GMRES on the bound's derivative stopped short: A^-1 F)
        # and taken in full
        self._steps: list[tuple[bool, bool]] = []
        # the increments' largest ratio (_rate_settled), and whether they have met delta
        self._rate, self._met = math.nan, False
        # the rate rule holds where the step carries a bound that can reach a rate-sensitive
        # metal's shear strength, whose near-free split the steps creep along (_rate_settled)
        self._rate_rule = self.friction_tangent is not None and problem.bound_reaches_strength

    def destroy(self) -> None:
        self.newton.destroy()
        for item in (self.coupled_tangent, self.friction_tangent, self.tangent):
            if item is not None:
                item.destroy()
        self._change.destroy()
        if self._contact_set is not None:
            self._contact_set.destroy()
        super().destroy()

    def energy_value(self) -> float:
        """Phi(u) at the current u (collective)."""
        start = time.perf_counter()
        value = self.forms.energy.value(self.problem.comm)
        self.newton.timings.assembly += time.perf_counter() - start
        return value

    def assemble_residual(self) -> PETSc.Vec:
        """F(u) into the Newton right-hand side, the Dirichlet rows holding u - g (zero once u meets
        them)."""
        return self.newton.assemble_vector(petsc_vec(self.problem.solution), -1.0)

    def assemble_operator(self) -> None:
        """The Newton operator at the current u and dual stress: G and G' of (4.5) at the Gauss
        points, then the matrix."""
        start = time.perf_counter()
        set_at_quadrature_points(self.forms.tangent, self.forms.tangent_update)
        self.newton.timings.assembly += time.perf_counter() - start
        self.newton.assemble_matrix()

    def count_switches(self) -> tuple[int, int]:
        """Gauss points whose branch of the flow-stress law (G' = 0 or not, from the operator's
        coefficients) and die nodes whose contact state changed since the last call, summed over the
        ranks (-1 on the first call of a solve, and for contact in a scene without it): the
        semismooth part of the Newton operator."""
        start = time.perf_counter()
        tangent = self.forms.tangent
        owned = tangent.function_space.dofmap.index_map.size_local
        branches = tangent.x.array.reshape(-1, 2)[:owned, 1] == 0.0
        active = None
        if self._contact_set is not None:
            with self._contact_set.localForm() as local:
                local.set(0.0)
            dolfinx.fem.petsc.assemble_vector(self._contact_set, self.forms.contact_set)
            self._contact_set.ghostUpdate(addv=PETSc.InsertMode.ADD,
                                          mode=PETSc.ScatterMode.REVERSE)
            active = self._contact_set.array > 0.0
        changed = [-1 if self._branches is None else np.count_nonzero(branches != self._branches),
                   -1 if self._active is None or active is None
                   else np.count_nonzero(active != self._active)]
        self._branches, self._active = branches, active
        # -1 on every rank, or >= 0 on every rank
        counts = self.problem.comm.allreduce(np.array(changed), op=MPI.SUM)
        self.newton.timings.assembly += time.perf_counter() - start
        law, contact = (int(count) if count >= 0 else -1 for count in counts)
        return law, contact

    def _newton_step(self, result: SolveResult, inner: int, start: float) -> float:
        """Solve J du = F at u, then u <- u - s du with s from the line search (_line_search).
        Returns the relative change ||du||/||u|| of the full step, or of the step taken when longer
        (NaN after a failed solve)."""
        forms = self.forms
        problem, u = self.problem, petsc_vec(self.problem.solution)
        du = petsc_vec(forms.step)  # the dual update reads it and the previous iterate
        problem.freeze(problem.u)  # tau_f (every frozen coefficient) at u, as in (3.13)
        if forms.dual_recap is not None:
            # a strain or temperature just frozen can lower the flow stress below the dual's
            # |tau_h|; capped again, the operator stays positive definite and -du a descent
            # direction of Phi, which the line search needs (docs/hardening.md)
            set_at_quadrature_points(forms.dual, forms.dual_recap)
        residual = self._residual_norm = self.assemble_residual().norm()
        self.assemble_operator()
        law_switches, contact_switches = self.count_switches()
        inner_before = self.newton.velocity_iterations
        du.set(0.0)  # the iterative solver's initial guess: its tolerance is relative to F's norm
        try:
            self.newton.solve_system(du)
        except LinearSolveError as error:
            self._solve_failure = messages.newton_linear_failure(
                inner, error, problem.scene, self.newton.saddle_point is not None)
            result.reason = messages.newton_solve_failed(self._solve_failure, error)
            return math.nan
        result.linear_solves += 1
        # relative to u
        self._estimate = lambda: self.newton.error_estimate() * du.norm() / max(u.norm(), 1e-300)
        solve_error = self.sampled_error(result)
        coupled, frozen = "", False  # frozen: GMRES stopped short and the step is A^-1 F
        corrections = self._corrections()
        if corrections:
            error = self._estimate()  # of A's solve, before du moves
            self._estimate = lambda: error
            # GMRES stopped short: the strain's step keeps its last iterate (a cold copper pass
            # at m = 1 failed with the frozen step, and the copper demo on a fine mesh took 25
            # solves with both derivatives, 19 with it); the friction bound's alone, near
            # sticking where J is near singular, the frozen step (two steel passes then stopped
            # unconverged; docs/hardening.md)
            keep = not self._friction_in_tangent or self._coupled_in_tangent()
            converged = self.tangent.solve(self.newton.b, du, corrections, keep)
            fallback = "its last iterate" if keep else "the frozen step"
            frozen = not converged and not keep
            coupled = (f"  {', '.join(c.name for c in corrections)} in the tangent: "
                       f"{self.tangent.iterations} GMRES iterations") \
                + ("" if converged else f" (not converged: {fallback})")
        slope = self.newton.b.dot(du)  # F.dw > 0 when -dw is a descent direction of Phi
        energy0 = self.energy_value()
        forms.step.x.scatter_forward()
        self.keep_previous()
        petsc_vec(problem.u).copy(petsc_vec(self._velocity))
        step = self._line_search(energy0, slope)
        if self._friction_in_tangent and not frozen and step < FROZEN_STEP_BELOW:
            # Phi hardly falls along J^-1 F: at the factor law's m = 1 on a rate-sensitive metal
            # J is near singular and its step runs along the stick zone's slip (steel strips
            # rolled 3 -> 2.2 and 15 -> 10 mm stopped unconverged after 242 and 218 solves; with
            # the frozen step instead they converged in 109 and 93, docs/rolling.md)
            self.tangent.restore_start(du)
            forms.step.x.scatter_forward()
            frozen = True
            coupled += f" (cut to {step:.3g}: the frozen step instead)"
            slope = self.newton.b.dot(du)
            step = self._line_search(energy0, slope)
        # (4.4): the full step, or the longer one taken
        increment = self._relative_change() / min(step, 1.0)
        if not math.isfinite(increment):
            self._move(0.0)
        else:
            # a full dual step, then the cap
            set_at_quadrature_points(forms.dual, forms.dual_update)
        record = IterationRecord(0, inner, increment, time.perf_counter() - start, solve_error,
                                 residual, step, law_switches, contact_switches,
                                 self.newton.krylov_iterations,
                                 self.newton.velocity_iterations - inner_before)
        self.newton.follow(increment)
        result.history.append(record)
        self._steps.append((frozen, step >= 1.0))
        # the friction bound's derivative joins the steps after the first taken in full: from the
        # first step on, R/h1 = 100, 40 %, mu = 0.3 diverged (docs/rolling.md)
        if self.friction_tangent is not None and step >= 1.0:
            self._friction_in_tangent = True
        if problem.comm.rank == 0:
            log.info("newton %3d  ||du||/||u|| = %.3e  ||F|| = %.3e  step %.3g  switched: law %d, "
                     "contact %d  (%.1f s)%s", inner, increment, residual, step, law_switches,
                     contact_switches, record.elapsed, coupled)
        return increment

    def keep_previous(self) -> None:
        """The current iterate becomes the previous one (forms.previous, ghosts too): the line
        search moves from it, the dual update and the operator's joined contact set read it."""
        petsc_vec(self.problem.solution).copy(petsc_vec(self.forms.previous))
        self.forms.previous.x.scatter_forward()

    def _relative_change(self) -> float:
        """||u - u_before|| / ||u|| of the velocity over the current Newton step."""
        change, velocity = self._change, petsc_vec(self.problem.u)
        velocity.copy(change)
        change.axpy(-1.0, petsc_vec(self._velocity))
        norm = velocity.norm()
        return change.norm() / norm if norm > 0 else math.inf

    def _line_search(self, energy0: float, slope: float) -> float:
        """Move u to previous - s du and return s. A full step that lowers Phi by at least
        ARMIJO * F.du is taken, or, when it does not yet meet delta nor carry the strain's
        derivative (_coupled_in_tangent), lengthened to the best of s = 1, s = 2 and the minimiser
        of the parabola through Phi at s = 0, 1, 2 (parabola_step): near the answer the minimum of
        Phi along -du often lies beyond the full step, since while the dual stress differs from
        tau(u) the operator is stiffer than the consistent tangent along the flow direction
        (docs/solvers.md). Otherwise the step is halved until it lowers Phi by ARMIJO * s * F.du and
        then moved towards the minimum of Phi along -du (_refine). A full step too small for Phi
        to tell (ENERGY_ROUNDING) is taken, and so is one below delta that carries the friction
        bound's derivative: Phi, at the frozen bound, is not the merit of that direction (a hot
        rolling pass with tensions had every such step cut to about 0.41 for 17 steps after its
        increment met delta, 29 solves instead of 14; docs/rolling.md). A step through the factor
        law's bound is taken in full when it lowers ||F|| (_lowers_residual)."""
        step, energy = 1.0, self._energy_at(1.0)
        if abs(slope) < ENERGY_ROUNDING * abs(energy0):
            return step
        if self._friction_in_tangent and self._relative_change() < self.settings.tolerance:
            return step  # Newton's step through the bound below delta: Phi cannot judge it
        if self._friction_in_tangent and self.problem.factor_bound_moves \
                and self._lowers_residual():
            return step
        energies = {0.0: energy0, step: energy}
        for _ in range(MAX_HALVINGS):
            if energy <= energy0 - ARMIJO * step * slope:
                break
            step *= 0.5
            energy = energies[step] = self._energy_at(step)
        else:
            return step  # no sufficient decrease down to 2**-12: the stall checks end such runs
        if step < 1.0:
            return self._lowest(energies, self._refine(energies, step))
        if self._relative_change() < self.settings.tolerance or self._corrections():
            return step
        step = 2.0
        energies[step] = self._energy_at(step)
        fitted = parabola_step(energy0, energy, energies[step])
        if fitted is not None:
            step = fitted
            energies[step] = self._energy_at(step)
        return self._lowest(energies, step)

    def _rate_settled(self, increments: list[float]) -> bool:
        """Whether the last steps put the answer within delta, in rolling with the friction
        bound's derivative in the step, where the bound can reach a rate-sensitive metal's shear
        strength (FlowProblem.bound_reaches_strength). Near sticking its J is nearly singular:
        GMRES stops short and the frozen steps (A^-1 F) creep along the near-null mode, the stick
        zone's slip, or the line search cuts Newton's step. A steel strip rolled 2 -> 1.4 mm at
        m = 1 met delta = 1e-4 on a frozen step with its roll force 1.1 % low, its frozen steps
        then creeping by 1.8e-5 a step for a hundred steps; one rolled 5 -> 4 mm met it on a
        Newton step after two cut ones, 0.7 % low (docs/rolling.md). So a run ends on a Newton
        step only after a step taken in full, and on a frozen step once the last RATE_RUN, all
        frozen and full, fall and bound the distance to the answer, sum_j>k ||du_j|| <= ||du_k||
        rho / (1 - rho), rho their largest ratio, below delta."""
        self._rate = math.nan
        if not self._rate_rule or increments[-1] < ROUNDING:
            return True
        frozen, full = zip(*self._steps[-RATE_RUN:])
        if not frozen[-1]:
            return len(full) > 1 and full[-2]
        if len(frozen) < RATE_RUN or not all(frozen) or not all(full):
            return False
        last = increments[-RATE_RUN:]
        self._rate = rho = max(b / a if a > 0 else math.inf for a, b in zip(last[:-1], last[1:]))
        return rho < 1.0 and last[-1] * rho / (1.0 - rho) < self.settings.tolerance

    def _stall_window(self) -> int:
        """No stall once the increments of a run the rate holds (_rate_settled) have met delta:
        they creep along the stick zone's slip, rising and falling (from 1.8e-5 to 4.7e-5 and down
        to 1e-6 a step in the 2 -> 1.4 mm strip, one cut step at 1.5e-4 in the 5 -> 4 mm one), and
        the direct method a stall falls back on meets delta further from the answer (12 % and
        5.8 % below their roll forces without the force balance's stop; docs/rolling.md)."""
        return sys.maxsize if self._met else self.settings.stall_window

    def _lowers_residual(self) -> bool:
        """Whether the full step (u at it) lowers ||F|| with the friction bound at its end: the
        merit of a step through the factor law's m k(rate), which Phi, at the bound frozen at the
        step's start, cut to about 0.1 for ten steps on a steel slab rolled at m = 1 (24 solves
        against 15; docs/rolling.md). The bound is frozen at the step's start again after."""
        state = self.problem.friction_state
        state.freeze(self.problem.u)
        lower = self.assemble_residual().norm() < self._residual_norm
        state.freeze(self._velocity)
        return lower

    def force_tolerance(self) -> float:
        """solver.force_tolerance, or COUPLED_BALANCE when unset and the step carries the strain's
        derivative, or in 3D: the increment of such steps falls below delta while the penalty
        pressure, which a velocity change of delta moves by much more, is still out of balance
        (docs/three_d.md: a frictionless rectangular bar stopped 12 % out of balance)."""
        scene_tolerance = self.settings.force_tolerance
        three_d = self.problem.mesh.geometry.dim == 3
        if scene_tolerance > 0 or not (self._coupled_in_tangent() or three_d):
            return scene_tolerance
        return COUPLED_BALANCE

    def _factor_at_strength(self) -> bool:
        """Whether the friction is rolling's factor law at a rate-sensitive metal's strength."""
        return self.problem.bound_reaches_strength \
            and self.problem.scene.friction.law == "factor"

    def _corrections(self) -> list:
        """The frozen coefficients' derivatives the step carries (tangent_gmres.py)."""
        active = [self.coupled_tangent] if self._coupled_in_tangent() else []
        if self._friction_in_tangent:
            active.append(self.friction_tangent)
        return active

    def _coupled_in_tangent(self) -> bool:
        """Whether the step carries the strain's derivative (strain_tangent.py): it is then not
        a Newton step for Phi at the frozen strain, whose minimum along it lies further (lengthened
        to it, the step undoes the strain's share and the iteration crawls; docs/hardening.md)."""
        return self.coupled_tangent is not None and self.coupled_tangent.field.in_tangent

    def _refine(self, energies: dict[float, float], current: float) -> float:
        """Evaluate Phi at up to REFINEMENTS more step lengths chosen by next_trial within the
        bracket of the lengths tried (below the shortest step the halving rejected), adding them to
        ``energies``; returns the length u is left at (``current`` when none was tried). Where a
        step is cut, Phi along the direction falls nearly linearly up to a steep rise (the flow
        stress of (4.5) is nearly constant above rate1, so Phi grows like |rate| where the step
        reverses the flow), and the halving alone lands anywhere within a factor 2 of that
        minimum."""
        for _ in range(REFINEMENTS):
            trial = next_trial(energies)
            if trial is None:
                break
            energies[trial] = self._energy_at(trial)
            current = trial
        return current

    def _lowest(self, energies: dict[float, float], current: float) -> float:
        """Move u from step length ``current`` to the nonzero length of lowest Phi among
        ``energies`` (the lengths the line search evaluated) and return it."""
        best = min((length for length in energies if length > 0.0), key=energies.get)
        if best != current:
            self._move(best)
        return best

    def _move(self, step: float) -> None:
        """u = previous - step du, and the problem's state with it."""
        u, du, previous = (petsc_vec(f) for f in (self.problem.solution, self.forms.step,
                                                  self.forms.previous))
        previous.copy(u)
        u.axpy(-step, du)
        self.problem.after_solve()

    def _energy_at(self, step: float) -> float:
        """Phi(previous - step du), leaving u there."""
        self._move(step)
        return self.energy_value()

    def timings(self) -> Timings:
        return self.linear.timings + self.newton.timings

    def _newton_iterate(self, initial: dolfinx.fem.Function | None) -> SolveResult:
        """Secant start, then Newton steps until the step is below delta (and the force balance
        holds)."""
        problem, settings = self.problem, self.settings
        start = time.perf_counter()
        result = SolveResult(converged=False, reason="")
        result.outer_iterations = 1
        self._solve_failure = ""
        self._steps, self._met = [], False  # this solve's (a coupled run solves again)
        if not self._start(initial, result, start):
            return result
        friction_note = messages.newton_friction_note(problem.scene, settings.tolerance,
                                                      settings.method) \
            if problem.has_friction else ""
        increments: list[float] = []
        for inner in range(1, settings.secant_start + 1):
            problem.update_state(problem.u, frozen_too=True)
            increments.append(self._step(result, 0, inner, start))
            if self._must_stop(result, increments, 0, inner, ""):
                return result
        self._newton_start, self._newton_first = problem.u.copy(), len(result.history)
        self._coupled_start = problem.snapshot()
        # tau(u), scaled by solver.dual_start
        set_at_quadrature_points(self.forms.dual, self.forms.dual_reset)
        self.forms.dual.x.array[:] *= settings.dual_start
        self.keep_previous()  # the first operator's previous iterate: its contact set is u's
        self._branches = self._active = None  # count_switches starts afresh
        self._friction_in_tangent = False
        increments = []
        for inner in range(1, settings.max_iterations + 1):
            increment = self._newton_step(result, inner, start)
            increments.append(increment)
            # once met, delta ends the run only with the rate's consent (_rate_settled)
            self._met = self._met or (self._rate_rule and increment < settings.tolerance)
            if self._must_stop(result, increments, 0, inner, friction_note):
                return result
            # a step the line search cut does not end the run: its short full step says little
            # about the distance to the answer when the energy along it is far from the Newton
            # model (a full step below ROUNDING of u changes Phi by less than its rounding: the
            # line search cannot judge it, and the step is as good as taken)
            full = result.history[-1].step >= 1.0 or increment < ROUNDING
            settled = full and self._contact_settled(increment, increments)
            if (increment < settings.tolerance and settled
                    and self._rate_settled(increments)
                    and self._may_end(0, inner)
                    and problem.coupled_settled(problem.u, settings.coupling_tolerance)
                    and self._balanced(result)):
                result.converged, result.reason = True, "increment below tolerance"
                return result
        if self._met and not self._rate_settled(increments):
            result.reason = messages.slow_convergence(settings.max_iterations, increments,
                                                      self._rate, settings.tolerance) \
                + messages.strength_friction_hint(self._factor_at_strength())
            result.cause = "slow"  # no fallback: the direct method creeps too
            return result
        result.reason = messages.no_convergence(
            settings.max_iterations, increment, settings.tolerance, self._balance_note(result),
            "Newton steps") + messages.hardening_hint(problem.scene) \
            + messages.strength_friction_hint(self._factor_at_strength())
        result.cause = "max_iterations"
        return result

    def _iterate(self, initial: dolfinx.fem.Function | None) -> SolveResult:
        """Newton's method (_newton_iterate); should it diverge, stall or fail a solve, the direct
        method (3.13) from the iterate Newton started from (the secant start's)."""
        result = self._newton_iterate(initial)
        if result.converged or result.cause not in FALL_BACK_ON or self._newton_start is None:
            return result
        steps = result.history[self._newton_first:]
        failed = self._solve_failure or messages.newton_failed(result.cause, steps)
        if self.problem.comm.rank == 0:
            log.warning("%s: the direct method (3.13) goes on from the secant start's iterate",
                        failed)
        self.settings = dataclasses.replace(self.settings, method="direct")
        self._met = False  # the direct method's stalls count
        self.problem.restore(self._coupled_start)
        # from an early iterate, with the coefficients it had: not a start near the answer
        direct = SecantSolver._iterate(self, self._newton_start, near_answer=False)
        direct.history = result.history + direct.history
        direct.linear_solves += result.linear_solves
        direct.force_balance_checks = result.force_balance_checks + direct.force_balance_checks
        direct.fallback = failed
        direct.reason = messages.after_fallback(direct.reason, failed) \
            + messages.strength_friction_hint(self._factor_at_strength())
        return direct

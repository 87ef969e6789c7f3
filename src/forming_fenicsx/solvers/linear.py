"""The flow's linear systems: K(u_n, u_{0,m}) u_{n+1} = F of (4.4) and Newton's step, solved by a
PETSc KSP under the options prefix ``flow_`` (MUMPS Cholesky for the penalty formulation, LU for the
mixed one, by default; secant.py chooses), or iteratively (the mixed formulation's augmented saddle
point, fem/saddle_point.py), with an estimate of each solve's error."""
from __future__ import annotations

import math
import time
from collections.abc import Sequence
from typing import Any

import dolfinx.fem
from petsc4py import PETSc

from forming_fenicsx.core.errors import LinearSolveError
from forming_fenicsx.fem.forms import FlowProblem
from forming_fenicsx.fem.linear_problem import LinearProblem
from forming_fenicsx.fem.saddle_point import AugmentedSaddlePoint

# the iterative solves' relative residual (relative to the initial one: the current iterate's for
# the secant systems, F's for Newton's): KRYLOV_FACTOR times the last relative increment of the
# nonlinear iteration, within [KRYLOV_FLOOR times solver.tolerance, KRYLOV_CEILING]: tighter than
# the nonlinear iteration's own error. The ceiling holds the first solves, whose increments are
# large: at 1e-3 their error moved the iterates by 1 %, the augmented contact's multiplier then
# settled elsewhere within its window and the answer by up to 1.5e-4 (docs/iterative_solver.md)
KRYLOV_FACTOR = 1e-3
KRYLOV_FLOOR = 1e-3
KRYLOV_CEILING = 1e-5
# solver.linear = "auto" solves a 3D mixed problem of at least this many unknowns iteratively: on
# one rank the iterative solver was slower than MUMPS at every size both solved (3k to 40k unknowns,
# 1.2 to 1.6 times), on two it overtook MUMPS near 92k (twice as fast at 277k), and on a thin
# section it was 7 times slower (18k unknowns); MUMPS' memory, extrapolated (N^1.27), reaches this
# machine's 24 GiB near 700k unknowns, where the iterative solver's, 13.8 GB at 1.05M, still fits
# (docs/iterative_solver.md)
ITERATIVE_FROM = 500_000


def iterative(problem: FlowProblem) -> bool:
    """Whether the scene's solver.linear (auto: by dimension, formulation and size) is iterative."""
    kind = problem.scene.solver.linear
    if kind == "auto":
        return (problem.mixed and problem.mesh.geometry.dim == 3
                and problem.unknowns >= ITERATIVE_FROM)
    return kind == "iterative"


def saddle_point_of(problem: FlowProblem) -> AugmentedSaddlePoint:
    """The iterative solver's augmentation of the problem's mixed system, weighted by its secant
    coefficient."""
    return AugmentedSaddlePoint(problem.system_space, problem.secant_coefficient(), problem.dx,
                                collapsed=problem.fields.collapsed)


class LinearSolver(LinearProblem):
    """The matrix, right-hand side and KSP of one bilinear form of the flow, created once and reused
    by every iterate: the secant system b(u_n; ., .) of (3.5) by default, or another form such as
    Newton's operator with the right-hand side ``linear`` (the parts of its residual).

    ``matrix_of``: another LinearSolver whose matrix and KSP this one assembles into and
    factorises, for a form on the same space: MUMPS' symbolic analysis is then done once for both,
    and one set of factors is held (Newton's operator after the secant start's matrix); its
    ``petsc_options`` and ``positive_definite`` are then those of that KSP and matrix, and the
    arguments are not read.
    ``name``: the prefix of its PETSc options, which stay set until destroy.
    ``saddle_point``: the augmentation and fieldsplit of the iterative solver (none: direct; with
    ``matrix_of``, that one's)."""

    def __init__(self, problem: FlowProblem, petsc_options: dict[str, Any],
                 bilinear: dolfinx.fem.Form | None = None,
                 linear: Sequence[dolfinx.fem.Form] | None = None,
                 matrix_of: LinearSolver | None = None, positive_definite: bool = False,
                 name: str = "flow", saddle_point: AugmentedSaddlePoint | None = None):
        self.problem = problem
        self.saddle_point = saddle_point if matrix_of is None else matrix_of.saddle_point
        self.positive_definite = (matrix_of.positive_definite if matrix_of is not None
                                  else positive_definite)
        if linear is None:
            linear = [] if problem.L is None else [problem.L]
        super().__init__(problem.a if bilinear is None else bilinear, linear, problem.solution,
                         problem.bcs, prefix=name, options=petsc_options, keep_options=True,
                         matrix_of=matrix_of)
        self._residual = self.b.duplicate()
        self._correction = self.b.duplicate()
        self._x: PETSc.Vec | None = None
        if self.saddle_point is not None and matrix_of is None:
            self.ksp.setTolerances(rtol=KRYLOV_CEILING)  # the first solve's: follow sets the next

    def assemble_matrix(self) -> None:
        super().assemble_matrix()
        if self.saddle_point is not None:  # the preconditioner's set-up: factorisation's time
            start = time.perf_counter()
            self.saddle_point.augment_matrix(self.A)
            self.timings.factorisation += time.perf_counter() - start
        if self.positive_definite:
            # MUMPS then factorises L L^T, without pivoting (read at the first factorisation)
            self.A.setOption(PETSc.Mat.Option.SPD, True)

    def solve(self, matrix: bool = True) -> dolfinx.fem.Function:
        """Assemble K and F at the problem's current state and solve for problem.u (and the
        pressure)."""
        super().solve(matrix)
        self.problem.after_solve()
        return self.u

    def solve_system(self, x: PETSc.Vec, b: PETSc.Vec | None = None) -> None:
        """x = A^-1 b; iteratively, b is augmented first (in place: the system solved is the
        augmented one, of the same solution) with the weight of the matrix as last assembled, and
        the system scaled for the solve (saddle_point.py)."""
        self._x = x
        if self.saddle_point is None:
            super().solve_system(x, b)
            return
        b = self.b if b is None else b
        start = time.perf_counter()  # the augmentation, scaling and multigrid set-up
        self.saddle_point.augment_vector(b)
        self.saddle_point.scale(self.A, b, x)
        self.saddle_point.configure(self.ksp)
        self.timings.factorisation += time.perf_counter() - start
        try:
            super().solve_system(x, b)
        except LinearSolveError:
            raise LinearSolveError(
                f"the iterative solver stopped after {self.ksp.getIterationNumber()} Krylov "
                f"iterations (reason {self.ksp.getConvergedReason()}); solver.linear = \"direct\" "
                "solves the same system by MUMPS") from None
        finally:
            start = time.perf_counter()
            self.saddle_point.unscale(self.A, b, x)
            self.timings.factorisation += time.perf_counter() - start

    def follow(self, increment: float) -> None:
        """The next iterative solve's relative residual from the nonlinear iteration's last
        relative increment (KRYLOV_FACTOR)."""
        if self.saddle_point is not None and math.isfinite(increment):
            floor = KRYLOV_FLOOR * self.problem.scene.solver.tolerance
            rtol = min(max(KRYLOV_FACTOR * increment, floor), KRYLOV_CEILING)
            self.ksp.setTolerances(rtol=rtol)

    @property
    def krylov_iterations(self) -> int:
        """The last solve's Krylov iterations (1 for a direct solve)."""
        return self.ksp.getIterationNumber()

    @property
    def velocity_iterations(self) -> int:
        """The velocity block's Krylov iterations of all iterative solves so far (0: direct)."""
        return 0 if self.saddle_point is None else self.saddle_point.velocity_iterations

    def error_estimate(self) -> float:
        """Relative forward error of the last solve, ||A^-1 (b - A x)|| / ||x||: one step of
        iterative refinement with the factors already computed (a matrix-vector product and a pair
        of triangular solves, no new factorisation). A backward-stable LU leaves a residual of
        rounding size, so the estimate is about the condition number of K times the machine
        precision: it shows when a small penalty parameter (1/d, 1/d_N, 1/d_T in K) makes the linear
        systems ill-conditioned. Iteratively: NaN (the Krylov's residual is its rtol's)."""
        if self.saddle_point is not None:  # not estimated: the Krylov stops at its rtol
            return math.nan
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
        for item in (self._residual, self._correction):
            item.destroy()
        if self.saddle_point is not None and self._owner:
            self.saddle_point.destroy()
        super().destroy()

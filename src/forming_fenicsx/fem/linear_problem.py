"""One linear problem a(s, w) = L(w) with strong Dirichlet conditions, as dolfinx's
fem.petsc.LinearProblem: the compiled forms, the matrix, vector and PETSc KSP under a required
options prefix, and the one place that assembles, lifts and solves. On it: the flow's systems of
(4.4) and Newton's (solvers/linear.py), the coupled fields' transport and heat equations, the
averaged normal stress (boundary_filter.py) and the element-wise projection (projection.py). An
iterative flow solver would add its preconditioning form (KSP operators A, P) and near-null space
here.
"""
from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import dolfinx.fem
import dolfinx.fem.petsc
import dolfinx.la
from petsc4py import PETSc

from forming_fenicsx.core.compat import petsc_vec
from forming_fenicsx.core.errors import LinearSolveError
from forming_fenicsx.core.petsc_options import PrefixedOptions

DIRECT = {"ksp_type": "preonly", "pc_type": "lu", "pc_factor_mat_solver_type": "mumps"}


@dataclass
class Timings:
    """Seconds spent in assembly, in the set-up (PCSetUp: a direct solver's factorisation) and in
    the solves of linear systems."""

    assembly: float = 0.0
    factorisation: float = 0.0
    solve: float = 0.0

    def __add__(self, other: Timings) -> Timings:
        return Timings(self.assembly + other.assembly, self.factorisation + other.factorisation,
                       self.solve + other.solve)


class LinearProblem:
    """The bilinear form ``a``, the parts ``L`` whose sum is the right-hand side (split_form's;
    none: the lifting alone), the Dirichlet conditions ``bcs`` and the solution ``u``; the matrix
    ``A``, vector ``b`` and ``ksp``, and the time each step took (``timings``)."""

    def __init__(self, a: dolfinx.fem.Form, L: Sequence[dolfinx.fem.Form],
                 u: dolfinx.fem.Function, bcs: Sequence[dolfinx.fem.DirichletBC] = (), *,
                 prefix: str, options: dict[str, Any] | None = None, keep_options: bool = False,
                 fallback: bool = False, matrix_of: LinearProblem | None = None):
        """``prefix``: the name of the PETSc options (petsc_options.py), ``options`` set under it;
        they stay in the database until the first solve has set the KSP up (a preconditioner's
        sub-solvers and MUMPS read theirs only then), with ``keep_options`` until destroy.
        ``fallback``: an iterative solve that fails is repeated by MUMPS LU. ``matrix_of``: another
        LinearProblem, of a form on the same spaces (hence the same sparsity), whose matrix this one
        assembles into and whose KSP it solves with: one symbolic factorisation for both; the
        options, their prefix and the fallback are then that one's."""
        self.a, self.L, self.u, self.bcs = a, list(L), u, list(bcs)
        space = a.function_spaces[0]  # b as create_vector makes it for a linear form on this space
        self.b = dolfinx.la.create_petsc_vector(space.dofmap.index_map, space.dofmap.index_map_bs)
        self.timings = Timings()
        self._options: PrefixedOptions | None = None
        self._owner = matrix_of is None
        if matrix_of is None:
            self.keep_options, self.fallback = keep_options, fallback
            self.A, self.ksp = self._create(prefix, options or {})
        else:
            self.keep_options, self.fallback = matrix_of.keep_options, matrix_of.fallback
            self.A, self.ksp = matrix_of.A, matrix_of.ksp

    def _create(self, prefix: str, options: dict[str, Any]) -> tuple[PETSc.Mat, PETSc.KSP]:
        """A matrix of a's sparsity and a KSP configured by ``options`` under ``prefix``."""
        A = dolfinx.fem.petsc.create_matrix(self.a)
        ksp = PETSc.KSP().create(A.getComm())
        self._options = PrefixedOptions(prefix, options)
        ksp.setOptionsPrefix(self._options.prefix)
        ksp.setFromOptions()
        A.setOptionsPrefix(self._options.prefix)
        A.setFromOptions()
        # the operators after setFromOptions: set before, the PC makes its factor matrix there
        # (PCFactorSetDefaultOrdering), before assemble_matrix can mark A symmetric positive
        # definite, and MUMPS factorises the flow's penalty matrix as L D L^T instead of L L^T
        ksp.setOperators(A)
        return A, ksp

    def assemble_matrix(self) -> None:
        """A at the coefficients' current values, the Dirichlet rows and columns those of the
        identity."""
        start = time.perf_counter()
        self.A.zeroEntries()
        dolfinx.fem.petsc.assemble_matrix(self.A, self.a, bcs=self.bcs)
        self.A.assemble()
        self.timings.assembly += time.perf_counter() - start

    def assemble_vector(self, x0: PETSc.Vec | None = None, scale: float = 1.0) -> PETSc.Vec:
        """b = L - scale a(g - x0, .) with scale (g - x0) in the Dirichlet rows, g their values (x0
        zero unless given: Newton's residual passes its iterate and -1)."""
        start = time.perf_counter()
        with self.b.localForm() as local:
            local.set(0.0)
        for part in self.L:
            dolfinx.fem.petsc.assemble_vector(self.b, part)
        # positional: the keyword is scale in dolfinx 0.5 and alpha in 0.9
        dolfinx.fem.petsc.apply_lifting(self.b, [self.a], [self.bcs], [] if x0 is None else [x0],
                                        scale)
        self.b.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        dolfinx.fem.petsc.set_bc(self.b, self.bcs, x0, scale)
        self.timings.assembly += time.perf_counter() - start
        return self.b

    def solve(self, matrix: bool = True) -> dolfinx.fem.Function:
        """Assemble A (unless ``matrix`` is False: its coefficients are constant, the factors kept)
        and b, and solve for u (collective)."""
        if matrix:
            self.assemble_matrix()
        self.assemble_vector()
        self.solve_system(petsc_vec(self.u))
        self.u.x.scatter_forward()
        return self.u

    def solve_system(self, x: PETSc.Vec, b: PETSc.Vec | None = None) -> None:
        """x = A^-1 b (b: the assembled right-hand side unless given) with A as last assembled. With
        ``fallback`` an iterative solve that fails (the same reason on every rank) is repeated by
        MUMPS LU, which the KSP keeps from then on; a failed solve raises LinearSolveError."""
        b = self.b if b is None else b
        self._solve(b, x)
        if self.fallback and self.ksp.getConvergedReason() < 0 and self.ksp.getType() != "preonly":
            self.ksp.setType("preonly")
            self.ksp.getPC().setType("lu")
            self.ksp.getPC().setFactorSolverType("mumps")
            self._solve(b, x)
        reason = self.ksp.getConvergedReason()
        if reason < 0:
            raise LinearSolveError(f"KSP diverged (reason {reason})")

    def _solve(self, b: PETSc.Vec, x: PETSc.Vec) -> None:
        """KSPSolve after the set-up, each timed; a PETSc error (e.g. a zero pivot or a MUMPS
        failure: the same on every rank) raises LinearSolveError."""
        try:
            start = time.perf_counter()
            self.ksp.setUp()
            # refactorises when A changed (KSPSetUp alone does so only once)
            self.ksp.getPC().setUp()
            set_up = time.perf_counter()
            self.ksp.solve(b, x)
        except PETSc.Error as error:
            raise LinearSolveError(f"PETSc error {error.ierr} in KSPSolve") from None
        self.timings.factorisation += set_up - start
        self.timings.solve += time.perf_counter() - set_up
        if not self.keep_options:
            self.release_options()

    def release_options(self) -> None:
        """Remove the options set under the prefix (the KSP has read them: set up or, for options
        that setFromOptions reads, constructed); a user's own (command line) stay."""
        if self._options is not None:
            self._options.release()
            self._options = None

    def destroy(self) -> None:
        """Free the PETSc objects (the matrix and KSP if not another problem's) and the options."""
        self.release_options()
        owned = (self.ksp, self.A) if self._owner else ()
        for item in (*owned, self.b):
            item.destroy()

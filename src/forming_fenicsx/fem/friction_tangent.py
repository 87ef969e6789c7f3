"""The friction bound in Newton's step: the derivative of the residual through tau_f.

Newton's residual F(u; s) reads the friction bound tau_f at the friction state s (Coulomb's
mu sigma_N-bar(s), capped at k(s) with friction.shear_limit, or the factor law's m k(s)), and each
step freezes s = u (newton.py). Its derivative is then

    J = A + K + B M^-1 C,

A = dF/du at fixed s (Newton's operator, newton_forms.py), K = dF/ds through the local part of the
bound (k(s), a local normal stress), and, with Coulomb's averaged normal stress
sigma_N-bar = M^-1 b(s) (boundary_filter.py: M the filter's matrix, b(s) = (sigma_N(s), q) on
Gamma3), B = dF/dsigma_N-bar and C = db/ds. Without these terms the bound follows the pressure one
step late, and the last steps converge linearly (about 0.54 a step); with them the rolling grid's
two slowest Coulomb points took 15 and 18 solves instead of 22 and 21 (docs/rolling.md). The terms
join Newton's GMRES (tangent_gmres.py) as a Correction: K and C are not symmetric, and A keeps its
own (symmetric) factorisation. Newton's step carries them in rolling only: Coulomb's bound, and
the factor law's m k(s) on a rate-sensitive metal (FlowProblem.factor_bound_moves; newton.py says
why not otherwise).
"""
from __future__ import annotations

import dolfinx.fem
import dolfinx.fem.petsc
import ufl
from petsc4py import PETSc
from ufl.algorithms import expand_derivatives

from forming_fenicsx.fem.forms import FlowProblem


class FrictionTangent:
    """K, B and C compiled from Newton's residual (module docstring): the Correction of the friction
    bound's derivative."""

    name = "friction bound"

    def __init__(self, problem: FlowProblem, residual: ufl.Form):
        state = problem.friction_state.state
        self._bcs = problem.bcs
        self._filter = problem.normal_stress_average
        trial = ufl.TrialFunction(problem.system_space)
        velocity = ufl.split(trial)[0] if problem.mixed else trial
        direction = ufl.TrialFunction(state.function_space)

        def by_state(form: ufl.Form) -> ufl.Form | None:
            """d form/ds in the velocity part of the system's trial function (None: zero)."""
            derivative = expand_derivatives(ufl.derivative(form, state, direction))
            if derivative.empty():
                return None
            return ufl.replace(derivative, {direction: velocity}) if problem.mixed else derivative

        local = by_state(residual)
        source = None if self._filter is None else by_state(self._filter.source_form)
        if source is None:  # the averaged stress of a state-independent pressure (the
            self._filter = None  # augmented contact's multiplier) is constant in the step
        self.terms = (local is not None) + (source is not None)
        self._K = None if local is None else dolfinx.fem.form(local)
        self.K = None if local is None else dolfinx.fem.petsc.create_matrix(self._K)
        self._B = self._C = self.B = self.C = None
        self._vectors: tuple[PETSc.Vec, ...] = ()
        if source is not None:
            self._B = dolfinx.fem.form(ufl.derivative(residual, self._filter.value,
                                                      ufl.TrialFunction(self._filter.space)))
            self._C = dolfinx.fem.form(source)
            self.B, self.C = (dolfinx.fem.petsc.create_matrix(self._B),
                              dolfinx.fem.petsc.create_matrix(self._C))
            # C x (on the filter's space) and M^-1 C x
            self._vectors = (self.C.createVecs()[1], self.C.createVecs()[1])

    def assemble(self) -> None:
        """K, B and C at the current u = s; rows and columns of constrained velocities are left
        out (their du is set by the Dirichlet rows of A), K's constrained diagonal zero."""
        if self.K is not None:
            self.K.zeroEntries()
            dolfinx.fem.petsc.assemble_matrix(self.K, self._K, bcs=self._bcs, diagonal=0.0)
            self.K.assemble()
        if self._filter is not None:
            for matrix, form in ((self.B, self._B), (self.C, self._C)):
                matrix.zeroEntries()
                dolfinx.fem.petsc.assemble_matrix(matrix, form, bcs=self._bcs)
                matrix.assemble()

    def add_to(self, x: PETSc.Vec, y: PETSc.Vec) -> None:
        """y += (K + B M^-1 C) x."""
        if self.K is not None:
            self.K.multAdd(x, y, y)
        if self._filter is not None:
            source, average = self._vectors
            self.C.mult(x, source)
            self._filter.solve_vector(source, average)
            self.B.multAdd(average, y, y)

    def destroy(self) -> None:
        for item in (self.K, self.B, self.C, *self._vectors):
            if item is not None:
                item.destroy()

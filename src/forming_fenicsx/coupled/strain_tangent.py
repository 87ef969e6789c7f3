"""The transported strain in Newton's step: the reduced Jacobian of the coupled flow.

With eps = eps(u) the transport solution (strain_transport.py, R(eps, u) = 0 with matrix D), the
flow residual F(u, eps(u)) has the derivative

    J = A - B D^-1 C,   A = dF/du (Newton's operator, newton_forms.py), B = dF/deps, C = dR/du.

Staggered, the step solves A du = F and the strain follows at the next freeze: where the velocity
is sensitive to the strain the two creep towards each other by a fixed factor per step. Here
J du = F is solved by GMRES, J applied matrix-free and right-preconditioned with A's factors,
starting from A^-1 F: each iteration is a pair of triangular solves with A's factors and a
transport solve with D (strain_transport.StrainField.transport_solve), so no matrix is factorised
beyond the staggered step's.
"""
from __future__ import annotations

import dolfinx.fem
import dolfinx.fem.petsc
import ufl
from petsc4py import PETSc

# relative residual of J du = F: 1e-6 took 11 to 18 iterations a step, 1e-2 more Newton steps
# (docs/hardening.md)
GMRES_TOLERANCE = 1e-3
GMRES_ITERATIONS = 30


class StrainTangent:
    """B and C compiled from the flow residual and the strain field, and the GMRES solve of J du = F
    with Newton's operator A and its factors (the KSP ``factors``; the options prefix
    ``strain_tangent_`` can change the Krylov method)."""

    def __init__(self, problem, field, residual: ufl.Form, A: PETSc.Mat, factors: PETSc.KSP):
        """``field``: a coupled field whose derivative the step carries (``tangent``: its
        ``coefficient`` the flow reads, ``velocity_derivative`` and ``transport_solve``)."""
        self.field, self._bcs, self._A = field, problem.bcs, A
        trial = ufl.TrialFunction(problem.system_space)
        velocity = ufl.split(trial)[0] if problem.mixed else trial
        self._forms = (dolfinx.fem.form(ufl.derivative(residual, field.coefficient,
                                                       ufl.TrialFunction(field.space))),
                       dolfinx.fem.form(field.velocity_derivative(velocity)))
        self.B, self.C = (dolfinx.fem.petsc.create_matrix(form) for form in self._forms)
        strain = self.C.createVecs()[1]
        self._strain_vectors = strain, strain.duplicate()
        self._flow_vector = self.B.createVecs()[1]
        self._start = self._flow_vector.duplicate()
        self._shell = PETSc.Mat().createPython(A.getSizes(), _Shell(self.mult), comm=A.getComm())
        self._shell.setUp()
        self._ksp = PETSc.KSP().create(A.getComm())
        self._ksp.setOperators(self._shell)
        self._ksp.setType("gmres")
        self._ksp.setPCSide(PETSc.PC.Side.RIGHT)
        self._ksp.getPC().setType("python")
        self._ksp.getPC().setPythonContext(_Shell(factors.solve))
        self._ksp.setTolerances(rtol=GMRES_TOLERANCE, max_it=GMRES_ITERATIONS)
        self._ksp.setInitialGuessNonzero(True)
        self._ksp.setOptionsPrefix("strain_tangent_")
        self._ksp.setFromOptions()
        self.iterations = 0

    def assemble(self) -> None:
        """B and C at the current u and eps = eps(u); rows and columns of constrained velocities are
        left out (their du is set by the Dirichlet rows of A)."""
        for matrix, form in zip((self.B, self.C), self._forms):
            matrix.zeroEntries()
            dolfinx.fem.petsc.assemble_matrix(matrix, form, bcs=self._bcs)
            matrix.assemble()

    def mult(self, x: PETSc.Vec, y: PETSc.Vec) -> None:
        """y = J x = A x - B D^-1 C x, with A as last assembled."""
        c, d = self._strain_vectors
        self._A.mult(x, y)
        self.C.mult(x, c)
        self.field.transport_solve(c, d)
        self.B.mult(d, self._flow_vector)
        y.axpy(-1.0, self._flow_vector)

    def solve(self, F: PETSc.Vec, du: PETSc.Vec) -> bool:
        """J du = F by GMRES from du (A^-1 F on entry, A and its factors at the current u); True
        when it converged, else du is left as it came."""
        self.assemble()
        du.copy(self._start)
        self._ksp.solve(F, du)
        converged = self._ksp.getConvergedReason() > 0
        self.iterations = self._ksp.getIterationNumber()
        if not converged:
            self._start.copy(du)
        return converged

    def destroy(self) -> None:
        for item in (self._ksp, self._shell, self.B, self.C, *self._strain_vectors,
                     self._flow_vector, self._start):
            item.destroy()


class _Shell:
    """A PETSc Python context (shell matrix or preconditioner) applying ``action(x, y)``."""

    def __init__(self, action):
        self._action = action

    def mult(self, _, x: PETSc.Vec, y: PETSc.Vec) -> None:
        self._action(x, y)

    def apply(self, _, x: PETSc.Vec, y: PETSc.Vec) -> None:
        self._action(x, y)

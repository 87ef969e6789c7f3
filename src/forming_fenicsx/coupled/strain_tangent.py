"""The transported strain in Newton's step: the reduced Jacobian of the coupled flow.

With eps = eps(u) the transport solution (strain_transport.py, R(eps, u) = 0 with matrix D), the
flow residual F(u, eps(u)) has the derivative

    J = A - B D^-1 C,   A = dF/du (Newton's operator, newton_forms.py), B = dF/deps, C = dR/du.

Staggered, the step solves A du = F and the strain follows at the next freeze: where the velocity
is sensitive to the strain the two creep towards each other by a fixed factor per step. Here the
term -B D^-1 C joins Newton's GMRES (fem/tangent_gmres.py); each product is a transport solve with
D (strain_transport.StrainField.transport_solve), so no matrix is factorised beyond the staggered
step's.
"""
from __future__ import annotations

import dolfinx.fem
import dolfinx.fem.petsc
import ufl
from petsc4py import PETSc


class StrainTangent:
    """B and C compiled from the flow residual and the strain field: the Correction -B D^-1 C of
    fem/tangent_gmres.py."""

    def __init__(self, problem, field, residual: ufl.Form):
        """``field``: a coupled field whose derivative the step carries (``tangent``: its
        ``coefficient`` the flow reads, ``velocity_derivative`` and ``transport_solve``)."""
        self.field, self.name, self._bcs = field, field.name, problem.bcs
        trial = ufl.TrialFunction(problem.system_space)
        velocity = ufl.split(trial)[0] if problem.mixed else trial
        self._forms = (dolfinx.fem.form(ufl.derivative(residual, field.coefficient,
                                                       ufl.TrialFunction(field.space))),
                       dolfinx.fem.form(field.velocity_derivative(velocity)))
        self.B, self.C = (dolfinx.fem.petsc.create_matrix(form) for form in self._forms)
        strain = self.C.createVecs()[1]
        self._strain_vectors = strain, strain.duplicate()
        self._flow_vector = self.B.createVecs()[1]

    def assemble(self) -> None:
        """B and C at the current u and eps = eps(u); rows and columns of constrained velocities are
        left out (their du is set by the Dirichlet rows of A)."""
        for matrix, form in zip((self.B, self.C), self._forms):
            matrix.zeroEntries()
            dolfinx.fem.petsc.assemble_matrix(matrix, form, bcs=self._bcs)
            matrix.assemble()

    def add_to(self, x: PETSc.Vec, y: PETSc.Vec) -> None:
        """y += -B D^-1 C x."""
        c, d = self._strain_vectors
        self.C.mult(x, c)
        self.field.transport_solve(c, d)
        self.B.mult(d, self._flow_vector)
        y.axpy(-1.0, self._flow_vector)

    def destroy(self) -> None:
        for item in (self.B, self.C, *self._strain_vectors, self._flow_vector):
            item.destroy()

"""Averaging at element centres or nodes, as the paper averages strain rates, pressures and
stresses, and the element-wise L2 projection.

Averaging is a lumped L2 projection: value_i = (integral of f * phi_i) / (integral of phi_i). Onto
a piecewise-constant space this is the element mean ("centres"); onto a Lagrange space it is a
weighted mean of the elements around each node ("nodes"). It needs no linear solve and is the
same on any number of MPI ranks.
"""
from __future__ import annotations

import dolfinx.fem
import dolfinx.fem.petsc
import numpy as np
import ufl
from petsc4py import PETSc

from forming_fenicsx.core.compat import function_space, petsc_vec
from forming_fenicsx.fem.linear_problem import LinearProblem

# CG with Jacobi to 1e-12 on a block-diagonal mass matrix: a few iterations, about a tenth of
# MUMPS LU's time on the projection of streamlines.py (docs/hardening.md)
ELEMENTWISE = {"ksp_type": "cg", "pc_type": "jacobi", "ksp_rtol": 1e-12, "ksp_atol": 0.0,
               "ksp_max_it": 500}


class LumpedProjector:
    """Projects one UFL expression onto the space of ``target``; forms are compiled once."""

    def __init__(self, expr: ufl.core.expr.Expr, target: dolfinx.fem.Function,
                 quadrature_degree: int, measure: ufl.Measure | None = None):
        """``measure`` defaults to dx; a boundary measure (ds(tag)) projects onto the traces there
        and leaves every other value zero."""
        space = target.function_space
        v = ufl.TestFunction(space)
        if measure is None:
            measure = ufl.dx(domain=space.mesh, metadata={"quadrature_degree": quadrature_degree})
        ones = ufl.as_vector([1.0] * space.num_sub_spaces) if space.num_sub_spaces else 1.0
        self.target = target
        self._form = dolfinx.fem.form(ufl.inner(expr, v) * measure)
        self._weights = dolfinx.fem.petsc.assemble_vector(
            dolfinx.fem.form(ufl.inner(ones, v) * measure))
        self._weights.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        weights = self._weights.getArray()
        weights[:] = np.divide(1.0, weights, out=np.zeros_like(weights), where=weights != 0)
        self._rhs = self._weights.duplicate()

    def weights_mask(self) -> np.ndarray:
        """1 at the owned values the projection sets (those of the measure's support), else 0."""
        return (self._weights.getArray() != 0).astype(float)

    def project(self) -> dolfinx.fem.Function:
        """Recompute the target from the current values of the expression's coefficients."""
        with self._rhs.localForm() as local:
            local.set(0.0)
        dolfinx.fem.petsc.assemble_vector(self._rhs, self._form)
        self._rhs.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        petsc_vec(self.target).pointwiseMult(self._rhs, self._weights)
        self.target.x.scatter_forward()
        return self.target


def project_discontinuous(expr: ufl.core.expr.Expr, target: dolfinx.fem.Function,
                          quadrature_degree: int) -> dolfinx.fem.Function:
    """The L2 projection of ``expr`` onto the discontinuous space of ``target``: M c = (f, phi_i)
    with the element-block-diagonal mass matrix M, by conjugate gradients with Jacobi's
    preconditioner (ELEMENTWISE, options prefix ``projection_``). Unlike an interpolation it
    evaluates ``expr`` only at interior Gauss points (the hoop rate u_y/y is 0/0 on the axis)."""
    space = target.function_space
    u, v = ufl.TrialFunction(space), ufl.TestFunction(space)
    dx = ufl.dx(domain=space.mesh, metadata={"quadrature_degree": quadrature_degree})
    problem = LinearProblem(dolfinx.fem.form(ufl.inner(u, v) * dx),
                            [dolfinx.fem.form(ufl.inner(expr, v) * dx)], target,
                            prefix="projection", options=ELEMENTWISE)
    try:
        return problem.solve()
    finally:
        problem.destroy()


def cell_means(mesh, expr, name: str, degree: int) -> dolfinx.fem.Function:
    """Element means of an expression (a DG0 function), with quadrature of ``degree``."""
    target = dolfinx.fem.Function(function_space(mesh, "DP", 0), name=name)
    return LumpedProjector(expr, target, degree).project()

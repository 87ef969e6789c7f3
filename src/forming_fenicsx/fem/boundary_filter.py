"""The averaged (mollified) normal stress sigma_N-bar of section 2, on the traces of P1 on Gamma3.

The boundary Helmholtz filter (p, q) + l^2 (grad_t p, grad_t q) = (f, q) on Gamma3 for every P1
trace q: a convolution of f with the kernel exp(-|s|/l)/(2l) along the die. The matrix is assembled
and factorised once; ``update`` re-solves for the current values of the expression's coefficients.
"""
from __future__ import annotations

import dolfinx.fem
import dolfinx.mesh
import numpy as np
import ufl
from petsc4py import PETSc

from forming_fenicsx.core.compat import function_space
from forming_fenicsx.fem.linear_problem import DIRECT, LinearProblem


class BoundaryFilter:
    """The P1 field ``value`` on Gamma3 (zero elsewhere), ``source`` mollified over ``length``."""

    def __init__(self, source: ufl.core.expr.Expr, mesh: dolfinx.mesh.Mesh,
                 facet_tags: dolfinx.mesh.MeshTags, contact_tag: int, length: float, name: str,
                 prefix: str):
        """``prefix``: the name of its PETSc options (petsc_options.py), MUMPS LU by default."""
        self.space = space = function_space(mesh, "P", 1)
        self.value = dolfinx.fem.Function(space, name=name)
        p, q = ufl.TrialFunction(space), ufl.TestFunction(space)
        n = ufl.FacetNormal(mesh)
        ds = ufl.Measure("ds", domain=mesh, subdomain_data=facet_tags)(contact_tag)

        def tangential_gradient(f: ufl.core.expr.Expr) -> ufl.core.expr.Expr:
            return ufl.grad(f) - ufl.dot(ufl.grad(f), n) * n

        # The zero cell term puts every row in the sparsity pattern, so that the rows off Gamma3 can
        # carry the unit diagonal of their (zero) Dirichlet condition.
        pattern = dolfinx.fem.Constant(mesh, PETSc.ScalarType(0.0)) * p * q * ufl.dx(domain=mesh)
        a = (p * q + length**2 * ufl.dot(tangential_gradient(p), tangential_gradient(q))) * ds \
            + pattern
        fdim = mesh.topology.dim - 1
        contact_dofs = dolfinx.fem.locate_dofs_topological(
            space, fdim, facet_tags.indices[facet_tags.values == contact_tag])
        local = space.dofmap.index_map.size_local + space.dofmap.index_map.num_ghosts
        others = np.setdiff1d(np.arange(local, dtype=np.int32), contact_dofs)
        bcs = [dolfinx.fem.dirichletbc(PETSc.ScalarType(0.0), others, space)]
        # (f, q) on Gamma3 (friction_tangent.py differentiates it)
        self.source_form = source * q * ds
        self._problem = LinearProblem(dolfinx.fem.form(a), [dolfinx.fem.form(self.source_form)],
                                      self.value, bcs, prefix=prefix, options=DIRECT)
        # all read by setFromOptions (a user's own, on the command line, stay)
        self._problem.release_options()
        self._problem.assemble_matrix()

    def update(self) -> dolfinx.fem.Function:
        """Recompute the field from the current values of the source's coefficients."""
        return self._problem.solve(matrix=False)

    def solve_vector(self, b: PETSc.Vec, x: PETSc.Vec) -> None:
        """x = M^-1 b with the filter's factors (b zero off Gamma3)."""
        self._problem.solve_system(x, b)

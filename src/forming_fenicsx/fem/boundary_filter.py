"""The averaged (mollified) normal stress sigma_N-bar of section 2, on the traces of P1 on Gamma3.

The boundary Helmholtz filter (p, q) + l^2 (grad_t p, grad_t q) = (f, q) on Gamma3 for every P1 trace
q: a convolution of f with the kernel exp(-|s|/l)/(2l) along the die. The matrix is assembled and
factorised once; ``update`` re-solves for the current values of the expression's coefficients.
"""
from __future__ import annotations

import dolfinx.fem
import dolfinx.fem.petsc
import numpy as np
import ufl
from petsc4py import PETSc

from forming_fenicsx.core.compat import function_space, petsc_vec
from forming_fenicsx.core.petsc_options import PrefixedOptions


class BoundaryFilter:
    """The P1 field ``value`` on Gamma3 (zero elsewhere), ``source`` mollified over ``length``."""

    OPTIONS = {"ksp_type": "preonly", "pc_type": "lu", "pc_factor_mat_solver_type": "mumps"}

    def __init__(self, source, mesh, facet_tags, contact_tag: int, length: float, name: str,
                 prefix: str):
        """``prefix``: the name of its PETSc options (petsc_options.py), defaults OPTIONS."""
        space = function_space(mesh, "P", 1)
        self.value = dolfinx.fem.Function(space, name=name)
        p, q = ufl.TrialFunction(space), ufl.TestFunction(space)
        n = ufl.FacetNormal(mesh)
        ds = ufl.Measure("ds", domain=mesh, subdomain_data=facet_tags)(contact_tag)

        def tangential_gradient(f):
            return ufl.grad(f) - ufl.dot(ufl.grad(f), n) * n

        # The zero cell term puts every row in the sparsity pattern, so that the rows off Gamma3 can
        # carry the unit diagonal of their (zero) Dirichlet condition.
        pattern = dolfinx.fem.Constant(mesh, PETSc.ScalarType(0.0)) * p * q * ufl.dx(domain=mesh)
        self._a = dolfinx.fem.form((p * q + length**2 * ufl.dot(tangential_gradient(p), tangential_gradient(q)))
                                   * ds + pattern)
        self._L = dolfinx.fem.form(source * q * ds)
        fdim = mesh.topology.dim - 1
        contact_dofs = dolfinx.fem.locate_dofs_topological(space, fdim, facet_tags.indices[facet_tags.values == contact_tag])
        local = space.dofmap.index_map.size_local + space.dofmap.index_map.num_ghosts
        others = np.setdiff1d(np.arange(local, dtype=np.int32), contact_dofs)
        self._bcs = [dolfinx.fem.dirichletbc(PETSc.ScalarType(0.0), others, space)]
        self._A = dolfinx.fem.petsc.assemble_matrix(self._a, bcs=self._bcs)
        self._A.assemble()
        self._b = dolfinx.fem.petsc.create_vector(self._L)
        self._ksp = PETSc.KSP().create(mesh.comm)
        self._ksp.setOperators(self._A)
        options = PrefixedOptions(prefix, self.OPTIONS)
        self._ksp.setOptionsPrefix(options.prefix)
        self._ksp.setFromOptions()
        options.release()  # all read by setFromOptions; a user's own (command line) stay

    def update(self) -> dolfinx.fem.Function:
        """Recompute the field from the current values of the source's coefficients."""
        with self._b.localForm() as local:
            local.set(0.0)
        dolfinx.fem.petsc.assemble_vector(self._b, self._L)
        dolfinx.fem.petsc.apply_lifting(self._b, [self._a], bcs=[self._bcs])
        self._b.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        dolfinx.fem.petsc.set_bc(self._b, self._bcs)
        self._ksp.solve(self._b, petsc_vec(self.value))
        self.value.x.scatter_forward()
        return self.value


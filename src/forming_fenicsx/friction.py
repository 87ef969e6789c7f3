"""Coulomb friction on Gamma3, regularised by d_T as in Remark 3.2 / (3.11).

j_dT(w, v) = int tau_f(w) sqrt(|v_T|^2 + d_T^2), with Gateaux derivative
tau_f(w) v_T / sqrt(|v_T|^2 + d_T^2); the secant-modulus methods linearise it with the slip
coefficient tau_f / sqrt(|u_n,T|^2 + d_T^2) of the current state.
"""
from __future__ import annotations

import dolfinx.fem
import dolfinx.fem.petsc
import numpy as np
import ufl
from petsc4py import PETSc

from .compat import function_space, petsc_vec


def tangential(u, n):
    """u_T = u - u_N n."""
    return u - ufl.dot(u, n) * n


def friction_bound(mu: float, normal_pressure):
    """Coulomb bound tau_f = mu * sigma_N-bar (section 2), sigma_N-bar >= 0 the normal pressure."""
    return mu * normal_pressure


def slip_coefficient(tau_f, u_state, n, d_T: float):
    """tau_f / sqrt(|u_T|^2 + d_T^2): the secant of the regularised friction traction."""
    slip = tangential(u_state, n)
    return tau_f / ufl.sqrt(ufl.dot(slip, slip) + d_T**2)


def friction_form(u, v, coefficient, n, ds_contact):
    """int c_T u_T . v_T over Gamma3: the linearised <j'_dT(w, u), v> of (3.12)."""
    return coefficient * ufl.dot(tangential(u, n), tangential(v, n)) * ds_contact


SLOW_SLIP = 1e-2  # Newton's operator takes the secant where |u_T| < SLOW_SLIP * process velocity


def regularised_functional(tau_f, u, n, d_T: float):
    """Integrand of j_dT(w, u) = int tau_f(w) sqrt(|u_T|^2 + d_T^2) of (3.11)."""
    slip = tangential(u, n)
    return tau_f * ufl.sqrt(ufl.dot(slip, slip) + d_T**2)


def newton_form(du, v, u, tau_f, n, d_T: float, slow_slip: float, ds_contact):
    """Friction's part of Newton's operator at u (tau_f fixed): the secant form of (3.13) where the die
    point slips slower than ``slow_slip`` or sticks, the tangent of (3.11) where it slips faster. Near
    zero slip the tangent's curvature is about tau_f/d_T, which made Newton's line search cut the steps
    (docs/solvers.md); in fast slip the tangent keeps the steps quadratic."""
    slip = tangential(u, n)
    coefficient = slip_coefficient(tau_f, u, n, d_T)
    fast = ufl.conditional(ufl.gt(ufl.dot(slip, slip), slow_slip**2), 1.0, 0.0)
    du_T, v_T = tangential(du, n), tangential(v, n)
    return (friction_form(du, v, coefficient, n, ds_contact)
            - fast * coefficient * ufl.dot(slip, du_T) * ufl.dot(slip, v_T) / (ufl.dot(slip, slip) + d_T**2)
            * ds_contact)


def friction_traction(coefficient, u_state, n):
    """Friction stress on the workpiece, sigma_T = -c_T u_T (opposes the slip)."""
    return -coefficient * tangential(u_state, n)


class AveragedNormalStress:
    """The averaged (mollified) normal stress sigma_N-bar of section 2, on the traces of P1 on Gamma3.

    The contact pressure is projected onto the boundary space and mollified over the length l by
    the boundary Helmholtz filter (p, q) + l^2 (grad_t p, grad_t q) = (sigma_N, q) on Gamma3, i.e. a
    convolution with the kernel exp(-|s|/l)/(2l) along the die. The matrix is assembled and factorised
    once; ``update`` re-solves for the current source.
    """

    def __init__(self, source, mesh, facet_tags, contact_tag: int, length: float, petsc_options: dict):
        space = function_space(mesh, "P", 1)
        self.value = dolfinx.fem.Function(space, name="averaged_normal_stress")
        p, q = ufl.TrialFunction(space), ufl.TestFunction(space)
        n = ufl.FacetNormal(mesh)
        ds = ufl.Measure("ds", domain=mesh, subdomain_data=facet_tags)(contact_tag)

        def tangential_gradient(f):
            return ufl.grad(f) - ufl.dot(ufl.grad(f), n) * n

        # The zero cell term puts every row in the sparsity pattern, so that the rows off Gamma3 can
        # carry the unit diagonal of their (zero) Dirichlet condition.
        pattern = dolfinx.fem.Constant(mesh, PETSc.ScalarType(0.0)) * p * q * ufl.dx(domain=mesh)
        a = dolfinx.fem.form((p * q + length**2 * ufl.dot(tangential_gradient(p), tangential_gradient(q))) * ds
                             + pattern)
        self._L = dolfinx.fem.form(source * q * ds)
        fdim = mesh.topology.dim - 1
        contact_dofs = dolfinx.fem.locate_dofs_topological(space, fdim, facet_tags.indices[facet_tags.values == contact_tag])
        local = space.dofmap.index_map.size_local + space.dofmap.index_map.num_ghosts
        others = np.setdiff1d(np.arange(local, dtype=np.int32), contact_dofs)
        self._bcs = [dolfinx.fem.dirichletbc(PETSc.ScalarType(0.0), others, space)]
        self._A = dolfinx.fem.petsc.assemble_matrix(a, bcs=self._bcs)
        self._A.assemble()
        self._a = a
        self._b = dolfinx.fem.petsc.create_vector(self._L)
        self._ksp = PETSc.KSP().create(mesh.comm)
        self._ksp.setOperators(self._A)
        self._ksp.setType(petsc_options.get("ksp_type", "preonly"))
        pc = self._ksp.getPC()
        pc.setType(petsc_options.get("pc_type", "lu"))
        if pc.getType() in ("lu", "cholesky"):
            pc.setFactorSolverType(petsc_options.get("pc_factor_mat_solver_type", "mumps"))

    def update(self) -> dolfinx.fem.Function:
        """Recompute sigma_N-bar from the current source (the contact pressure of the friction state)."""
        with self._b.localForm() as local:
            local.set(0.0)
        dolfinx.fem.petsc.assemble_vector(self._b, self._L)
        dolfinx.fem.petsc.apply_lifting(self._b, [self._a], bcs=[self._bcs])
        self._b.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        dolfinx.fem.petsc.set_bc(self._b, self._bcs)
        self._ksp.solve(self._b, petsc_vec(self.value))
        self.value.x.scatter_forward()
        return self.value

"""The secant state of the iteration: the velocity u_n the secant coefficient G(u_n) =
sigma_p/rate of a(w; u, v) (3.2), the contact active set and the slip regularisation are taken
from."""
from __future__ import annotations

import dolfinx.fem
import numpy as np
import ufl
from petsc4py import PETSc

from forming_fenicsx.core.compat import function_space, petsc_vec
from forming_fenicsx.physics.coordinates import CoordinateSystem
from forming_fenicsx.fem.projection import LumpedProjector


class SecantState:
    """``u``: u_n. G is evaluated at the Gauss points of u_n ("quadrature": a UFL expression), or
    held as a Function of element means ("centres") or vertex means ("nodes": bilinear in between
    keeps G > 0 everywhere; Q2 nodal values would not) of the projected equivalent strain rate."""

    def __init__(self, space, coordinates: CoordinateSystem, material, averaging: str, degree: int,
                 strain=None, temperature=None):
        mesh = space.mesh
        self.material = material
        self.u = dolfinx.fem.Function(space)
        rate = coordinates.equivalent_strain_rate(self.u)
        self._uniform = dolfinx.fem.Constant(mesh, PETSc.ScalarType(0.0))
        # the strain (a hardening law's UFL field) and the temperature only with "quadrature", as
        # the scene checks
        self._quadrature = (material.secant_ufl(rate, strain, temperature)
                            if averaging == "quadrature" else None)
        if self._quadrature is None:
            averaging_space = (function_space(mesh, "DP", 0) if averaging == "centres"
                               else function_space(mesh, "P", 1))
            self.strain_rate = dolfinx.fem.Function(averaging_space, name="equivalent_strain_rate")
            self.secant = dolfinx.fem.Function(averaging_space, name="secant_viscosity")
            self._projector = LumpedProjector(rate, self.strain_rate, degree)

    def coefficient(self):
        """G(u_n): the averaged Function, or the quadrature-point expression (a uniform value
        first)."""
        if self._quadrature is None:
            return self.secant
        return ufl.conditional(ufl.gt(self._uniform, 0.0), self._uniform, self._quadrature)

    def set_uniform(self, rate: float) -> None:
        """A uniform modulus G(rate), the start of both secant methods (u_0 carries no strain
        rate)."""
        value = self.material.secant(np.array([rate]))[0]
        if self._quadrature is None:
            self.secant.x.array[:] = value
        else:
            self._uniform.value = value

    def update(self, u: dolfinx.fem.Function) -> None:
        """u_n <- u, and G from it."""
        u.x.scatter_forward()
        petsc_vec(u).copy(petsc_vec(self.u))
        self.u.x.scatter_forward()
        if self._quadrature is None:
            self._projector.project()
            self.secant.x.array[:] = self.material.secant(self.strain_rate.x.array)
        else:
            self._uniform.value = 0.0

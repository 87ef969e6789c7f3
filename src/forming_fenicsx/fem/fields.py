"""The unknowns of a flow problem and their boundary conditions: the velocity (penalty
formulation), or velocity and pressure (mixed), with the constraints (2.5) on Gamma1 and (2.8) on
Gamma6."""
from __future__ import annotations

import dolfinx.fem
import numpy as np
from petsc4py import PETSc

from forming_fenicsx.core.compat import function_space, mixed_space
from forming_fenicsx.core.roles import ROLES


class FlowFields:
    """Spaces and functions: ``solution`` (what a linear system solves for), the velocity ``u`` and
    (mixed) the ``pressure``; ``bcs`` the Dirichlet conditions of the system."""

    def __init__(self, mesh, facet_tags, constraints, degree: int, mixed: bool):
        self.mesh, self.facet_tags, self.mixed = mesh, facet_tags, mixed
        self.pressure = None
        if mixed:
            self.system_space = mixed_space(mesh, degree, "DPC", 1)
            self.solution = dolfinx.fem.Function(self.system_space)
            self.V, self._velocity_dofs = self.system_space.sub(0).collapse()
            pressure_space, self._pressure_dofs = self.system_space.sub(1).collapse()
            self.pressure = dolfinx.fem.Function(pressure_space, name="pressure")
            self.u = dolfinx.fem.Function(self.V, name="velocity")
        else:
            self.V = self.system_space = function_space(mesh, "P", degree, (mesh.geometry.dim,))
            self.u = self.solution = dolfinx.fem.Function(self.V, name="velocity")
        velocity = self.system_space.sub(0) if mixed else self.V
        self.bcs = [dolfinx.fem.dirichletbc(PETSc.ScalarType(c.value),
                                            self.boundary_dofs(c.role, c.component, velocity),
                                            velocity.sub(c.component)) for c in constraints]

    def after_solve(self) -> None:
        """Velocity (and pressure) from the solution of a linear system."""
        self.solution.x.scatter_forward()
        if self.mixed:
            self.u.x.array[:] = self.solution.x.array[self._velocity_dofs]
            self.pressure.x.array[:] = self.solution.x.array[self._pressure_dofs]

    @property
    def unknowns(self) -> int:
        """Global number of unknowns of the linear systems."""
        index_map = self.system_space.dofmap.index_map
        return index_map.size_global * self.system_space.dofmap.index_map_bs

    def role_facets(self, role: str) -> np.ndarray:
        """Local facets of a boundary role."""
        return self.facet_tags.indices[self.facet_tags.values == ROLES[role]]

    def boundary_dofs(self, role: str, component: int, space=None) -> np.ndarray:
        """Local dof indices (blocked space, unrolled) of one velocity component on a boundary
        role, in ``space`` (default the velocity space V; the mixed formulation's velocity subspace
        for its bcs)."""
        space = self.V if space is None else space
        return dolfinx.fem.locate_dofs_topological(space.sub(component), self.mesh.topology.dim - 1,
                                                   self.role_facets(role))

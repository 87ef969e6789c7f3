"""The unknowns of a flow problem and their boundary conditions: the velocity (penalty
formulation), or velocity and pressure (mixed), with the constraints (2.5) on Gamma1 and (2.8) on
Gamma6."""
from __future__ import annotations

import dolfinx.fem
import numpy as np
from mpi4py import MPI
from petsc4py import PETSc

from forming_fenicsx.core.compat import function_space, mixed_space
from forming_fenicsx.core.roles import ROLES


def collapse_vector(sub: dolfinx.fem.FunctionSpace, mesh, degree: int
                    ) -> tuple[dolfinx.fem.FunctionSpace, np.ndarray]:
    """``sub.collapse()`` for the vector Lagrange sub-space of a mixed space: the vector space and
    each of its (unrolled) dofs' index in the mixed space. Built from the collapses of the scalar
    components, which dolfinx numbers as the nodes of a vector space made alone (checked: the
    dofs' coordinates, on every rank; else the vector collapse itself). dolfinx 0.5's collapse of
    the vector sub-space grows as N^2.5 (32.7 s for 788943 unknowns on two ranks, the components'
    0.05 s): 72 s of the set-up of a million-unknown 3D problem."""
    dim = mesh.geometry.dim
    space = function_space(mesh, "P", degree, (dim,))
    points = space.tabulate_dof_coordinates()
    owned = space.dofmap.index_map.size_local
    parts = [sub.sub(k).collapse() for k in range(dim)]
    aligned = all(part.dofmap.index_map.size_local == owned
                  and np.array_equal(part.tabulate_dof_coordinates(), points) for part, _ in parts)
    if not mesh.comm.allreduce(aligned, op=MPI.LAND):
        space, dofs = sub.collapse()
        return space, np.asarray(dofs)
    dofs = np.empty(len(points) * dim, dtype=np.int64)
    for k, (_, component) in enumerate(parts):
        dofs[k::dim] = component
    return space, dofs


class FlowFields:
    """Spaces and functions: ``solution`` (what a linear system solves for), the velocity ``u`` and
    (mixed) the ``pressure``; ``bcs`` the Dirichlet conditions of the system."""

    def __init__(self, mesh, facet_tags, constraints, degree: int, mixed: bool):
        self.mesh, self.facet_tags, self.mixed = mesh, facet_tags, mixed
        self.pressure = None
        if mixed:
            self.system_space = mixed_space(mesh, degree, "DPC", 1)
            self.solution = dolfinx.fem.Function(self.system_space)
            self.V, self._velocity_dofs = collapse_vector(self.system_space.sub(0), mesh, degree)
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

    def start_from_velocity(self) -> None:
        """(mixed) The solution's velocity part set from u and its pressure part from pressure: a
        start from a given velocity (a restart, a free surface's next shape), which Newton's
        steps increment (docs/free_surface.md, step 7)."""
        if self.mixed:
            self.solution.x.array[self._velocity_dofs] = self.u.x.array
            self.solution.x.array[self._pressure_dofs] = self.pressure.x.array

    @property
    def collapsed(self) -> list[tuple[dolfinx.fem.FunctionSpace, np.ndarray]] | None:
        """(mixed) The velocity and pressure spaces, each with its dofs' indices in the system
        space (None for the penalty formulation)."""
        if not self.mixed:
            return None
        return [(self.V, self._velocity_dofs),
                (self.pressure.function_space, self._pressure_dofs)]

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

"""The error indicator that adapted meshes equidistribute (mesh/adapted.py): a recovered
strain-rate estimate of each cell in the energy norm of the flow (Zienkiewicz and Zhu's, as
Zienkiewicz, Liu and Huang used it for the flow formulation of forming, 1988).

    eta_K^2 = int_K G(u_h) |e* - e(u_h)|^2 dOmega,

with e(u_h) the strain-rate tensor (2.3) of the finite-element velocity, e* its recovery, the
nodal average onto the velocity's continuous space (projection.LumpedProjector), and
G = sigma_p/rate the secant coefficient of the law at u_h, so that eta^2 has the units of the
plastic power (dOmega with the axisymmetric weight 2 pi y).
"""
from __future__ import annotations

from typing import TYPE_CHECKING

import dolfinx.fem
import dolfinx.fem.petsc
import numpy as np
import ufl

from forming_fenicsx.core.compat import cell_geometry_nodes, function_space, original_cell_index
from forming_fenicsx.fem.projection import LumpedProjector

if TYPE_CHECKING:
    from forming_fenicsx.fem.forms import FlowProblem

RULE_ABOVE = 2  # the rule's degree over twice the element's


def strain_rate_indicator(problem: FlowProblem
                          ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """eta_K^2 (module docstring), the cell areas, their corners (cells, 4, 2) in order around each
    cell and their indices in the cell list the mesh was made from, for the owned cells of a 2D
    mesh (collective)."""
    mesh = problem.mesh
    owned = mesh.topology.index_map(mesh.topology.dim).size_local
    degree = problem.scene.discretisation.degree
    e = problem.strain_rate(problem.u)
    n = e.ufl_shape[0]
    components = ufl.as_vector([e[i, j] for i in range(n) for j in range(n)])
    recovered = dolfinx.fem.Function(function_space(mesh, "P", degree, (n * n,)))
    rule = 2 * degree + RULE_ABOVE
    LumpedProjector(components, recovered, rule).project()
    rate = problem.equivalent_strain_rate(problem.u)
    secant = problem.scene.material.secant_ufl(rate, problem.strain, problem.temperature)
    cell = ufl.TestFunction(function_space(mesh, "DP", 0))
    dx = problem.coordinates.measure(ufl.dx(domain=mesh, metadata={"quadrature_degree": rule}))
    error = recovered - components
    indicator = dolfinx.fem.petsc.assemble_vector(dolfinx.fem.form(
        secant * ufl.inner(error, error) * cell * dx)).array[:owned].copy()
    area = dolfinx.fem.petsc.assemble_vector(dolfinx.fem.form(
        cell * ufl.dx(domain=mesh))).array[:owned].copy()
    corners = mesh.geometry.x[cell_geometry_nodes(mesh)[:owned][:, [0, 1, 3, 2]]][:, :, :2]
    return indicator, area, corners, original_cell_index(mesh)[:owned]

"""The fields a run writes (fields.xdmf) and draws: nodal functions on Lagrange elements of the
geometry degree, the form XDMF, ParaView and the flow lines read."""
from __future__ import annotations

import dolfinx.fem
import numpy as np
from mpi4py import MPI

from forming_fenicsx.core.compat import function_space, geometry_degree
from forming_fenicsx.fem.forms import FlowProblem
from forming_fenicsx.fem.projection import LumpedProjector

NON_NEGATIVE_FIELDS = ("equivalent_strain_rate", "secant_viscosity", "equivalent_strain",
                       "flow_stress")
# the floor of a non-negative field relative to its largest value: far above the rounding (1e-15
# relative) with which dolfinx's XDMF writer evaluates the nodal function at the nodes, so the file
# holds no negative value, and far below anything a figure or ParaView shows
FLOOR = 1e-12


def nodal_velocity(problem: FlowProblem) -> dolfinx.fem.Function:
    """The velocity on Lagrange elements of the geometry degree (interpolated when the element
    differs): the form XDMF, ParaView and the flow lines read."""
    degree = geometry_degree(problem.mesh)
    if problem.scene.discretisation.degree == degree:
        return problem.u
    space = function_space(problem.mesh, "P", degree, (problem.mesh.geometry.dim,))
    velocity = dolfinx.fem.Function(space, name="velocity")
    velocity.interpolate(problem.u)
    return velocity


def output_fields(problem: FlowProblem) -> list[dolfinx.fem.Function]:
    """Velocity, equivalent strain rate, hydrostatic pressure and secant viscosity at the mesh
    nodes (and, with a hardening law, the equivalent strain and the flow stress; with [thermal],
    the temperature as solved).

    Scalars are nodal means (lumped projections) on Lagrange elements of the geometry degree, the
    form XDMF and ParaView read. Q2's basis functions change sign, so the nodal mean
    (f, phi_i)/(1, phi_i) of a non-negative f can be negative where f varies steeply: the
    non-negative fields (NON_NEGATIVE_FIELDS) are clipped, max(value, FLOOR max|value|), node by
    node (the projection is not positivity-preserving; the clip is), the floor above the writer's
    rounding (docs/outputs.md).
    """
    space = function_space(problem.mesh, "P", geometry_degree(problem.mesh))
    sources = {
        "equivalent_strain_rate": (problem.equivalent_strain_rate(problem.u), problem.full_degree),
        "hydrostatic_pressure": (problem.hydrostatic_stress(), problem.volumetric_degree),
        "secant_viscosity": (problem.secant_coefficient(), problem.full_degree),
    }
    if problem.strain is not None:  # a hardening law: its strain and flow stress
        sources["equivalent_strain"] = (problem.strain, problem.full_degree)
        sources["flow_stress"] = (problem.flow_stress(problem.u), problem.full_degree)
    fields = [nodal_velocity(problem)]
    if problem.field("temperature") is not None:  # [thermal]: the temperature, as solved
        fields.append(problem.field("temperature").T)
    for name, (expr, quadrature) in sources.items():
        target = LumpedProjector(expr, dolfinx.fem.Function(space, name=name), quadrature).project()
        if name in NON_NEGATIVE_FIELDS:
            largest = problem.comm.allreduce(np.abs(target.x.array).max(initial=0.0), op=MPI.MAX)
            np.maximum(target.x.array, FLOOR * largest, out=target.x.array)
        fields.append(target)
    return fields

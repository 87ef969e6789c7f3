"""A scene's temperature field (its [thermal] section): the container wall told apart from the
die, the exchanges with the die, the container and the air, the friction heat, and the heat
sources of the flow (coupled/thermal.py's TemperatureField)."""
from __future__ import annotations

import dolfinx.fem
import dolfinx.mesh
import numpy as np
import ufl
from mpi4py import MPI

from forming_fenicsx.core.roles import ROLES
from forming_fenicsx.coupled.thermal import (FieldExpression, FrictionHeat, HeatExchange,
                                             TemperatureField, ThermalMaterial)
from forming_fenicsx.physics.friction import tangential

CONTAINER = max(ROLES.values()) + 1  # the facet tag of the container wall, split from gamma3


def container_tags(problem):
    """The problem's facet tags with the contact facets ahead of the die (the container wall of a
    built-in extrusion geometry: x < die_entry or die_position) tagged CONTAINER; unchanged for
    drawing and a mesh file (one Gamma3)."""
    geometry, tags = problem.scene.geometry, problem.facet_tags
    start = getattr(geometry, "die_entry", None) or getattr(geometry, "die_position", None)
    if problem.scene.process.kind != "extrusion" or geometry.mesh_file is not None or start is None:
        return tags
    midpoints = dolfinx.mesh.compute_midpoints(problem.mesh, problem.mesh.topology.dim - 1,
                                               tags.indices)
    values = tags.values.copy()
    ahead = midpoints[:, 0] < start * (1 - 1e-9)
    values[(values == ROLES["gamma3_contact"]) & ahead] = CONTAINER
    return dolfinx.mesh.meshtags(problem.mesh, problem.mesh.topology.dim - 1, tags.indices, values)


def scene_temperature_field(problem, plastic_power: FieldExpression | None = None,
                            friction_power: FieldExpression | None = None,
                            options: dict | None = None,
                            temperature: dolfinx.fem.Function | None = None) -> TemperatureField:
    """The TemperatureField of a flow problem whose scene has [thermal] (scene.Thermal): the die
    (Gamma3) and container exchanges, the air on the free surfaces (Gamma2, Gamma4) when air_h > 0,
    friction heat on the contact when the flow has friction, Q_k of the flow's degree.
    ``plastic_power`` defaults to the flow law's sigma(rate(v)) rate(v) (the isothermal law: a
    temperature-dependent law passes its own), ``friction_power`` to the regularised friction's
    power at v itself, tau_f |v_T|^2 / sqrt(|v_T|^2 + d_T^2) or sticking's c_T |v_T|^2
    (friction.py; not with the flow's slip coefficient, which Newton's steps do not update:
    docs/thermal.md). ``temperature``: the flow's own T Function when its law reads it (the field
    then solves into it)."""
    thermal, problem_roles = problem.scene.thermal, problem.roles
    tags = container_tags(problem)
    contact = [ROLES["gamma3_contact"]] if "gamma3_contact" in problem_roles else []
    has_container = problem.comm.allreduce(int(np.any(tags.values == CONTAINER)), op=MPI.MAX)
    container = [CONTAINER] if has_container else []
    free = tuple(ROLES[role] for role in ("gamma2_free", "gamma4_free") if role in problem_roles)
    exchanges = [HeatExchange("die", tuple(contact), thermal.die_h, thermal.die_temperature),
                 HeatExchange("container", tuple(container), thermal.container_h,
                              thermal.container_temperature)]
    if thermal.air_h > 0:
        exchanges.append(HeatExchange("air", free, thermal.air_h, thermal.air_temperature))

    def flow_power(v, T):
        return problem.flow_stress(v) * problem.equivalent_strain_rate(v)

    def slip_power(v, T):  # c(v) |s|^2 at v itself: tau_f/sqrt(|s|^2 + d_T^2), or sticking's
        # constant k0/d_T (FlowProblem.friction_coefficient)
        slip = problem.slip(v)
        tangent = tangential(slip, problem.n)
        return problem.friction_coefficient(v) * ufl.dot(tangent, tangent)
    friction = None
    if problem.has_friction:
        friction = FrictionHeat(friction_power or slip_power, tuple(contact + container),
                                thermal.friction_share)
    material = ThermalMaterial(thermal.heat_capacity, thermal.conductivity, thermal.heat_fraction)
    return TemperatureField(problem.u, problem.coordinates, tags, material,
                            thermal.inflow_temperature, problem.scene.discretisation.degree,
                            plastic_power=plastic_power or flow_power,
                            exchanges=tuple(e for e in exchanges if e.tags), friction=friction,
                            options=options, temperature=temperature)

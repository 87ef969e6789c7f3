"""Forces, pressures and fields of a converged (or last) iterate.

Global forces are consistent reactions (the residual of (3.12) at the Gamma1 dofs) and boundary
integrals of the penalty and friction tractions; pressures are element or nodal means of the
penalty pressure sigma_H = div(u)/d of (3.4).
"""
from __future__ import annotations

import dolfinx.fem
import dolfinx.fem.petsc
import numpy as np
import ufl
from petsc4py import PETSc

from . import contact, friction
from .compat import function_space, geometry_degree
from .forms import FlowProblem
from .geometry import ROLES
from .kinematics import equivalent_strain_rate
from .projection import LumpedProjector


def _integrate(problem: FlowProblem, integrand) -> float:
    local = dolfinx.fem.assemble_scalar(dolfinx.fem.form(integrand))
    return problem.comm.allreduce(local)


def hydrostatic_pressure(problem: FlowProblem):
    """sigma_H = div(u)/d of (3.4), as UFL."""
    return ufl.div(problem.u) / problem.scene.penalty.d


def reaction(problem: FlowProblem, role: str = "gamma1_velocity") -> float:
    """Force the constraint on ``role`` exerts on the workpiece along its component: the residual summed
    over the constrained dofs."""
    residual = dolfinx.fem.petsc.assemble_vector(problem.residual)
    residual.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
    component = next(c.component for c in problem.constraints if c.role == role)
    dofs = problem.boundary_dofs(role, component)
    owned = problem.V.dofmap.index_map.size_local * problem.V.dofmap.index_map_bs
    value = residual.getArray(readonly=True)[dofs[dofs < owned]].sum()
    residual.destroy()
    return problem.comm.allreduce(value)


def die_forces_x(problem: FlowProblem) -> tuple[float, float]:
    """x-forces the workpiece exerts on the die: normal (contact penalty) and friction parts."""
    if not problem.has_contact:
        return 0.0, 0.0
    n, ds = problem.n, problem.ds_contact
    pressure = contact.contact_pressure(problem.u, n, problem.scene.penalty.d_N)
    normal = _integrate(problem, pressure * n[0] * ds)
    if not problem.has_friction:
        return normal, 0.0
    traction = friction.friction_traction(problem.friction_coefficient(), problem.u, n)
    return normal, _integrate(problem, -traction[0] * ds)


def applied_force_x(problem: FlowProblem) -> float:
    """x-force of F_N on Gamma5 (2.7) acting on the workpiece."""
    if not problem.has_force:
        return 0.0
    return problem.scene.process.applied_force * _integrate(problem, problem.n[0] * problem.ds(ROLES["gamma5_force"]))


def cell_means(problem: FlowProblem, expr, name: str, degree: int) -> dolfinx.fem.Function:
    """Element means of an expression (a DG0 function)."""
    target = dolfinx.fem.Function(function_space(problem.mesh, "DP", 0), name=name)
    return LumpedProjector(expr, target, degree).project()


def mean_hydrostatic_pressure(problem: FlowProblem) -> float:
    """The paper's p_av: -sigma_H averaged over the ram face Gamma1, sigma_H taken as element means.

    The elements along Gamma1 lie in the rigid zone at the ram, where sigma_H is close to the
    ram pressure; the mean uses the volumetric term's own quadrature.
    """
    pressure = cell_means(problem, -hydrostatic_pressure(problem), "pressure", problem.volumetric_degree)
    ds = problem.ds(ROLES["gamma1_velocity"])
    return _integrate(problem, pressure * ds) / _integrate(problem, 1.0 * ds)


def scalars(problem: FlowProblem) -> dict[str, float]:
    """The summary numbers of a run (ram pressure, p_av, die force and the x force balance)."""
    height = _integrate(problem, 1.0 * problem.ds(ROLES["gamma1_velocity"]))
    ram = reaction(problem)
    die_normal, die_friction = die_forces_x(problem)
    die = die_normal + die_friction
    external = applied_force_x(problem)
    div_u = np.sqrt(_integrate(problem, ufl.div(problem.u) ** 2 * problem.dx_vol))
    return {
        "ram_force": ram,
        "ram_pressure": ram / height,
        "mean_hydrostatic_pressure": mean_hydrostatic_pressure(problem),
        "die_force_x": die,
        "die_normal_force_x": die_normal,
        "die_friction_force_x": die_friction,
        "applied_force_x": external,
        "force_balance_residual": abs(ram + external - die) / max(abs(ram), abs(die), 1e-300),
        "divergence_l2": div_u,
    }


def output_fields(problem: FlowProblem) -> list[dolfinx.fem.Function]:
    """Velocity, equivalent strain rate, hydrostatic pressure and secant viscosity at the mesh nodes.

    Scalars are nodal means (lumped projections) on Lagrange elements of the geometry degree, the
    form XDMF and ParaView read.
    """
    degree = geometry_degree(problem.mesh)
    space = function_space(problem.mesh, "P", degree)
    velocity = problem.u
    if problem.scene.discretisation.degree != degree:
        velocity = dolfinx.fem.Function(function_space(problem.mesh, "P", degree, (2,)), name="velocity")
        velocity.interpolate(problem.u)
    sources = {
        "equivalent_strain_rate": (equivalent_strain_rate(problem.u), problem.full_degree),
        "hydrostatic_pressure": (hydrostatic_pressure(problem), problem.volumetric_degree),
        "secant_viscosity": (problem.secant, problem.full_degree),
    }
    fields = [velocity]
    for name, (expr, quadrature) in sources.items():
        target = dolfinx.fem.Function(space, name=name)
        fields.append(LumpedProjector(expr, target, quadrature).project())
    return fields


def ram_face_pressure_model(law, d: float, ram_pressure: float) -> float:
    """p_av on Gamma1 predicted from the ram pressure, for the zone at the ram that the penalty compresses.

    Beside the ram the container holds u_y ~ 0, so the penalty's volumetric rate e = d sigma_H is a
    uniaxial-strain compression of equivalent rate 2/3 |e| and s_xx = 4/9 G e. Below rate1 of (4.5)
    G = sigma_p(rate1)/rate1 and p_ram = p_av (1 + 4/9 G d); above it the zone yields and
    p_ram = p_av + 2/3 sigma_p(2/3 d p_av). As d -> 0, p_av -> p_ram.
    """
    stiff = law.secant(np.array([law.rate1]))[0]
    p_av = ram_pressure / (1 + 4 / 9 * stiff * d)
    if 2 / 3 * d * p_av < law.rate1:
        return p_av
    p_av = ram_pressure
    for _ in range(50):  # fixed point; sigma_p barely depends on the rate here
        p_av = ram_pressure - 2 / 3 * law.flow_stress(np.array([2 / 3 * d * p_av]))[0]
    return p_av

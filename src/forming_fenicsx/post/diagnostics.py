"""How far a run can be trusted, measured on its flow: the volume change the penalty leaves
(Theorem 3.1), the flow into the die and across the free surfaces that the fixed-domain model
(2.6) lets through, a product that still deforms after the die, the work done outside the
law's rate window, and a hardening law's strain beyond what the pass can give. The sanity checks
(sanity.py) grade these numbers of the summary."""
from __future__ import annotations

import math

import dolfinx.fem
import dolfinx.fem.petsc
import numpy as np
import ufl
from mpi4py import MPI
from petsc4py import PETSc

from forming_fenicsx.core.roles import ROLES
from forming_fenicsx.fem.forms import FlowProblem
from forming_fenicsx.physics import contact
from forming_fenicsx.post.flux import throughput
from forming_fenicsx.post.integrals import integrate


def divergence_l2(problem: FlowProblem) -> float:
    """||div u||, the L2 norm over the workpiece with the volumetric term's quadrature."""
    return float(np.sqrt(integrate(problem, problem.divergence(problem.u) ** 2 * problem.dx_vol)))


def volume_change(problem: FlowProblem) -> float:
    """int div u dx / Q, Q the throughput: the volume the flow gains between its way in and its way
    out (the net flux through the whole boundary, by the divergence theorem) per unit throughput.
    The penalty (3.5) makes it d int sigma_H dx / Q, O(d) (Theorem 3.1); the mixed formulation's
    piecewise-linear pressure holds each cell's int div u at zero up to the solve."""
    through = throughput(problem)
    gained = integrate(problem, problem.divergence(problem.u) * problem.dx)
    return gained / through if through else math.nan


def relative_divergence(problem: FlowProblem, divergence: float) -> float:
    """||div u|| / ||e(u)|| (L2 norms over the strip), given ||div u||: the volume change the
    penalty 1/d leaves, per unit of deformation rate; Theorem 3.1 drives it to zero like O(d)."""
    e = problem.strain_rate(problem.u)
    deformation = integrate(problem, ufl.inner(e, e) * problem.dx)
    if deformation == 0:  # no deformation at all (e.g. a first solve that failed)
        return math.nan
    return float(divergence / np.sqrt(deformation))


def discrete_divergence(problem: FlowProblem) -> float:
    """|(q, div u)| over the pressure basis functions q (Euclidean norm): the incompressibility the
    mixed formulation imposes exactly (zero up to the linear solve), while ||div u|| itself is not
    zero."""
    q = ufl.TestFunction(problem.pressure.function_space)
    vector = dolfinx.fem.petsc.assemble_vector(
        dolfinx.fem.form(q * problem.divergence(problem.u) * problem.dx))
    vector.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
    value = vector.norm()
    vector.destroy()
    return value


CROSSED_SURFACES = {"stock": "gamma2_free", "product": "gamma4_free"}


def free_surface_crossings(problem: FlowProblem) -> dict[str, float]:
    """Volume crossing each free surface, in or out, relative to the flux through Gamma1: the
    stock's (Gamma2, upstream) and the product's (Gamma4), facets whose normal is mostly across
    the flow (its y (and z) part over 0.5); zero for a steady state whose free surfaces are
    streamlines, so they measure what the fixed-domain model (2.6) lets cross them."""
    n = problem.n
    across = abs(n[1]) if problem.mesh.geometry.dim == 2 else ufl.sqrt(n[1] ** 2 + n[2] ** 2)
    surface = ufl.conditional(ufl.gt(across, 0.5), 1.0, 0.0)
    through = throughput(problem)
    crossed = {}
    for name, role in CROSSED_SURFACES.items():
        out = (integrate(problem, abs(ufl.dot(problem.u, n)) * surface * problem.ds(ROLES[role]))
               if role in problem.roles else 0.0)
        crossed[name] = out / through if through else math.nan
    return crossed


def die_penetration(problem: FlowProblem) -> float:
    """Volume flowing into the die (u_N > 0 on Gamma3) over the throughput: the penalty (3.4) lets
    the workpiece into the die at u_N = d_N sigma_N, which must stay a small fraction of the
    flow."""
    if not problem.has_contact:
        return 0.0
    inflow = integrate(problem, ufl.max_value(contact.normal_velocity(problem.u, problem.n), 0.0)
                       * problem.ds_contact)
    through = throughput(problem)
    return inflow / through if through else math.nan


def exit_zone_rate_ratio(problem: FlowProblem) -> float:
    """Mean equivalent strain rate over the last exit thickness of the workpiece (x within one full
    exit thickness of its downstream end) over its mean over the whole workpiece: near zero when
    the product leaves the die rigid, of order one when it yields after the die."""
    x = ufl.SpatialCoordinate(problem.mesh)[0]
    end = problem.comm.allreduce(problem.mesh.geometry.x[:, 0].max(), op=MPI.MAX)
    zone = ufl.conditional(ufl.gt(x, end - problem.scene.geometry.exit_thickness), 1.0, 0.0)
    rate = problem.equivalent_strain_rate(problem.u)
    mean = integrate(problem, rate * problem.dx) / integrate(problem, 1.0 * problem.dx)
    zone_mean = integrate(problem, rate * zone * problem.dx) / integrate(problem, zone * problem.dx)
    return zone_mean / mean if mean > 0 else math.nan


def strain_extremes(problem: FlowProblem) -> dict[str, float | list[float]]:
    """A hardening law's transported strain at its nodes: its largest value and where it lies,
    and its smallest. Strain only grows along a streamline, from the entry strain to about the
    ideal ln(A0/A1) above it (times the redundant work); far more marks material that barely moves
    and keeps straining, below the entry strain the transport's undershoot (docs/hardening.md).
    Collective."""
    if problem.strain is None:
        return {}
    eps = problem.strain
    owned = eps.function_space.dofmap.index_map.size_local
    values = eps.x.array[:owned]
    where = eps.function_space.tabulate_dof_coordinates()[:owned, :problem.mesh.geometry.dim]
    top = int(np.argmax(values)) if owned else -1
    local = (float(values[top]), where[top].tolist()) if owned else (-math.inf, [])
    largest, at = max(problem.comm.allgather(local), key=lambda item: item[0])
    smallest = problem.comm.allreduce(float(values.min(initial=math.inf)), op=MPI.MIN)
    return {"max_strain": largest, "max_strain_at": at, "min_strain": smallest}


def dissipation_outside_window(problem: FlowProblem) -> dict[str, float]:
    """The fractions of the plastic work rate int sigma_p rate dissipated where the law is linear
    (viscous) instead of nearly rate-independent: below rate1 and above rate2 for the law (4.5),
    below the rate floor for the others."""
    law = problem.scene.material
    rate = problem.equivalent_strain_rate(problem.u)
    power = problem.flow_stress(problem.u) * rate
    total = integrate(problem, power * problem.dx)
    if total <= 0:
        return {}
    tests = (("above_rate2", ufl.gt(rate, law.rate2)), ("below_rate1", ufl.lt(rate, law.rate1))) \
        if hasattr(law, "rate2") else (("below_rate_floor", ufl.lt(rate, law.rate_floor)),)
    return {f"dissipation_{name}": integrate(problem, ufl.conditional(test, power, 0.0)
                                             * problem.dx) / total for name, test in tests}

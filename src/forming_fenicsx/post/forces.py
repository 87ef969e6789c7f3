"""Forces on the workpiece: consistent reactions (the residual of (3.12) at the dofs of a
prescribed velocity), the die's penalty (3.4) and friction tractions integrated over Gamma3, the
applied force F_N on Gamma5 (2.7), the x force balance between them, and the model's forces made
the whole product's."""
from __future__ import annotations

from typing import Any

import ufl
from mpi4py import MPI

from forming_fenicsx.core.roles import ROLES
from forming_fenicsx.fem.forms import FlowProblem
from forming_fenicsx.post.die_nodes import PRESSED, on_die_nodes
from forming_fenicsx.post.integrals import integrate


def reaction(problem: FlowProblem, role: str = "gamma1_velocity") -> float:
    """Force the constraint on ``role`` exerts on the workpiece along its component (0 without
    one: rolling's entry face, whose speed is free)."""
    component = next((c.component for c in problem.constraints if c.role == role), None)
    return 0.0 if component is None else reaction_on(problem, role, component)


def reaction_on(problem: FlowProblem, role: str, component: int) -> float:
    """Force along x (0) or y (1) that the velocity prescribed on ``role`` exerts on the
    workpiece: the residual summed over that component's dofs there (the whole body's when
    axisymmetric)."""
    residual = problem.residual.vector()
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
    normal = integrate(problem, problem.contact_pressure(problem.u) * n[0] * ds)
    if not problem.has_friction:
        return normal, 0.0
    return normal, integrate(problem, -problem.friction_traction()[0] * ds)


def unpressed_friction_x(problem: FlowProblem) -> float:
    """x-force of the friction factor's m k on the die where the workpiece does not press on it
    (its contact pressure is zero): the fixed domain holds the workpiece on Gamma3 where it would
    leave it (a land or bearing), and the factor law, unlike Coulomb's mu p, does not vanish with
    the pressure. 0 for Coulomb friction and without friction."""
    if not pressure_free_friction(problem):
        return 0.0
    return integrate(problem, -problem.friction_traction()[0] * unpressed(problem)
                     * problem.ds_contact)


def pressure_free_friction(problem: FlowProblem) -> bool:
    """Whether the die (or roll) has friction that does not vanish with the contact pressure: the
    friction factor's m k, or sticking's penalised slip."""
    return problem.has_contact and problem.has_friction \
        and problem.scene.friction.law in ("factor", "sticking")


def unpressed(problem: FlowProblem) -> ufl.core.expr.Expr:
    """1 where the contact pressure on Gamma3 at its nodes (P1, its lumped projection over Gamma3,
    as die.csv's) is zero, not above PRESSED of its largest as contact_end_x reads it (the
    workpiece does not press on the die), else 0. Not the pressure at the quadrature points:
    along a pressed die it can oscillate through zero from point to point (a copper rod through a
    cosine CSV die, mean pressure 540 MPa: 15 % of Gamma3's points, a false 8 % share;
    docs/sanity.md)."""
    pressure = on_die_nodes(problem, problem.contact_pressure(problem.u))
    largest = problem.comm.allreduce(float(pressure.x.array.max(initial=0.0)), op=MPI.MAX)
    return ufl.conditional(ufl.le(pressure, PRESSED * largest), 1.0, 0.0)


def die_separation_force(problem: FlowProblem, component: int = 1) -> float:
    """The force that pushes the die apart: the y-traction of the workpiece on the die (contact
    pressure p n_y plus the friction stress's y part) integrated over Gamma3 with the coordinate
    system's separation weight: per unit width on one die half in plane strain; for a round die,
    the force across a diametral plane, 2 int y t_y ds; on a 3D die's half y > 0 (component 2:
    the z-traction, on its half z > 0: the force on the side dies)."""
    if not problem.has_contact:
        return 0.0
    n, c = problem.n, problem.coordinates
    traction = problem.contact_pressure(problem.u) * n[component]
    if problem.has_friction:
        traction -= problem.friction_traction()[component]
    plain = problem.ds.measure(ROLES["gamma3_contact"])
    return integrate(problem, traction * c.separation_weight * plain)


def applied_force_x(problem: FlowProblem) -> float:
    """x-force of F_N on Gamma5 (2.7) acting on the workpiece (rolling's tensions: f(e_x))."""
    if not problem.has_force:
        return 0.0
    if problem.rolling:
        return integrate(problem, problem.load(ufl.as_vector((1.0, 0.0))))
    return problem.scene.process.applied_force * integrate(
        problem, problem.n[0] * problem.ds(ROLES["gamma5_force"]))


def force_balance(problem: FlowProblem) -> tuple[float, float, float, float, float]:
    """(relative residual, Gamma1 force, die normal x-force, die friction x-force, applied x-force)
    of the x force balance Gamma1 force + applied force = die force (verification.md), at the
    current state, relative to the largest of the forces (in rolling the rolls' normal and
    friction x-forces nearly cancel)."""
    force = reaction(problem)
    die_normal, die_friction = die_forces_x(problem)
    external = applied_force_x(problem)
    die = die_normal + die_friction
    scale = max(abs(force), abs(die), abs(die_normal), abs(die_friction), 1e-300)
    return (abs(force + external - die) / scale, force, die_normal, die_friction, external)


# forces on the whole product (the model's times CoordinateSystem.whole and the strip's width)
PRODUCT_FORCES = ("ram_force", "drawing_force", "die_force_x", "die_normal_force_x",
                  "die_friction_force_x", "unpressed_friction_force_x", "applied_force_x",
                  "roll_power")
# forces and torques on each die half or roll, which the half model holds whole
EACH_TOOL = ("die_separation_force", "die_side_force", "roll_force", "roll_torque",
             "unpressed_friction_torque")
# the energy balance's ratios; its other terms are powers, scaled as the forces
BALANCE_RATIOS = ("residual", "global_residual")


def whole_product(problem: FlowProblem, numbers: dict[str, Any]) -> dict[str, Any]:
    """The model's forces and powers made the whole product's: times 2 for the plane-strain half
    model (per unit width), and times geometry.width when the scene gives it (then in force
    units). The die separation force acts on each die half, which the half model holds whole: it
    takes the width only."""
    width = problem.scene.geometry.width or 1.0
    factor = problem.coordinates.whole * width
    scaled = {key: value * factor if key in PRODUCT_FORCES else value
              for key, value in numbers.items()}
    for key in EACH_TOOL:
        if key in scaled:
            scaled[key] *= width
    for balance in ("energy_balance", "power_balance"):
        if balance in scaled:
            scaled[balance] = {key: value if key in BALANCE_RATIOS else value * factor
                               for key, value in scaled[balance].items()}
    return scaled

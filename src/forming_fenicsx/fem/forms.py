"""The penalty variational problem (3.5)-(3.12) for one scene: its parts and the forms.

b(w; u, v) = int 2/3 G(w) e'(u):e'(v) dx + int (1/d) div u div v dx + int_G3 (1/d_N) u_N^+ v_N ds,
plus the regularised friction <j'_dT(w, u), v> on Gamma3 when there is friction and
f(v) = int_G5 F_N v_N when the scene has Gamma5. Only the terms the scene needs are built. The
kinematics and the measures' weight come from the scene's coordinate system (coordinates.py).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import dolfinx.fem
import dolfinx.fem.petsc
import ufl
from petsc4py import PETSc

from forming_fenicsx.physics import contact, friction, roll, rolling_slab
from forming_fenicsx.fem.boundary_filter import BoundaryFilter
from forming_fenicsx.core.compat import function_space
from forming_fenicsx.physics.coordinates import CoordinateSystem
from forming_fenicsx.fem.contact_multiplier import ContactMultiplier
from forming_fenicsx.fem.entry_speed import EntrySpeed
from forming_fenicsx.fem.fields import FlowFields
from forming_fenicsx.fem.frozen import FrozenCoefficient, FrozenVelocity
from forming_fenicsx.mesh.geometry import FormingMesh
from forming_fenicsx.mesh.transfer import same_layout, transfer
from forming_fenicsx.fem.measures import Measures
from forming_fenicsx.core.roles import ROLES
from forming_fenicsx.config.scene import Scene
from forming_fenicsx.fem.secant_state import SecantState


@dataclass
class SplitForm:
    """A scalar or linear form (``ufl``) compiled as the parts whose sum it is (see
    ``split_form``)."""

    ufl: ufl.Form
    parts: list[dolfinx.fem.Form]

    def value(self, comm) -> float:
        """The assembled scalar form, summed over the ranks."""
        return comm.allreduce(sum(dolfinx.fem.assemble_scalar(part) for part in self.parts))

    def add_to(self, b: PETSc.Vec) -> None:
        """Assemble the linear form into b, adding to what b holds (no ghost update)."""
        for part in self.parts:
            dolfinx.fem.petsc.assemble_vector(b, part)

    def vector(self) -> PETSc.Vec:
        """The assembled linear form in a new vector, ghost contributions added to their owners."""
        b = dolfinx.fem.petsc.create_vector(self.parts[0])
        with b.localForm() as local:
            local.set(0.0)
        self.add_to(b)
        b.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        return b


def split_form(form: ufl.Form, apart_degree: int | None) -> SplitForm:
    """The form compiled as one, or with its integrals of quadrature degree ``apart_degree``
    compiled apart from the others.

    FFCx (the 0.5 of Debian 12 and the 0.9 of Debian 13) miscomputes a scalar or linear form that
    integrates a coefficient's derivatives with a one-point rule beside another rule: the form
    sum(tau(u):e(v) dx + (1/d) div u div v dx_1) differs from its two terms assembled apart by 2 to
    5 % of their size (tests/test_forms.py). This is the reduced penalty term of Q1. Such a form is
    compiled in parts, whose assembled values add up to the form's."""
    if apart_degree is None:
        return SplitForm(form, [dolfinx.fem.form(form)])
    apart = [i for i in form.integrals() if i.metadata().get("quadrature_degree") == apart_degree]
    rest = [i for i in form.integrals() if i.metadata().get("quadrature_degree") != apart_degree]
    return SplitForm(form, [dolfinx.fem.form(ufl.Form(group)) for group in (rest, apart) if group])


class FlowProblem:
    """One scene's flow problem, made of its parts: the coordinate system, the fields and boundary
    conditions (fields.py), the measures (measures.py), the secant state u_n (secant_state.py), the
    contact multiplier (contact.py) and the frozen coefficients (frozen.py: the friction bound, from
    ``friction_state``, u_{0,m} in (3.33) and u_n in (3.13)); it builds the forms of
    (3.5)-(3.12)."""

    def __init__(self, scene: Scene, forming_mesh: FormingMesh):
        self.scene = scene
        self.mesh = mesh = forming_mesh.mesh
        self.roles = forming_mesh.roles
        self.facet_tags = forming_mesh.facet_tags
        self.constraints = forming_mesh.constraints
        self.comm = mesh.comm
        disc = scene.discretisation
        planes = sum(role in self.roles for role in ("gamma6_symmetry", "gamma7_symmetry"))
        self.coordinates = CoordinateSystem(mesh, scene.geometry.symmetry, planes)
        self.mixed = disc.formulation == "mixed"
        self.fields = FlowFields(mesh, self.facet_tags, self.constraints, disc.degree, self.mixed)
        self.V, self.system_space = self.fields.V, self.fields.system_space
        self.u, self.solution, self.pressure = (self.fields.u, self.fields.solution,
                                                self.fields.pressure)
        self.bcs = self.fields.bcs
        reduced = disc.volumetric_integration == "reduced" and not self.mixed
        self.measures = Measures(mesh, self.facet_tags, self.coordinates, disc.degree, reduced)
        m = self.measures
        self.dx, self.dx_vol, self.ds, self.n = m.dx, m.dx_vol, m.ds, m.n
        self.full_degree, self.volumetric_degree = m.full_degree, m.volumetric_degree
        self._apart_degree = m.apart_degree
        self.frozen: list[FrozenCoefficient] = []
        self.followers: list[FrozenCoefficient] = []  # coupled one way (couple)
        # the coefficients a flow law reads besides the velocity: the equivalent strain of a
        # hardening law and (below) the temperature; the coupled fields that solve for them
        # (forming_fenicsx.coupled) join the frozen coefficients through couple()
        self.strain = None
        if scene.material.hardens:
            self.strain = dolfinx.fem.Function(function_space(mesh, "P", disc.degree),
                                               name="equivalent_strain")
        # the temperature a flow law reads (the [thermal] field, thermal.py, frozen with the
        # strain); none when the law does not read it or the scene has no [thermal]
        self.temperature = None
        if scene.material.heats and scene.thermal is not None:
            self.temperature = dolfinx.fem.Function(function_space(mesh, "P", disc.degree),
                                                    name="temperature")
            self.temperature.x.array[:] = scene.thermal.inflow_temperature
        self.state = SecantState(self.V, self.coordinates, scene.material, disc.averaging,
                                 self.full_degree, self.strain, self.temperature)
        self.u_state = self.state.u

        self.has_contact = "gamma3_contact" in self.roles
        law = scene.friction
        self.has_friction = self.has_contact and law.coefficient > 0
        # sticking (or the factor law's m = 1 solved as its limit, Friction.sticks): the slip
        # penalised at a fixed stiffness, no bound to freeze (friction.py)
        self.sticking = self.has_friction and bool(law.sticks)
        self._sticking_stiffness = dolfinx.fem.Constant(mesh, PETSc.ScalarType(
            friction.sticking_coefficient(scene.scales.flow_stress, law.d_T))) \
            if self.sticking else None
        self.rolling = scene.process.kind == "rolling"
        process = scene.process
        self.has_force = ("gamma5_force" in self.roles and process.applied_force is not None) or (
            self.rolling and (process.back_tension > 0 or process.front_tension > 0))
        # a start from another shape's flow (carry_from): its first iterate measures the
        # shape's change, not the distance to this shape's answer
        self.first_iterates = 1
        # the die's surface velocity w (rolling's roll, roll.py): friction opposes the slip u - w
        self.tool_velocity = None
        if self.rolling:
            g = scene.geometry
            self.tool_velocity = roll.surface_velocity(
                ufl.SpatialCoordinate(mesh), dolfinx.fem.Constant(mesh, PETSc.ScalarType(
                    g.roll_centre)), dolfinx.fem.Constant(mesh, PETSc.ScalarType(
                        process.velocity)), dolfinx.fem.Constant(mesh, PETSc.ScalarType(
                            g.roll_radius)))
        self.multiplier = None  # the augmented contact's lambda (contact.py), or none: pure penalty
        if self.has_contact and scene.penalty.augmented:
            self.multiplier = ContactMultiplier(self.u, self.n, scene.penalty.d_N,
                                                self.ds_contact, self.full_degree)
        # rolling's factor law on a rate-sensitive metal: Newton's step carries the derivative of
        # m k(rate) (newton.py), k read at the rate floor where the metal is rigid (yield_stress);
        # not in the mixed formulation, where a steel pass at m = 1 then diverged (docs/rolling.md)
        self.factor_bound_moves = (
            self.rolling and self.has_friction and law.law == "factor" and not self.sticking
            and not self.mixed and scene.rate_sensitive)
        # rolling's bound that can reach a rate-sensitive metal's shear strength k (the factor law
        # at m > 0.99, Coulomb's capped at k): there the slip regularisation d_T splits the slip
        # between the interface and the metal under it, nearly freely (docs/rolling.md)
        reaches = {"factor": law.m > 1.0 - friction.STRENGTH_MARGIN,
                   "coulomb": law.shear_limit, "sticking": False}[law.law]
        self.bound_reaches_strength = bool(
            self.rolling and self.has_friction and not self.sticking and reaches
            and scene.rate_sensitive)
        self.friction_state: FrozenVelocity | None = None
        self.normal_stress_average: BoundaryFilter | None = None
        if self.has_friction and not self.sticking:
            self.friction_state = FrozenVelocity("friction bound", self.V)
            self.frozen.append(self.friction_state)
            if law.law == "coulomb" and law.normal_stress == "averaged":
                self.normal_stress_average = BoundaryFilter(
                    self.friction_normal_stress(), mesh, self.facet_tags, ROLES["gamma3_contact"],
                    law.mollification_length, "averaged_normal_stress",
                    "normal_stress_filter")
                self.friction_state.derived.append(self.normal_stress_average)
        # rolling: the entry speed is the flow's, held for the first solves (two with Coulomb's
        # bound, which the first freeze takes from the viscous solve's pressure) at v_R (1 + S)
        # h1/h0, S Coulomb's slab forward slip: at S = 0 a thin strip's Newton steps were cut to
        # 0.1 to 0.4 for ten steps while it gained its 9 % forward slip. The factor law and
        # sticking start at S = 0: a copper pass at m = 1 took 24 solves instead of 19 from the
        # slab's S, and the grid's sticking rows gained nothing (docs/rolling.md)
        self.entry_speed: EntrySpeed | None = None
        if self.rolling:
            g = scene.geometry
            forward_slip = 0.0 if law.law != "coulomb" else rolling_slab.forward_slip_estimate(
                g.roll_radius, g.entry_thickness, g.exit_thickness,
                scene.reference_flow_stress / math.sqrt(3.0), law.mu, process.back_tension,
                process.front_tension)
            self.entry_speed = EntrySpeed(mesh, process.velocity * (1.0 + forward_slip)
                                          * g.exit_thickness / g.entry_thickness,
                                          1.0 / scene.penalty.d_N,
                                          self.ds(ROLES["gamma1_velocity"]),
                                          held_solves=2 if law.law == "coulomb" else 1)
            self.frozen.append(self.entry_speed)

        if self.mixed:
            (du, dp), (v, q) = (ufl.split(ufl.TrialFunction(self.system_space)),
                                ufl.split(ufl.TestFunction(self.system_space)))
            self.a_ufl = self._bilinear(du, v) - (dp * self.divergence(v)
                                                  + q * self.divergence(du)) * self.dx
        else:
            du, v = ufl.TrialFunction(self.V), ufl.TestFunction(self.V)
            self.a_ufl = self._bilinear(du, v)
        self.a = dolfinx.fem.form(self.a_ufl)
        load = self._linear(v)
        self.L = dolfinx.fem.form(load) if load is not None else None
        # the residual of the velocity equations at u (its values on constrained dofs are reactions)
        v = ufl.TestFunction(self.V)
        residual = ufl.action(self._bilinear(ufl.TrialFunction(self.V), v), self.u)
        if self.mixed:
            residual -= self.pressure * self.divergence(v) * self.dx
        load = self._linear(v)
        if load is not None:
            residual -= load
        self.residual = split_form(residual, self._apart_degree)

    def couple(self, field: FrozenCoefficient, two_way: bool = True) -> None:
        """A coupled field (forming_fenicsx.coupled: the strain, the temperature) joins the flow:
        two way, the frozen coefficients (the iterations freeze it with the velocity and converge
        once it settles); one way, the followers (fields of the converged flow, settled by the
        post-processing)."""
        (self.frozen if two_way else self.followers).append(field)

    def field(self, name: str) -> FrozenCoefficient | None:
        """The coupled field of that name (two way or one way), or None."""
        return next((f for f in self.frozen + self.followers if f.name == name), None)

    # -- kinematics of the scene's coordinate system --------------------------------------------
    def strain_rate(self, u):
        return self.coordinates.strain_rate(u)

    def divergence(self, u):
        return self.coordinates.divergence(u)

    def equivalent_strain_rate(self, u):
        return self.coordinates.equivalent_strain_rate(u)

    # -- terms of b(w; u, v) and f(v) ---------------------------------------------------------
    def secant_coefficient(self):
        """G(w) = sigma_p/rate of a(w; u, v) at the secant state."""
        return self.state.coefficient()

    def viscous_form(self, u, v):
        """a(w; u, v) of (3.2) with the secant coefficient G(w) = sigma_p/rate."""
        product = self.coordinates.deviatoric_product(self.strain_rate(u), self.strain_rate(v))
        return 2.0 / 3.0 * self.secant_coefficient() * product * self.dx

    def volumetric_form(self, u, v):
        """Penalty incompressibility (1/d) int div u div v of (3.5), complete or reduced Gauss."""
        return 1.0 / self.scene.penalty.d * self.divergence(u) * self.divergence(v) * self.dx_vol

    def hydrostatic_stress(self):
        """sigma_H: div(u)/d of the penalty (3.4), or minus the pressure of the mixed
        formulation."""
        return -self.pressure if self.mixed else self.divergence(self.u) / self.scene.penalty.d

    def stress(self):
        """Cauchy stress s + sigma_H I with s = 2/3 G e' (2.4) (with its hoop part when
        axisymmetric)."""
        c = self.coordinates
        deviator = 2.0 / 3.0 * self.secant_coefficient() * c.deviatoric(self.strain_rate(self.u))
        return deviator + self.hydrostatic_stress() * c.identity

    def flow_stress(self, u):
        """sigma_p(rate(u)) of the material law, a UFL expression."""
        return self._stress_at(self.equivalent_strain_rate(u))

    def yield_stress(self, u):
        """sigma_p at max(rate(u), rate floor): the flow stress, and in a rigid zone, where the
        law's linear part below the floor stands for rigidity, the yield stress it stays below
        (whose rate derivative is the law's, not the floor's 1/rate)."""
        return self._stress_at(ufl.max_value(self.equivalent_strain_rate(u),
                                             self.scene.material.rate_floor))

    def _stress_at(self, rate):
        """sigma_p = G(rate) rate at the strain and temperature the law reads."""
        return self.scene.material.secant_ufl(rate, self.strain, self.temperature) * rate

    def after_solve(self) -> None:
        """Velocity (and pressure) from the solution of a linear system."""
        self.fields.after_solve()

    @property
    def unknowns(self) -> int:
        """Global number of unknowns of the linear systems."""
        return self.fields.unknowns

    @property
    def ds_contact(self):
        return self.ds(ROLES["gamma3_contact"])

    def contact_pressure(self, u):
        """-sigma_N >= 0 on Gamma3 at the velocity u: (lambda + u_N/d_N)^+ (contact.py)."""
        return contact.contact_pressure(u, self.n, self.scene.penalty.d_N, self.multiplier_value)

    def contact_active(self, u):
        """The active set of the contact at the velocity u (an indicator)."""
        return contact.active_indicator(u, self.n, self.scene.penalty.d_N, self.multiplier_value)

    @property
    def multiplier_value(self):
        """lambda of the augmented contact (0 for the pure penalty)."""
        return self.multiplier.value if self.multiplier is not None else 0.0

    def friction_normal_stress(self):
        """The local normal pressure of the friction bound: the multiplier lambda of the augmented
        contact (the pressure it has converged to, updated with it), else u_N^+/d_N of (3.4) at the
        friction state. Rolling reads (lambda + u_N/d_N)^+ at the friction state, which tends to
        lambda as it converges: its strip is held along x by friction alone (entry_speed.py), from
        the first iterate on, before lambda is first updated."""
        if self.multiplier is not None and not self.rolling:
            return self.multiplier.value
        return self.contact_pressure(self.friction_state.state)

    def normal_pressure(self):
        """The sigma_N-bar >= 0 of Coulomb's tau_f: averaged (mollified) or local, frozen with the
        friction state."""
        if self.normal_stress_average is not None:
            return ufl.max_value(self.normal_stress_average.value, 0.0)
        return self.friction_normal_stress()

    def friction_bound(self):
        """tau_f at the friction state: Coulomb's mu sigma_N-bar, capped at k with
        friction.shear_limit, or the factor law's m k (friction.py)."""
        law, state = self.scene.friction, self.friction_state.state
        if law.law == "factor":
            k = self.yield_stress(state) if self.factor_bound_moves else self.flow_stress(state)
            return friction.factor_bound(law.m, k)
        bound = friction.coulomb_bound(law.mu, self.normal_pressure())
        if law.shear_limit:
            return friction.shear_limited(bound, self.flow_stress(state))
        return bound

    def friction_coefficient(self, velocity=None):
        """Slip coefficient tau_f/sqrt(|w_T|^2 + d_T^2) of the regularised friction at the slip w of
        ``velocity`` (default the secant state u_state); sticking's constant k0/d_T."""
        if self.sticking:
            return self._sticking_stiffness
        state = self.u_state if velocity is None else velocity
        return friction.slip_coefficient(self.friction_bound(), self.slip(state), self.n,
                                         self.scene.friction.d_T)

    def slip(self, u):
        """u - w: the velocity relative to the die's surface (u itself for a fixed die)."""
        return u if self.tool_velocity is None else u - self.tool_velocity

    def friction_traction(self):
        """The friction stress on the workpiece at u, -c_T (u - w)_T (it opposes the slip)."""
        return friction.friction_traction(self.friction_coefficient(), self.slip(self.u), self.n)

    def _bilinear(self, u, v):
        """b(w; u, v) of (3.5); the mixed formulation adds its pressure terms instead of the
        penalty."""
        form = self.viscous_form(u, v)
        if not self.mixed:
            form += self.volumetric_form(u, v)
        if self.has_contact:
            form += contact.contact_form(u, v, self.contact_active(self.u_state), self.n,
                                         self.scene.penalty.d_N, self.ds_contact)
        if self.has_friction:
            form += friction.friction_form(u, v, self.friction_coefficient(), self.n,
                                           self.ds_contact)
        if self.entry_speed is not None:
            form += self.entry_speed.form(u, v)
        return form

    def _linear(self, v):
        """The right-hand side of the secant systems: f(v) = int_G5 F_N v_N of (3.2), minus the
        augmented contact's int lambda v_N over the state's active set; a moving die's friction
        int c_T w_T . v_T and the entry speed's hold (rolling); None when there is none."""
        terms = [self.load(v)] if self.has_force else []
        if self.multiplier is not None:
            terms.append(-contact.multiplier_form(v, self.contact_active(self.u_state),
                                                  self.multiplier.value, self.n, self.ds_contact))
        if self.has_friction and self.tool_velocity is not None:
            terms.append(friction.friction_form(self.tool_velocity, v, self.friction_coefficient(),
                                                self.n, self.ds_contact))
        if self.entry_speed is not None:
            terms.append(self.entry_speed.load(v))
        return sum(terms[1:], terms[0]) if terms else None

    def load(self, v):
        """f(v) = int_G5 F_N v_N of (3.2); rolling's tensions: the back tension t_b on Gamma1 and
        the front tension t_f on Gamma5, int t_b v_N + int t_f v_N (the outward normals), on once
        the entry speed is released (entry_speed.py)."""
        process = self.scene.process
        if not self.rolling:
            F_N = dolfinx.fem.Constant(self.mesh, PETSc.ScalarType(process.applied_force))
            return F_N * ufl.dot(v, self.n) * self.ds(ROLES["gamma5_force"])
        ends = (("gamma1_velocity", process.back_tension), ("gamma5_force", process.front_tension))
        terms = [self.entry_speed.released * dolfinx.fem.Constant(
            self.mesh, PETSc.ScalarType(tension)) * ufl.dot(v, self.n) * self.ds(ROLES[role])
            for role, tension in ends if tension > 0]
        return sum(terms[1:], terms[0])

    # -- boundary data --------------------------------------------------------------------------
    def boundary_dofs(self, role: str, component: int, space=None):
        return self.fields.boundary_dofs(role, component, space)

    def role_facets(self, role: str):
        return self.fields.role_facets(role)

    # -- the state between iterates ---------------------------------------------------------------
    def set_uniform_secant(self, rate: float) -> None:
        """A uniform modulus G(rate), the start of both secant methods."""
        self.state.set_uniform(rate)

    def update_state(self, u: dolfinx.fem.Function, frozen_too: bool) -> None:
        """Take G, the contact set and the slip regularisation from u (and the frozen coefficients
        too if asked)."""
        self.state.update(u)
        if frozen_too:
            self.freeze(u)

    def freeze(self, u: dolfinx.fem.Function) -> None:
        """Every frozen coefficient from u: u_{0,m} of the modified method (3.33), u_n of (3.13)."""
        for coefficient in self.frozen:
            coefficient.freeze(u)

    def carry_from(self, previous: FlowProblem, initial: dolfinx.fem.Function) -> None:
        """A solved problem on another mesh of the workpiece carried over (mesh/transfer.py): its
        velocity into ``initial``, node for node where the mesh is the previous one's with its
        nodes moved (same_layout), and the augmented contact's multiplier
        (ContactMultiplier.start_from), without which a warm start's first iterate has the
        penalty's contact pressure alone, and no friction bound (Coulomb's reads lambda). The
        iteration then may end from its second iterate on (``first_iterates``): the first moves
        the flow by about the shape's change, which can lie below delta while the answer is
        further (docs/free_surface.md, step 6)."""
        # the mixed formulation is interpolated: node for node its Newton line search stalled
        # (docs/free_surface.md, step 7)
        nodal = not self.mixed and same_layout(previous.u, self.u,
                                               (previous.facet_tags, self.facet_tags))
        transfer(previous.u, initial, nodal)
        self.first_iterates = 2
        if self.multiplier is not None and previous.multiplier is not None:
            self.multiplier.start_from(previous.multiplier.value, nodal)

    def start_at(self, u: dolfinx.fem.Function) -> None:
        """Every frozen coefficient for an iteration started from u, near the answer
        (frozen.py)."""
        for coefficient in self.frozen:
            coefficient.start_at(u)

    def frozen_change(self, u: dolfinx.fem.Function) -> float:
        """The largest relative change freezing the coefficients at u would make (0 without any)."""
        return max((coefficient.change(u) for coefficient in self.frozen), default=0.0)

    def coupled_settled(self, u: dolfinx.fem.Function, tolerance: float) -> bool:
        """Whether the coupled fields (the frozen coefficients but the friction bound: the
        transported strain, the temperature a flow law reads) would change by less than
        ``tolerance`` when frozen at u: an iteration whose velocity increment is below delta has
        not converged while they still move (the velocity is insensitive to some of their modes)."""
        return all(field.change(u) < tolerance for field in self.frozen if field.coupled)

    def snapshot(self) -> list[object]:
        """The frozen coefficients' and the contact multiplier's values (restore)."""
        multiplier = [] if self.multiplier is None else [self.multiplier.value.x.array.copy()]
        return [field.snapshot() for field in self.frozen] + multiplier

    def restore(self, saved: list[object]) -> None:
        """The values of a snapshot back."""
        if self.multiplier is not None:  # first: the friction bound's derived fields read it
            self.multiplier.value.x.array[:] = saved[-1]
        for field, values in zip(self.frozen, saved, strict=False):
            field.restore(values)

    def contact_settled(self, increment: float) -> bool:
        """After an iterate taken in full: the augmented contact's multiplier update
        (ContactMultiplier.settled); True when there is none or it has settled."""
        return self.multiplier is None or self.multiplier.settled(increment,
                                                                  self.scene.solver.tolerance)

    @property
    def contact_updates(self) -> int:
        """How often the augmented contact's multiplier has been updated (0 without one)."""
        return 0 if self.multiplier is None else self.multiplier.updates

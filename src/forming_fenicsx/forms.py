"""The penalty variational problem (3.5)-(3.12) for one scene: spaces, boundary conditions and forms.

b(w; u, v) = int 2/3 G(w) e'(u):e'(v) dx + int (1/d) div u div v dx + int_G3 (1/d_N) u_N^+ v_N ds,
plus the regularised friction <j'_dT(w, u), v> on Gamma3 when mu > 0 and f(v) = int_G5 F_N v_N
when the scene has Gamma5. Only the terms the scene needs are built.
"""
from __future__ import annotations

from dataclasses import dataclass

import dolfinx.fem
import dolfinx.fem.petsc
import numpy as np
import ufl
from petsc4py import PETSc

from . import contact, friction
from .boundary_filter import BoundaryFilter
from .compat import function_space, mixed_space, petsc_vec, quadrature_points, quadrature_space
from .geometry import FormingMesh
from .roles import ROLES
from .kinematics import deviatoric, deviatoric_product, equivalent_strain_rate, strain_rate
from .projection import LumpedProjector
from .scene import Scene


@dataclass
class NewtonForms:
    """What Newton's method needs of a problem (FlowProblem.newton_forms): compiled energy and residual
    (SplitForm), and the operator with its UFL form; the dual stress at the Gauss points with the
    expressions that reset and update it; the operator's material coefficients at the Gauss points (G
    and (G'/G)/rate at u) with the expression that sets them; the last Newton step du and the iterate
    before it."""

    energy: SplitForm
    residual: SplitForm
    operator: dolfinx.fem.Form
    operator_ufl: ufl.Form
    dual: dolfinx.fem.Function
    dual_reset: dolfinx.fem.Expression
    dual_update: dolfinx.fem.Expression
    tangent: dolfinx.fem.Function
    tangent_update: dolfinx.fem.Expression
    step: dolfinx.fem.Function
    previous: dolfinx.fem.Function
    contact_set: dolfinx.fem.Form | None


def quadrature_degree(element_degree: int, reduced: bool) -> int:
    """Gauss degree of complete ((k+1)^2 points) or reduced (k^2 points) integration for Q_k."""
    points = element_degree if reduced else element_degree + 1
    return 2 * points - 1


ONE_POINT_DEGREE = 1  # Gauss rules up to this degree have a single point on quadrilaterals


@dataclass
class SplitForm:
    """A scalar or linear form (``ufl``) compiled as the parts whose sum it is (see ``split_form``)."""

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
    """The form compiled as one, or with its integrals of quadrature degree ``apart_degree`` compiled
    apart from the others.

    FFCx (the 0.5 of Debian 12 and the 0.9 of Debian 13) miscomputes a scalar or linear form that
    integrates a coefficient's derivatives with a one-point rule beside another rule: the form
    sum(tau(u):e(v) dx + (1/d) div u div v dx_1) differs from its two terms assembled apart by 2 to 5 %
    of their size (tests/test_forms.py). This is the reduced penalty term of Q1. Such a form is
    compiled in parts, whose assembled values add up to the form's."""
    if apart_degree is None:
        return SplitForm(form, [dolfinx.fem.form(form)])
    apart = [i for i in form.integrals() if i.metadata().get("quadrature_degree") == apart_degree]
    rest = [i for i in form.integrals() if i.metadata().get("quadrature_degree") != apart_degree]
    return SplitForm(form, [dolfinx.fem.form(ufl.Form(group)) for group in (rest, apart) if group])


class FlowProblem:
    """Velocity space, secant state and compiled forms of the penalty problem for one scene.

    The state functions hold the iterate the coefficients are taken from: ``u_state`` (u_n) for the
    secant coefficient G, the contact active set and the friction regularisation, and
    ``u_friction`` (u_{0,m} in (3.33), u_n in (3.13)) for the friction bound tau_f.
    """

    def __init__(self, scene: Scene, forming_mesh: FormingMesh):
        self.scene = scene
        self.mesh = mesh = forming_mesh.mesh
        self.roles = forming_mesh.roles
        self.facet_tags = forming_mesh.facet_tags
        self.constraints = forming_mesh.constraints
        self.comm = mesh.comm
        k = scene.discretisation.degree
        # the unknown of the linear systems: the velocity (penalty), or velocity and pressure (mixed)
        self.mixed = scene.discretisation.formulation == "mixed"
        if self.mixed:
            self.system_space = mixed_space(mesh, k, "DPC", 1)
            self.solution = dolfinx.fem.Function(self.system_space)
            self.V, self._velocity_dofs = self.system_space.sub(0).collapse()
            pressure_space, self._pressure_dofs = self.system_space.sub(1).collapse()
            self.pressure = dolfinx.fem.Function(pressure_space, name="pressure")
            self.u = dolfinx.fem.Function(self.V, name="velocity")
        else:
            self.V = self.system_space = function_space(mesh, "P", k, (2,))
            self.u = self.solution = dolfinx.fem.Function(self.V, name="velocity")
        self.u_state = dolfinx.fem.Function(self.V)
        self.u_friction = dolfinx.fem.Function(self.V)

        self.full_degree = quadrature_degree(k, reduced=False)
        reduced = scene.discretisation.volumetric_integration == "reduced" and not self.mixed
        self.volumetric_degree = quadrature_degree(k, reduced)
        self.dx = ufl.dx(domain=mesh, metadata={"quadrature_degree": self.full_degree})
        self.dx_vol = ufl.dx(domain=mesh, metadata={"quadrature_degree": self.volumetric_degree})
        # scalar and linear forms with a one-point volumetric rule beside the others are compiled in parts
        self._apart_degree = (self.volumetric_degree if self.volumetric_degree != self.full_degree
                              and self.volumetric_degree <= ONE_POINT_DEGREE else None)
        self.ds = ufl.Measure("ds", domain=mesh, subdomain_data=forming_mesh.facet_tags,
                              metadata={"quadrature_degree": self.full_degree})
        self.n = ufl.FacetNormal(mesh)

        # "quadrature": G evaluated at the integration points of the state, a UFL expression; else G is a
        # Function of element means ("centres") or vertex means ("nodes": bilinear in between keeps G > 0
        # everywhere; Q2 nodal values would not), updated from the projected equivalent strain rate.
        self._uniform = dolfinx.fem.Constant(mesh, PETSc.ScalarType(0.0))
        self.quadrature_secant = None
        if scene.discretisation.averaging == "quadrature":
            self.quadrature_secant = scene.material.secant_ufl(equivalent_strain_rate(self.u_state))
        else:
            averaging_space = (function_space(mesh, "DP", 0) if scene.discretisation.averaging == "centres"
                               else function_space(mesh, "P", 1))
            self.strain_rate = dolfinx.fem.Function(averaging_space, name="equivalent_strain_rate")
            self.secant = dolfinx.fem.Function(averaging_space, name="secant_viscosity")
            self._rate_projector = LumpedProjector(equivalent_strain_rate(self.u_state), self.strain_rate,
                                                   self.full_degree)

        self.has_contact = "gamma3_contact" in self.roles
        self.has_friction = self.has_contact and scene.friction.mu > 0
        self.has_force = "gamma5_force" in self.roles and scene.process.applied_force is not None
        self.multiplier = None  # the augmented contact's lambda (contact.py), or none: the pure penalty
        if self.has_contact and scene.penalty.augmented:
            self.multiplier = contact.ContactMultiplier(self.u, self.n, scene.penalty.d_N, self.ds_contact,
                                                        self.full_degree)
        self.normal_stress_average = None
        if self.has_friction and scene.friction.normal_stress == "averaged":
            self.normal_stress_average = BoundaryFilter(
                self.friction_normal_stress(), mesh, self.facet_tags, ROLES["gamma3_contact"],
                scene.friction.mollification_length, scene.solver.petsc_options, "averaged_normal_stress")
        self.bcs = self._boundary_conditions()

        if self.mixed:
            (du, dp), (v, q) = ufl.split(ufl.TrialFunction(self.system_space)), ufl.split(
                ufl.TestFunction(self.system_space))
            self.a_ufl = self._bilinear(du, v) - dp * ufl.div(v) * self.dx - q * ufl.div(du) * self.dx
        else:
            du, v = ufl.TrialFunction(self.V), ufl.TestFunction(self.V)
            self.a_ufl = self._bilinear(du, v)
        self.a = dolfinx.fem.form(self.a_ufl)
        load = self._linear(v)
        self.L = dolfinx.fem.form(load) if load is not None else None
        zero = dolfinx.fem.Constant(mesh, PETSc.ScalarType((0.0, 0.0)))
        self.system_vector = self.L or dolfinx.fem.form(ufl.inner(zero, v) * self.dx)
        # the residual of the velocity equations at u (its values on constrained dofs are reactions)
        v = ufl.TestFunction(self.V)
        residual = ufl.action(self._bilinear(ufl.TrialFunction(self.V), v), self.u)
        if self.mixed:
            residual -= self.pressure * ufl.div(v) * self.dx
        load = self._linear(v)
        if load is not None:
            residual -= load
        self.residual = split_form(residual, self._apart_degree)

    # -- terms of b(w; u, v) and f(v) ---------------------------------------------------------
    def secant_coefficient(self):
        """G(w) = sigma_p/rate of a(w; u, v): the averaged Function, or the quadrature-point expression."""
        if self.quadrature_secant is None:
            return self.secant
        return ufl.conditional(ufl.gt(self._uniform, 0.0), self._uniform, self.quadrature_secant)

    def viscous_form(self, u, v):
        """a(w; u, v) of (3.2) with the secant coefficient G(w) = sigma_p/rate."""
        return 2.0 / 3.0 * self.secant_coefficient() * deviatoric_product(strain_rate(u), strain_rate(v)) * self.dx

    def volumetric_form(self, u, v):
        """Penalty incompressibility (1/d) int div u div v of (3.5), complete or reduced Gauss."""
        return 1.0 / self.scene.penalty.d * ufl.div(u) * ufl.div(v) * self.dx_vol

    def hydrostatic_stress(self):
        """sigma_H: div(u)/d of the penalty (3.4), or minus the pressure of the mixed formulation."""
        return -self.pressure if self.mixed else ufl.div(self.u) / self.scene.penalty.d

    def stress(self):
        """In-plane Cauchy stress s + sigma_H I with s = 2/3 G e' (2.4)."""
        e = strain_rate(self.u)
        return 2.0 / 3.0 * self.secant_coefficient() * deviatoric(e) + self.hydrostatic_stress() * ufl.Identity(2)

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
        """The local normal pressure of the friction bound: the multiplier lambda of the augmented contact
        (the pressure it has converged to, updated with it), else u_N^+/d_N of (3.4) at ``u_friction``."""
        if self.multiplier is not None:
            return self.multiplier.value
        return self.contact_pressure(self.u_friction)

    def normal_pressure(self):
        """The sigma_N-bar >= 0 of tau_f: averaged (mollified) or local, frozen by freeze_friction."""
        if self.normal_stress_average is not None:
            return ufl.max_value(self.normal_stress_average.value, 0.0)
        return self.friction_normal_stress()

    def friction_coefficient(self):
        """Slip coefficient tau_f(u_friction)/sqrt(|u_state,T|^2 + d_T^2) of the regularised friction."""
        tau_f = friction.friction_bound(self.scene.friction.mu, self.normal_pressure())
        return friction.slip_coefficient(tau_f, self.u_state, self.n, self.scene.friction.d_T)

    def _bilinear(self, u, v):
        """b(w; u, v) of (3.5); the mixed formulation adds its pressure terms instead of the penalty."""
        form = self.viscous_form(u, v)
        if not self.mixed:
            form += self.volumetric_form(u, v)
        if self.has_contact:
            form += contact.contact_form(u, v, self.contact_active(self.u_state), self.n, self.scene.penalty.d_N,
                                         self.ds_contact)
        if self.has_friction:
            form += friction.friction_form(u, v, self.friction_coefficient(), self.n, self.ds_contact)
        return form

    def _linear(self, v):
        """The right-hand side of the secant systems: f(v) = int_G5 F_N v_N of (3.2), minus the augmented
        contact's int lambda v_N over the state's active set; None when the scene has neither."""
        form = self._load(v) if self.has_force else None
        if self.multiplier is not None:
            pressure = contact.multiplier_form(v, self.contact_active(self.u_state), self.multiplier.value, self.n,
                                               self.ds_contact)
            form = -pressure if form is None else form - pressure
        return form

    def _load(self, v):
        """f(v) = int_G5 F_N v_N of (3.2)."""
        F_N = dolfinx.fem.Constant(self.mesh, PETSc.ScalarType(self.scene.process.applied_force))
        return F_N * ufl.dot(v, self.n) * self.ds(ROLES["gamma5_force"])

    # -- Newton's method: energy, residual and the primal-dual operator -------------------------
    def newton_forms(self) -> NewtonForms:
        """Energy Phi(u), residual F(u; v) = Phi'(u; v) and the primal-dual Newton operator, compiled.

        Phi(u) = int W(rate(u)) + 1/(2d) (div u)^2 + int_G3 1/(2 d_N) (u_N^+)^2 + j_dT(u_friction; u) - f(u)
        with W' = sigma_p, so F(u; v) = int tau(u):e(v) + ... is the Euler equation of (3.10)-(3.12) whose
        fixed point the secant methods (3.13)/(3.33) find, tau(u) = 2/3 G(rate) e'(u) the deviatoric stress.
        The mixed formulation drops the penalty from Phi and adds -(p, div v) - (q, div u) to F; its
        iterates keep (q, div u) = 0, on which Phi is still the merit function of the line search.

        The operator linearises tau = tau(u) with a separate dual iterate tau_h at the Gauss points
        (primal-dual Newton, as for total-variation problems): d tau = 2/3 G e'(du) + (G'/G) d rate tau_h.
        With tau_h = tau(u) this is the consistent tangent, whose stiffness along the flow direction is
        only about alpha times the secant; carrying tau_h separately (updated by the same linearisation
        and capped at the flow stress) keeps the steps well scaled far from the answer. The operator
        takes the symmetric part of the coupling term, (d rate(du) tau_h:e(v) + d rate(v) tau_h:e(du))/2
        (Hintermueller and Stadler's symmetrised primal-dual Newton): it equals the consistent tangent
        when tau_h = tau(u), and with |tau_h| <= sigma_p(rate) (the cap) its smallest eigenvalue is alpha
        times the secant's, so the operator is symmetric positive definite with the penalty (Cholesky)
        and every Newton step is a descent direction of Phi. The contact
        penalty enters with its active set at u (semismooth) joined with the previous iterate's: a die
        node that left contact in the last step stays stiff one step more (without it, a node at the
        separation point entered and left contact on alternate steps, and the line search cut each step
        that pushed it in; docs/solvers.md). The regularised friction enters at a
        fixed bound tau_f (from ``u_friction``, updated every step as in (3.13): the nonlocal averaged
        normal stress is not differentiated) with its tangent where the die point slips faster than
        friction.SLOW_SLIP times the process velocity, and with its secant tau_f/sqrt(|u_T|^2 + d_T^2), the
        linearisation of the direct method (3.13), where it slips slower or sticks: there the
        tangent's curvature, about tau_f/d_T near zero slip, made the line search cut the steps
        (docs/solvers.md). The rate is regularised as sqrt(rate^2 + (1e-6 rate1)^2) so that everything
        stays finite in rigid zones.
        """
        scene, material, w = self.scene, self.scene.material, self.solution
        test, trial = ufl.TestFunction(self.system_space), ufl.TrialFunction(self.system_space)
        step = dolfinx.fem.Function(self.system_space)      # the last Newton solve's dw (w <- w - s dw)
        previous = dolfinx.fem.Function(self.system_space)  # w before that step
        if self.mixed:  # w = (u, p): the pressure terms replace the penalty
            (u, p), (v, q), (du, dp) = ufl.split(w), ufl.split(test), ufl.split(trial)
            u_previous, u_step = ufl.split(previous)[0], ufl.split(step)[0]
        else:
            u, v, du, u_previous, u_step = w, test, trial, previous, step
        dual = dolfinx.fem.Function(quadrature_space(self.mesh, self.full_degree, (2, 2)), name="dual_stress")
        floor = 1e-6 * material.rate_floor

        def rate(w):
            e = strain_rate(w)
            return ufl.sqrt(2.0 / 3.0 * deviatoric_product(e, e) + floor**2)

        def stress(w):
            return 2.0 / 3.0 * material.secant_ufl(rate(w)) * deviatoric(strain_rate(w))

        def secant_and_coupling(w):
            """G and (G'/G)/rate at w: d tau = 2/3 G e'(dw) + coupling e'(w):e'(dw) 2/3 tau."""
            r = ufl.variable(rate(w))
            g = material.secant_ufl(r)
            return g, ufl.diff(g, r) / g / r

        # G and (G'/G)/rate at u, evaluated at the Gauss points once per step (tangent_update, before the
        # operator is assembled): neither the operator nor the dual update then evaluates the flow law
        tangent = dolfinx.fem.Function(quadrature_space(self.mesh, self.full_degree, (2,)), name="tangent")
        g, coupling = tangent[0], tangent[1]
        e, e_du, e_v = strain_rate(u), strain_rate(du), strain_rate(v)
        symmetric_coupling = (deviatoric_product(e, e_du) * ufl.inner(dual, e_v)
                              + deviatoric_product(e, e_v) * ufl.inner(dual, e_du)) / 3.0  # 2/3 of the mean
        energy = material.potential_ufl(rate(u)) * self.dx
        operator = (2.0 / 3.0 * g * deviatoric_product(e_du, e_v) + coupling * symmetric_coupling) * self.dx
        if self.mixed:
            operator -= (dp * ufl.div(v) + q * ufl.div(du)) * self.dx
        else:
            energy += 0.5 / scene.penalty.d * ufl.div(u) ** 2 * self.dx_vol
            operator += self.volumetric_form(du, v)
        if self.has_contact:  # the active set of its second derivative: at u, joined with the previous iterate's
            energy += contact.contact_energy(u, self.n, scene.penalty.d_N, self.multiplier_value, self.ds_contact)
            active = ufl.max_value(self.contact_active(u), self.contact_active(u_previous))
            operator += contact.contact_form(du, v, active, self.n, scene.penalty.d_N, self.ds_contact)
        if self.has_friction:  # secant in slow slip, tangent in fast slip (friction.newton_form)
            tau_f, d_T = friction.friction_bound(scene.friction.mu, self.normal_pressure()), scene.friction.d_T
            energy += friction.regularised_functional(tau_f, u, self.n, d_T) * self.ds_contact
            operator += friction.newton_form(du, v, u, tau_f, self.n, d_T,
                                             friction.SLOW_SLIP * abs(scene.process.velocity), self.ds_contact)
        if self.has_force:
            energy -= ufl.action(self._load(v), w)
        residual = ufl.derivative(energy, w, test)
        if self.mixed:  # the energy (no pressure) stays a merit function: every step keeps (q, div u) = 0
            residual -= (p * ufl.div(v) + q * ufl.div(u)) * self.dx
        # the full dual Newton step tau(u) - d tau(du) at the old u (whatever primal step the line search
        # took; the tangent still holds G and G' there), d tau = 2/3 G e'(du) + (G'/G) d rate tau_h with
        # d rate = 2/3 e'(u):e'(du)/rate, capped at the flow stress of the new u: the projection of
        # primal-dual Newton methods
        e_previous, e_step = strain_rate(u_previous), strain_rate(u_step)
        updated = 2.0 / 3.0 * g * deviatoric(e_previous - e_step) \
            - coupling * 2.0 / 3.0 * deviatoric_product(e_previous, e_step) * dual
        equivalent = ufl.sqrt(1.5 * (ufl.inner(updated, updated) + ufl.tr(updated) ** 2)) + 1e-300
        cap = material.secant_ufl(rate(u)) * rate(u)
        capped = ufl.conditional(ufl.gt(equivalent, cap), cap / equivalent, 1.0) * updated
        points = quadrature_points(self.mesh, self.full_degree)
        contact_set = None
        if self.has_contact:
            node = ufl.TestFunction(function_space(self.mesh, "P", scene.discretisation.degree))
            contact_set = dolfinx.fem.form(self.contact_active(u) * node * self.ds_contact)
        return NewtonForms(split_form(energy, self._apart_degree), split_form(residual, self._apart_degree),
                           dolfinx.fem.form(operator), operator,
                           dual, dolfinx.fem.Expression(stress(u), points), dolfinx.fem.Expression(capped, points),
                           tangent, dolfinx.fem.Expression(ufl.as_vector(secant_and_coupling(u)), points),
                           step, previous, contact_set)

    # -- boundary conditions ------------------------------------------------------------------
    def boundary_dofs(self, role: str, component: int, space=None) -> np.ndarray:
        """Local dof indices (blocked space, unrolled) of one velocity component on a boundary role, in
        ``space`` (default the velocity space V; the mixed formulation's velocity subspace for its bcs)."""
        space = self.V if space is None else space
        return dolfinx.fem.locate_dofs_topological(space.sub(component), self.mesh.topology.dim - 1,
                                                   self.role_facets(role))

    def role_facets(self, role: str) -> np.ndarray:
        """Local facets of a boundary role."""
        return self.facet_tags.indices[self.facet_tags.values == ROLES[role]]

    def _boundary_conditions(self) -> list:
        """The mesh's constraints: u_N = u_N^0 on Gamma1 (2.5) and u_N = 0 on Gamma6 (2.8)."""
        velocity = self.system_space.sub(0) if self.mixed else self.V
        return [dolfinx.fem.dirichletbc(PETSc.ScalarType(c.value), self.boundary_dofs(c.role, c.component, velocity),
                                        velocity.sub(c.component)) for c in self.constraints]

    # -- secant state ---------------------------------------------------------------------------
    def set_uniform_secant(self, rate: float) -> None:
        """A uniform modulus G(rate), the start of both secant methods (u_0 carries no strain rate)."""
        value = self.scene.material.secant(np.array([rate]))[0]
        if self.quadrature_secant is None:
            self.secant.x.array[:] = value
        else:
            self._uniform.value = value

    def update_state(self, u: dolfinx.fem.Function, friction_too: bool) -> None:
        """Take G, the contact set and the slip regularisation from u (and tau_f too if asked)."""
        u.x.scatter_forward()
        petsc_vec(u).copy(petsc_vec(self.u_state))
        self.u_state.x.scatter_forward()
        if self.quadrature_secant is None:
            self._rate_projector.project()
            self.secant.x.array[:] = self.scene.material.secant(self.strain_rate.x.array)
        else:
            self._uniform.value = 0.0
        if friction_too:
            self.freeze_friction(u)

    def contact_settled(self, increment: float) -> bool:
        """After an iterate taken in full: the augmented contact's multiplier update (ContactMultiplier.settled);
        True when there is none or it has settled."""
        return self.multiplier is None or self.multiplier.settled(increment, self.scene.solver.tolerance)

    @property
    def contact_updates(self) -> int:
        """How often the augmented contact's multiplier has been updated (0 without one)."""
        return 0 if self.multiplier is None else self.multiplier.updates

    def freeze_friction(self, u: dolfinx.fem.Function) -> None:
        """tau_f from u: u_{0,m} of the modified method (3.33), u_n of the direct method (3.13)."""
        petsc_vec(u).copy(petsc_vec(self.u_friction))
        self.u_friction.x.scatter_forward()
        if self.normal_stress_average is not None:
            self.normal_stress_average.update()

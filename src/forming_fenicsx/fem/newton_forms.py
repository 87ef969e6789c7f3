"""Newton's forms of the flow problem: the energy Phi, its derivative F (the residual) and the
symmetrised primal-dual operator (newton.py solves with them)."""
from __future__ import annotations

from dataclasses import dataclass

import dolfinx.fem
import ufl

from forming_fenicsx.physics import contact, friction
from forming_fenicsx.core.compat import function_space, quadrature_points, quadrature_space
from forming_fenicsx.fem.forms import FlowProblem, SplitForm, split_form


@dataclass
class NewtonForms:
    """What Newton's method needs of a problem (newton_forms): compiled energy and residual
    (SplitForm), and the operator with its UFL form; the dual stress at the Gauss points with the
    expressions that reset and update it (and cap it again at the flow stress after the coupled
    fields move: None without any); the operator's material coefficients at the Gauss points (G
    and (G'/G)/rate at u) with the expression that sets them; the last Newton step du and the
    iterate before it."""

    energy: SplitForm
    residual: SplitForm
    operator: dolfinx.fem.Form
    operator_ufl: ufl.Form
    dual: dolfinx.fem.Function
    dual_reset: dolfinx.fem.Expression
    dual_update: dolfinx.fem.Expression
    dual_recap: dolfinx.fem.Expression | None
    tangent: dolfinx.fem.Function
    tangent_update: dolfinx.fem.Expression
    step: dolfinx.fem.Function
    previous: dolfinx.fem.Function
    contact_set: dolfinx.fem.Form | None


def newton_forms(problem: FlowProblem) -> NewtonForms:
    """Energy Phi(u), residual F(u; v) = Phi'(u; v) and the primal-dual Newton operator, compiled.

    Phi(u) = int W(rate(u)) + 1/(2d) (div u)^2 + int_G3 1/(2 d_N) (u_N^+)^2 + j_dT(u_friction; u)
    - f(u) with W' = sigma_p, so F(u; v) = int tau(u):e(v) + ... is the Euler equation of
    (3.10)-(3.12) whose fixed point the secant methods (3.13)/(3.33) find, tau(u) = 2/3 G(rate)
    e'(u) the deviatoric stress. The mixed formulation drops the penalty from Phi and adds
    -(p, div v) - (q, div u) to F; its iterates keep (q, div u) = 0, on which Phi is still the merit
    function of the line search.

    The operator linearises tau = tau(u) with a separate dual iterate tau_h at the Gauss points
    (primal-dual Newton, as for total-variation problems): d tau = 2/3 G e'(du) + (G'/G) d rate
    tau_h. With tau_h = tau(u) this is the consistent tangent, whose stiffness along the flow
    direction is only about alpha times the secant; carrying tau_h separately (updated by the same
    linearisation and capped at the flow stress) keeps the steps well scaled far from the answer.
    The operator takes the symmetric part of the coupling term, (d rate(du) tau_h:e(v) + d rate(v)
    tau_h:e(du))/2 (Hintermueller and Stadler's symmetrised primal-dual Newton): it equals the
    consistent tangent when tau_h = tau(u), and with |tau_h| <= sigma_p(rate) (the cap) its
    smallest eigenvalue is alpha times the secant's, so the operator is symmetric positive definite
    with the penalty (Cholesky) and every Newton step is a descent direction of Phi. The contact
    penalty enters with its active set at u (semismooth) joined with the previous iterate's: a die
    node that left contact in the last step stays stiff one step more (without it, a node at the
    separation point entered and left contact on alternate steps, and the line search cut each
    step that pushed it in; docs/solvers.md). The regularised friction enters at a fixed bound
    tau_f (from the friction state, updated every step as in (3.13): the nonlocal averaged normal
    stress is not differentiated) with its tangent where the die point slips faster than
    friction.SLOW_SLIP times the process velocity, and with its secant tau_f/sqrt(|u_T|^2 + d_T^2),
    the linearisation of the direct method (3.13), where it slips slower or sticks: there the
    tangent's curvature, about tau_f/d_T near zero slip, made the line search cut the steps
    (docs/solvers.md). Sticking's penalised slip is linear: its term is exact. The rate is
    regularised as sqrt(rate^2 + (1e-6 rate1)^2) so that everything stays finite in rigid zones.
    """
    scene, material, w = problem.scene, problem.scene.material, problem.solution
    c = problem.coordinates
    test, trial = ufl.TestFunction(problem.system_space), ufl.TrialFunction(problem.system_space)
    # the last Newton solve's dw (w <- w - s dw)
    step = dolfinx.fem.Function(problem.system_space)
    previous = dolfinx.fem.Function(problem.system_space)  # w before that step
    if problem.mixed:  # w = (u, p): the pressure terms replace the penalty
        (u, p), (v, q), (du, dp) = ufl.split(w), ufl.split(test), ufl.split(trial)
        u_previous, u_step = ufl.split(previous)[0], ufl.split(step)[0]
    else:
        u, v, du, u_previous, u_step = w, test, trial, previous, step
    dual = dolfinx.fem.Function(quadrature_space(problem.mesh, problem.full_degree, (c.dim, c.dim)),
                                name="dual_stress")
    floor = 1e-6 * material.rate_floor

    def rate(w):
        e = c.strain_rate(w)
        return ufl.sqrt(2.0 / 3.0 * c.deviatoric_product(e, e) + floor**2)

    def stress(w):
        return (2.0 / 3.0 * material.secant_ufl(rate(w), problem.strain, problem.temperature)
                * c.deviatoric(c.strain_rate(w)))

    def secant_and_coupling(w):
        """G and (G'/G)/rate at w: d tau = 2/3 G e'(dw) + coupling e'(w):e'(dw) 2/3 tau."""
        r = ufl.variable(rate(w))
        g = material.secant_ufl(r, problem.strain, problem.temperature)
        return g, ufl.diff(g, r) / g / r

    # G and (G'/G)/rate at u, evaluated at the Gauss points once per step (tangent_update, before
    # the operator is assembled): neither the operator nor the dual update then evaluates the flow
    # law
    tangent = dolfinx.fem.Function(quadrature_space(problem.mesh, problem.full_degree, (2,)),
                                   name="tangent")
    g, coupling = tangent[0], tangent[1]
    e, e_du, e_v = c.strain_rate(u), c.strain_rate(du), c.strain_rate(v)
    # the coupling term symmetrised: 2/3 of the mean of the two orders
    symmetric_coupling = (c.deviatoric_product(e, e_du) * ufl.inner(dual, e_v)
                          + c.deviatoric_product(e, e_v) * ufl.inner(dual, e_du)) / 3.0
    # Phi = int W(rate) + the other terms' energies; the residual takes the flow law's term from its
    # stress, 2/3 G e'(u):e'(v), the exact derivative of int W: a law whose W is a quadrature (no
    # closed form) then moves only the line search's merit, not the answer
    flow_energy = material.potential_ufl(rate(u), problem.strain, problem.temperature) * problem.dx
    others = []  # the energies of the other terms
    operator = (2.0 / 3.0 * g * c.deviatoric_product(e_du, e_v)
                + coupling * symmetric_coupling) * problem.dx
    if problem.mixed:
        operator -= (dp * c.divergence(v) + q * c.divergence(du)) * problem.dx
    else:
        others.append(0.5 / scene.penalty.d * c.divergence(u) ** 2 * problem.dx_vol)
        operator += problem.volumetric_form(du, v)
    # the active set of the contact term's second derivative: at u, joined with the previous
    # iterate's
    if problem.has_contact:
        others.append(contact.contact_energy(u, problem.n, scene.penalty.d_N,
                                             problem.multiplier_value, problem.ds_contact))
        active = ufl.max_value(problem.contact_active(u), problem.contact_active(u_previous))
        operator += contact.contact_form(du, v, active, problem.n, scene.penalty.d_N,
                                         problem.ds_contact)
    if problem.sticking:  # the slip penalised: linear, its secant the tangent
        stiffness = problem.friction_coefficient()
        others.append(friction.sticking_functional(stiffness, problem.slip(u), problem.n)
                      * problem.ds_contact)
        operator += friction.friction_form(du, v, stiffness, problem.n, problem.ds_contact)
    elif problem.has_friction:  # secant in slow slip, tangent in fast slip (friction.newton_form)
        tau_f, d_T = problem.friction_bound(), scene.friction.d_T
        others.append(friction.regularised_functional(tau_f, problem.slip(u), problem.n, d_T)
                      * problem.ds_contact)
        # rolling: the tangent everywhere; the friction's reversal at the neutral point holds the
        # strip along x, and the secant there under-steps the entry speed (docs/rolling.md)
        slow = 0.0 if problem.rolling else friction.SLOW_SLIP * abs(scene.process.velocity)
        operator += friction.newton_form(du, v, problem.slip(u), tau_f, problem.n, d_T, slow,
                                         problem.ds_contact)
    if problem.has_force:
        others.append(-ufl.action(problem.load(v), w))
    if problem.entry_speed is not None:  # rolling's hold of the entry speed (zero once released)
        others.append(problem.entry_speed.energy(u))
        operator += problem.entry_speed.form(du, v)
    residual = (2.0 / 3.0 * material.secant_ufl(rate(u), problem.strain, problem.temperature)
                * c.deviatoric_product(e, e_v) * problem.dx)
    energy = flow_energy
    for term in others:
        residual += ufl.derivative(term, w, test)
        energy += term
    # the energy (no pressure) stays a merit function: every step keeps (q, div u) = 0
    if problem.mixed:
        residual -= (p * c.divergence(v) + q * c.divergence(u)) * problem.dx
    # the full dual Newton step tau(u) - d tau(du) at the old u (whatever primal step the line
    # search took; the tangent still holds G and G' there), d tau = 2/3 G e'(du) + (G'/G) d rate
    # tau_h with d rate = 2/3 e'(u):e'(du)/rate, capped at the flow stress of the new u: the
    # projection of primal-dual Newton methods
    e_previous, e_step = c.strain_rate(u_previous), c.strain_rate(u_step)
    updated = (2.0 / 3.0 * g * c.deviatoric(e_previous - e_step)
               - coupling * 2.0 / 3.0 * c.deviatoric_product(e_previous, e_step) * dual)
    # |s| of the 3-D deviator: in plane strain the held 2x2 tensor's out-of-plane part is -tr; the
    # axisymmetric 3x3 deviator has zero trace
    cap = material.secant_ufl(rate(u), problem.strain, problem.temperature) * rate(u)

    def capped(t):
        """t scaled down to the flow stress of u where its equivalent exceeds it."""
        equivalent = ufl.sqrt(1.5 * (ufl.inner(t, t) + ufl.tr(t) ** 2)) + 1e-300
        return ufl.conditional(ufl.gt(equivalent, cap), cap / equivalent, 1.0) * t

    points = quadrature_points(problem.mesh, problem.full_degree)
    # the dual capped again once the coupled fields have moved the flow stress (dual_recap)
    coupled = problem.strain is not None or problem.temperature is not None
    # a factor that carries the mesh: a Newtonian law's G and G' are constants, which UFL gives no
    # domain
    on_mesh = dolfinx.fem.Constant(problem.mesh, 1.0)
    contact_set = None
    if problem.has_contact:
        node = ufl.TestFunction(function_space(problem.mesh, "P", scene.discretisation.degree))
        contact_set = dolfinx.fem.form(problem.contact_active(u) * node * problem.ds_contact)
    apart = problem.measures.apart_degree
    return NewtonForms(split_form(energy, apart), split_form(residual, apart),
                       dolfinx.fem.form(operator), operator, dual,
                       dolfinx.fem.Expression(stress(u), points),
                       dolfinx.fem.Expression(capped(updated), points),
                       dolfinx.fem.Expression(capped(dual), points) if coupled else None,
                       tangent,
                       dolfinx.fem.Expression(ufl.as_vector(secant_and_coupling(u)) * on_mesh,
                                              points),
                       step, previous, contact_set)

"""The forms hold only the terms a scene needs; the applied force on Gamma5 enters f(v) and the
force balance; compiled forms equal their quadrature rules assembled apart."""
import dolfinx.fem
import dolfinx.fem.petsc
import pytest
import ufl
from petsc4py import PETSc

from forming_fenicsx.core.compat import petsc_vec
from forming_fenicsx.coupled.coupling import coupled_problem
from forming_fenicsx.fem.forms import FlowProblem, SplitForm
from forming_fenicsx.fem.measures import quadrature_degree
from forming_fenicsx.fem.newton_forms import newton_forms
from forming_fenicsx.mesh.geometry import build_mesh
from forming_fenicsx.solvers.secant import SecantSolver

from conftest import make_scene, solved


def problem_for(**sections) -> FlowProblem:
    scene = make_scene(discretisation={"mesh_size": 1.0}, **sections)
    return coupled_problem(scene, build_mesh(scene))


def test_no_friction_term_at_zero_friction():
    frictionless = problem_for()
    averaged = problem_for(friction={"mu": 0.1})
    local = problem_for(friction={"mu": 0.1, "normal_stress": "local"})
    assert frictionless.normal_stress_average is None and local.normal_stress_average is None
    assert frictionless.friction_state is None and frictionless.frozen == []
    assert averaged.normal_stress_average.value in averaged.a_ufl.coefficients()
    assert local.friction_state.state in local.a_ufl.coefficients()
    for rough in (averaged, local):
        assert len(rough.a_ufl.integrals()) == len(frictionless.a_ufl.integrals()) + 1


def test_force_term_only_with_gamma5():
    assert problem_for().L is None
    loaded = problem_for(process={"applied_force": 0.3})
    assert loaded.L is not None and loaded.has_force


def test_quadrature_degrees():
    assert [quadrature_degree(k, reduced)
            for k in (1, 2) for reduced in (False, True)] == [3, 1, 5, 3]


def test_front_tension_lowers_the_ram_force_and_keeps_the_balance():
    free = solved(solver={"method": "direct"})
    pulled = solved(solver={"method": "direct"}, process={"applied_force": 0.5})
    assert pulled["converged"]
    # F_N times the exit height
    assert pulled["applied_force_x"] == pytest.approx(0.5 * 5.0, rel=1e-12)
    assert pulled["force_balance_residual"] < 1e-3
    assert pulled["ram_force"] < free["ram_force"] - 0.1


def _rules(form) -> list[ufl.Form]:
    """The form's integrals grouped by integral type and quadrature degree, one form per group."""
    groups: dict = {}
    for integral in form.integrals():
        groups.setdefault((integral.integral_type(), integral.metadata().get("quadrature_degree")),
                          []).append(integral)
    return [ufl.Form(group) for group in groups.values()]


def _apart(form) -> SplitForm:
    """The form with each of its rules compiled alone."""
    return SplitForm(form, [dolfinx.fem.form(rule) for rule in _rules(form)])


def _matrix_action(parts, x: PETSc.Vec) -> PETSc.Vec:
    result = x.duplicate()
    result.set(0.0)
    for part in parts:
        A = dolfinx.fem.petsc.assemble_matrix(part)
        A.assemble()
        result.axpy(1.0, A * x)
        A.destroy()
    return result


def _relative(a: PETSc.Vec, b: PETSc.Vec, scale: float | None = None) -> float:
    """||a - b|| over ``scale`` (default ||b||)."""
    difference = a.copy()
    difference.axpy(-1.0, b)
    return difference.norm() / (scale if scale is not None else b.norm())


def _term_scale(form) -> float:
    """The sum of the norms of a linear form's rules assembled apart: the size of the terms whose
    sum (a residual near a solution) is far smaller; rounding errors are relative to it."""
    return sum(_apart(rule).vector().norm() for rule in _rules(form))


@pytest.mark.parametrize("element", ["Q1", "Q2"])
def test_reduced_integration_forms_equal_their_rules_assembled_apart(element):
    """FFCx miscomputes a scalar or linear form integrating a coefficient's derivatives with a
    one-point rule beside another rule (Q1's reduced penalty term; forms.split_form). At a secant
    iterate of Example 1 with contact and averaged friction (mu = 0.1, every term present), with
    reduced integration: the secant residual, Newton's energy and residual (as FlowProblem compiles
    them) and the secant matrix and Newton's operator (compiled as one form each) equal the sums of
    their quadrature rules compiled apart, to rounding; and Newton's residual, the derivative of its
    energy, equals the secant residual b(u; u, v) at u (one Euler equation). Residual differences
    are taken relative to the sum of the rules' norms. Compiled as one form, the Q1 residual misses
    the sum of its rules by 3.6e-2 of that scale (measured with split_form disabled), and Newton
    stalled on Q1."""
    scene = make_scene(friction={"mu": 0.1},
                       discretisation={"mesh_size": 0.5, "element": element,
                                       "volumetric_integration": "reduced",
                                       "averaging": "quadrature"},
                       solver={"method": "direct", "tolerance": 1e-2})
    problem = coupled_problem(scene, build_mesh(scene))
    SecantSolver(problem).solve()
    problem.update_state(problem.u, frozen_too=True)
    forms = newton_forms(problem)
    newton_residual, secant_residual = forms.residual.vector(), problem.residual.vector()
    scale = _term_scale(forms.residual.ufl)
    assert _relative(newton_residual, _apart(forms.residual.ufl).vector(), scale) < 1e-13
    assert _relative(secant_residual, _apart(problem.residual.ufl).vector(), scale) < 1e-13
    assert _relative(newton_residual, secant_residual, scale) < 1e-12
    energy = forms.energy.value(problem.comm)
    assert energy == pytest.approx(_apart(forms.energy.ufl).value(problem.comm), rel=1e-12)
    x = petsc_vec(problem.u).duplicate()
    x.setRandom(PETSc.Random().create(problem.comm))
    for compiled, form in ((problem.a, problem.a_ufl), (forms.operator, forms.operator_ufl)):
        assert _relative(_matrix_action([compiled], x),
                         _matrix_action(_apart(form).parts, x)) < 1e-12
    assert len(forms.residual.parts) == (2 if element == "Q1" else 1)

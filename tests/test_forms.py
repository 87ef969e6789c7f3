"""The forms hold only the terms a scene needs; the applied force on Gamma5 enters f(v) and the force balance."""
import pytest

from forming_fenicsx.forms import FlowProblem, quadrature_degree
from forming_fenicsx.geometry import build_mesh

from conftest import make_scene, solved


def problem_for(**sections) -> FlowProblem:
    scene = make_scene(discretisation={"mesh_size": 1.0}, **sections)
    return FlowProblem(scene, build_mesh(scene))


def test_no_friction_term_at_zero_friction():
    frictionless = problem_for()
    averaged = problem_for(friction={"mu": 0.1})
    local = problem_for(friction={"mu": 0.1, "normal_stress": "local"})
    assert frictionless.normal_stress_average is None and local.normal_stress_average is None
    assert frictionless.u_friction not in frictionless.a_ufl.coefficients()
    assert averaged.normal_stress_average.value in averaged.a_ufl.coefficients()
    assert local.u_friction in local.a_ufl.coefficients()
    for rough in (averaged, local):
        assert len(rough.a_ufl.integrals()) == len(frictionless.a_ufl.integrals()) + 1


def test_force_term_only_with_gamma5():
    assert problem_for().L is None
    loaded = problem_for(process={"applied_force": 0.3})
    assert loaded.L is not None and loaded.has_force


def test_quadrature_degrees():
    assert [quadrature_degree(k, reduced) for k in (1, 2) for reduced in (False, True)] == [3, 1, 5, 3]


def test_front_tension_lowers_the_ram_force_and_keeps_the_balance():
    free = solved(solver={"method": "direct"})
    pulled = solved(solver={"method": "direct"}, process={"applied_force": 0.5})
    assert pulled["converged"]
    assert pulled["applied_force_x"] == pytest.approx(0.5 * 2.5, rel=1e-12)  # F_N times the exit half-height
    assert pulled["force_balance_residual"] < 1e-3
    assert pulled["ram_force"] < free["ram_force"] - 0.1

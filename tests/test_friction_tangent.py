"""The friction bound in Newton's step (fem/friction_tangent.py): K + B M^-1 C is the derivative of
the residual F(u; tau_f(s)) through the bound's state s, in the three ways a Coulomb bound reads the
velocity: the averaged normal stress of a pure penalty contact (drawing), the local one, and
rolling's averaged stress capped at the shear flow stress; and the factor law's m k(s) in rolling
on a rate-sensitive metal. Newton's step carries it in rolling
(newton.py), where it took the grid's slowest Coulomb points from 22 and 21 solves to 15 and 18
(docs/rolling.md)."""
import pytest
from mpi4py import MPI

import dolfinx.fem.petsc

from forming_fenicsx.core.compat import petsc_vec, set_at_quadrature_points
from forming_fenicsx.fem.forms import FlowProblem
from forming_fenicsx.fem.friction_tangent import FrictionTangent
from forming_fenicsx.mesh.geometry import build_mesh
from forming_fenicsx.solvers.newton import NewtonSolver
from forming_fenicsx.solvers.secant import SecantSolver

from conftest import make_scene
from test_rolling import _dimensionless

DRAWING = dict(process={"kind": "drawing"}, penalty={"augmented": False},
               discretisation={"mesh_size": 0.1, "averaging": "quadrature"},
               solver={"method": "direct", "tolerance": 1e-2})
CASES = {
    "averaged": lambda: make_scene(**DRAWING, friction={"mu": 0.2}),
    "local": lambda: make_scene(**DRAWING, friction={"mu": 0.2, "normal_stress": "local"}),
    "rolling": lambda: _dimensionless(25.0, 0.3, {"law": "coulomb", "mu": 0.3}),
    "factor": lambda: _dimensionless(25.0, 0.3, {"law": "factor", "m": 1.0, "sticks": False},
                                     {"law": "piecewise_power", "alpha": 0.15, "rate1": 1e-5}),
}
ROLLING = ("rolling", "factor")  # the cases Newton's step carries the bound in


@pytest.mark.parametrize("case", sorted(CASES))
def test_friction_tangent_is_the_derivative_of_the_residual_through_the_bound(case):
    """(F(u; tau_f(u - h w)) - F(u; tau_f(u))) / h + (K + B M^-1 C) w = O(h) at an iterate of the
    direct method, w = A^-1 F, the bound frozen at u - h w: the correction is the residual's
    derivative through the bound (measured: below 1e-10 of it at h = 1e-3 and 1e-4, the forms
    being linear in the state where neither the contact set nor the cap at k switches; 3 % at
    h = 1e-2 in rolling, where the cap does). Its share of J w: 0.031, 0.073 and 0.30 of A w
    (averaged, local, rolling), which Newton's operator alone leaves out. The factor law's m k on a
    rate-sensitive metal (alpha = 0.15, m = 1 kept the factor law): 0.87 of A w, and k(rate)
    nonlinear in the state, the remainder 2.43 h of h K w from h = 1e-2 to 1e-5 (O(h^2))."""
    scene = CASES[case]()
    if case in ROLLING:  # Newton by default; a few direct iterates give its start
        scene.solver.method, scene.solver.tolerance = "direct", 1e-2
        scene.solver.max_iterations = 8
    problem = FlowProblem(scene, build_mesh(scene, MPI.COMM_WORLD))
    SecantSolver(problem).solve()
    newton = NewtonSolver(problem)
    tangent = FrictionTangent(problem, newton.forms.residual.ufl)  # Newton's own in rolling
    assert (newton.friction_tangent is not None) == (case in ROLLING)
    state = problem.friction_state
    state.freeze(problem.u)
    set_at_quadrature_points(newton.forms.dual, newton.forms.dual_reset)
    u = petsc_vec(problem.u)
    residual = newton.assemble_residual().copy()
    newton.assemble_operator()
    direction = u.duplicate()
    newton.newton.solve_system(direction)
    dolfinx.fem.petsc.set_bc(direction, problem.bcs, None, 0.0)
    tangent.assemble()
    correction, plain = direction.duplicate(), direction.duplicate()
    correction.set(0.0)
    tangent.add_to(direction, correction)
    newton.newton.A.mult(direction, plain)
    share = correction.norm() / plain.norm()
    assert 1e-3 < share < (1.0 if case == "factor" else 0.5)
    moved = problem.u.copy()
    for h in (1e-3, 1e-4):
        u.copy(petsc_vec(moved))
        petsc_vec(moved).axpy(-h, direction)
        moved.x.scatter_forward()
        state.freeze(moved)  # the bound at u - h w, the residual's velocity still u
        difference = newton.assemble_residual().copy()
        difference.axpy(-1.0, residual)
        difference.axpy(h, correction)
        # the factor law's k(rate) is not linear in the state: its Taylor remainder, O(h^2)
        bound = 3.0 * h if case == "factor" else 1e-8
        assert difference.norm() < bound * h * correction.norm()
    tangent.destroy()
    newton.destroy()

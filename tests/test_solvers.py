"""Secant iteration control: stall detection, and a clear stop where large friction makes the
modified method oscillate; the factorisation each method uses and why."""
import json

import numpy as np
import pytest
from mpi4py import MPI

from forming_fenicsx.app.cli import main
from forming_fenicsx.core.compat import set_at_quadrature_points
from forming_fenicsx.coupled.coupling import coupled_problem
from forming_fenicsx.mesh.geometry import build_mesh
from forming_fenicsx.solvers.newton import NewtonSolver
from forming_fenicsx.post.summary import scalars
from forming_fenicsx.app.run import solve_scene
from forming_fenicsx.solvers.linear import LinearSolver
from forming_fenicsx.solvers.secant import SecantSolver, diverging, stalled

from conftest import make_scene

from test_drawing import DEMOS


def test_stalled():
    assert not stalled([1.0, 0.5, 0.25, 0.1], window=2)
    assert stalled([1.0, 0.1, 0.5, 0.2], window=2)
    assert stalled([1.0, 0.5, 0.8, 0.5, 0.8], window=3)
    assert not stalled([1.0, 0.5], window=3)


def test_large_friction_oscillation_stops_with_a_clear_message(shared_tmp, capsys):
    out = shared_tmp / "mu1"
    code = main(["run", str(DEMOS / "example2_drawing.toml"), "--out", str(out), "--quiet",
                 "--set", "friction.mu=1.0",
                 "--set", "discretisation.mesh_size=0.15", "--set", "output.fields=false",
                 "--set", "output.figures=false"])
    MPI.COMM_WORLD.barrier()
    assert code == 3
    summary = json.loads((out / "summary.json").read_text())
    assert summary["converged"] is False
    assert (("oscillates" in summary["reason"] or "diverging" in summary["reason"])
            and "not be unique" in summary["reason"])
    assert summary["outer_iterations"] < summary["scene"]["solver"]["max_outer_iterations"]
    assert (out / "history.csv").exists()


def test_diverging():
    assert diverging([1.0, 0.1, 0.2, 0.4, 0.8, 1.6, 3.2], run=5, factor=10)
    assert not diverging([1.0, 0.1, 0.2, 0.4, 0.8, 0.7, 3.2], run=5, factor=10)
    assert not diverging([0.1, 0.11, 0.12, 0.13, 0.14, 0.15, 0.16], run=5, factor=10)


class _Injected:
    """Replaces LinearSolver.solve: solves, then from the third call on spoils the solution."""

    def __init__(self, monkeypatch, spoil):
        self.calls, self.spoil = 0, spoil
        self.original = LinearSolver.solve
        injected = self

        def solve(linear):
            injected.original(linear)
            injected.calls += 1
            if injected.calls >= 3:
                spoil(linear.problem.u, injected.calls)
        monkeypatch.setattr(LinearSolver, "solve", solve)
        # a spoiled iterate is no solution of its system: keep the ill-conditioning check out of
        # these tests
        monkeypatch.setattr(LinearSolver, "error_estimate", lambda linear: 0.0)


def test_nan_iterate_stops_at_once_and_keeps_the_last_finite_one(monkeypatch):
    def make_nan(u, call):
        u.x.array[:] = float("nan")
    _Injected(monkeypatch, make_nan)
    problem, result, summary = solve_scene(make_scene(discretisation={"mesh_size": 1.0}))
    assert not result.converged and result.linear_solves == 3
    assert "non-finite iterate (NaN or Inf) at outer 0, inner 2" in result.reason
    assert np.isfinite(problem.u.x.array).all()
    assert np.isfinite(summary["ram_pressure"])


def test_growing_increment_stops_at_once(monkeypatch):
    def grow(u, call):
        u.x.array[:] *= 2.0 ** (call * call)
    _Injected(monkeypatch, grow)
    result = solve_scene(make_scene(discretisation={"mesh_size": 1.0, "corner_grading": 4.0}))[1]
    assert not result.converged and result.reason.startswith("diverging")
    assert result.linear_solves < 12


def test_ill_conditioned_penalty_stops_with_a_clear_message():
    """d = 1e-13 makes K so stiff that the estimated error of a linear solve exceeds 10 delta: the
    run says so after two solves instead of stalling; d = 1e-8 converges with a small estimate
    (3e-8) and the same ram pressure as d = 1e-6."""
    stiff = solve_scene(make_scene(penalty={"d": 1e-13}, discretisation={"mesh_size": 0.5}))
    assert not stiff[1].converged and stiff[1].linear_solves <= 3
    assert (stiff[1].reason.startswith("ill-conditioned linear systems")
            and "penalty.d = 1e-13" in stiff[1].reason)
    assert stiff[2]["solve_error_estimate"] > 1e-3
    fine, reference = (solve_scene(make_scene(penalty={"d": d},
                                              discretisation={"mesh_size": 0.5}))[2]
                       for d in (1e-8, 1e-6))
    assert fine["converged"] and 1e-10 < fine["solve_error_estimate"] < 1e-6
    assert fine["ram_pressure"] == pytest.approx(reference["ram_pressure"], rel=1e-5)


def asymmetry(A) -> float:
    """||A - A^T||_F / ||A||_F of a PETSc matrix."""
    difference = A.copy()
    difference.transpose()
    difference.axpy(-1.0, A)
    return difference.norm() / A.norm()


@pytest.mark.parametrize("quantity, sections", [
    ("ram_pressure", {"discretisation": {"mesh_size": 0.5}}),
    # contact, averaged friction
    ("mean_die_pressure", {"process": {"kind": "drawing"}, "friction": {"mu": 0.2},
                           "discretisation": {"mesh_size": 0.15, "element": "Q2",
                                              "volumetric_integration": "reduced"}}),
])
def test_penalty_secant_systems_are_symmetric_and_cholesky_gives_the_lu_answer(quantity, sections):
    """The secant methods factorise the penalty system b(w; u, v) by Cholesky by default, which
    needs it symmetric: at the converged iterate (contact and friction active) ||A - A^T|| is
    rounding, and the answer is LU's after as many solves (measured: 6e-12 and 3.1e-9 apart,
    delta = 1e-6)."""
    values = {}
    for pc_type in ("cholesky", "lu"):
        scene = make_scene(**sections, solver={
            "method": "direct", "tolerance": 1e-6, "max_iterations": 1000,
            "petsc_options": {} if pc_type == "cholesky" else {"pc_type": "lu"}})
        problem = coupled_problem(scene, build_mesh(scene, MPI.COMM_WORLD))
        solver = SecantSolver(problem)
        assert solver.linear.ksp.getPC().getType() == pc_type
        assert solver.linear.positive_definite == (pc_type == "cholesky")
        result = solver.solve()
        assert result.converged
        assert asymmetry(solver.linear.A) < 1e-14
        values[pc_type] = (scalars(problem)[quantity], result.linear_solves)
        solver.destroy()
    assert values["cholesky"][1] == values["lu"][1]
    # rounding, far below delta
    assert values["cholesky"][0] == pytest.approx(values["lu"][0], rel=1e-7)


def test_mixed_secant_system_is_factorised_by_lu():
    """The mixed saddle point is symmetric but indefinite: LU by default (an L D L^T with pivoting
    failed on it in Example 2 with friction, needing ever more delayed pivots)."""
    scene = make_scene(discretisation={"mesh_size": 0.5, "formulation": "mixed"},
                       solver={"method": "direct"})
    problem = coupled_problem(scene, build_mesh(scene, MPI.COMM_WORLD))
    solver = SecantSolver(problem)
    assert solver.linear.ksp.getPC().getType() == "lu" and not solver.linear.positive_definite
    solver.destroy()


def dense(A) -> np.ndarray:
    """The whole PETSc matrix as a dense array on every rank (small meshes only)."""
    indptr, indices, values = A.getValuesCSR()
    rows = np.repeat(np.arange(*A.getOwnershipRange()), np.diff(indptr))
    parts = MPI.COMM_WORLD.allgather((rows, indices, values))
    matrix = np.zeros(A.getSize())
    for rows, columns, entries in parts:
        np.add.at(matrix, (rows, columns), entries)
    return matrix


def test_newton_operator_is_symmetric_positive_definite_under_the_cap():
    """Newton's symmetrised primal-dual operator, with contact and averaged friction active and a
    dual stress apart from tau(u) (after two Newton steps), is symmetric and positive definite, and
    shares the secant start's Cholesky factorisation. Positive definiteness rests on the cap
    |tau_h| <= sigma_p: with the dual three times tau(u) the same operator has negative
    eigenvalues."""
    scene = make_scene(process={"kind": "drawing"}, friction={"mu": 0.2},
                       discretisation={"mesh_size": 0.3, "element": "Q2",
                                       "volumetric_integration": "reduced",
                                       "averaging": "quadrature"},
                       solver={"method": "newton", "max_iterations": 2})
    problem = coupled_problem(scene, build_mesh(scene, MPI.COMM_WORLD))
    solver = NewtonSolver(problem)
    solver.solve()
    assert solver.linear.ksp.getPC().getType() == "cholesky" and solver.newton.A is solver.linear.A
    assert solver.newton.positive_definite
    solver.assemble_operator()
    assert asymmetry(solver.newton.A) < 1e-14
    matrix = dense(solver.newton.A)
    eigenvalues = np.linalg.eigvalsh((matrix + matrix.T) / 2)
    assert eigenvalues[0] > 1e-10 * eigenvalues[-1]  # measured 5e-8: clear of rounding (1e-16)
    set_at_quadrature_points(solver.forms.dual, solver.forms.dual_reset)
    solver.forms.dual.x.array[:] *= 3.0
    solver.assemble_operator()
    matrix = dense(solver.newton.A)
    assert np.linalg.eigvalsh((matrix + matrix.T) / 2)[0] < 0
    solver.destroy()


def test_mixed_newton_operator_is_factorised_by_lu():
    """With the mixed formulation Newton's operator is a symmetric saddle point: LU, as the
    secant's."""
    scene = make_scene(discretisation={"mesh_size": 0.5, "averaging": "quadrature",
                                       "formulation": "mixed"},
                       solver={"method": "newton", "max_iterations": 1})
    problem = coupled_problem(scene, build_mesh(scene, MPI.COMM_WORLD))
    solver = NewtonSolver(problem)
    solver.solve()
    assert solver.linear.ksp.getPC().getType() == "lu" and not solver.newton.positive_definite
    solver.assemble_operator()
    assert asymmetry(solver.newton.A) < 1e-14
    solver.destroy()


@pytest.mark.parametrize("method", ["direct", "newton"])
def test_solve_error_is_sampled_on_solves_1_2_4_8_and_the_last(method):
    """The iterative-refinement estimate (a pair of triangular solves) runs on the run's linear
    solves 1, 2, 4, 8, ... and on the last one of a converged run; the summary's value is the
    largest of those."""
    problem, result, summary = solve_scene(make_scene(
        discretisation={"mesh_size": 0.5, "averaging": "quadrature"}, solver={"method": method}))
    assert result.converged and len(result.history) == result.linear_solves > 8
    sampled = [number for number, record in enumerate(result.history, start=1)
               if not np.isnan(record.solve_error)]
    last = result.linear_solves
    assert sampled == sorted({2**k for k in range(last.bit_length()) if 2**k <= last} | {last})
    estimates = [result.history[n - 1].solve_error for n in sampled]
    assert all(0 < e < 1e-6 for e in estimates)
    assert summary["solve_error_estimate"] == max(estimates)

"""Secant iteration control: stall detection, and a clear stop where large friction makes the modified
method oscillate."""
import json

import numpy as np
import pytest
from mpi4py import MPI

from forming_fenicsx.cli import main
from forming_fenicsx.run import solve_scene
from forming_fenicsx.solvers import LinearSolver, diverging, stalled

from conftest import make_scene

from test_drawing import DEMOS


def test_stalled():
    assert not stalled([1.0, 0.5, 0.25, 0.1], window=2)
    assert stalled([1.0, 0.1, 0.5, 0.2], window=2)
    assert stalled([1.0, 0.5, 0.8, 0.5, 0.8], window=3)
    assert not stalled([1.0, 0.5], window=3)


def test_large_friction_oscillation_stops_with_a_clear_message(shared_tmp, capsys):
    out = shared_tmp / "mu1"
    code = main(["run", str(DEMOS / "example2_drawing.toml"), "--out", str(out), "--quiet", "--set", "friction.mu=1.0",
                 "--set", "discretisation.mesh_size=0.15", "--set", "output.fields=false",
                 "--set", "output.figures=false"])
    MPI.COMM_WORLD.barrier()
    assert code == 3
    summary = json.loads((out / "summary.json").read_text())
    assert summary["converged"] is False
    assert ("oscillates" in summary["reason"] or "diverging" in summary["reason"]) and "not be unique" in summary["reason"]
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
        # a spoiled iterate is no solution of its system: keep the ill-conditioning check out of these tests
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
    result = solve_scene(make_scene(discretisation={"mesh_size": 1.0}))[1]
    assert not result.converged and result.reason.startswith("diverging")
    assert result.linear_solves < 12


def test_ill_conditioned_penalty_stops_with_a_clear_message():
    """d = 1e-13 makes K so stiff that the estimated error of a linear solve exceeds 10 delta: the run
    says so after two solves instead of stalling; d = 1e-8 converges with a small estimate (3e-8) and
    the same ram pressure as d = 1e-6."""
    stiff = solve_scene(make_scene(penalty={"d": 1e-13}, discretisation={"mesh_size": 0.5}))
    assert not stiff[1].converged and stiff[1].linear_solves <= 3
    assert stiff[1].reason.startswith("ill-conditioned linear systems") and "penalty.d = 1e-13" in stiff[1].reason
    assert stiff[2]["solve_error_estimate"] > 1e-3
    fine, reference = (solve_scene(make_scene(penalty={"d": d}, discretisation={"mesh_size": 0.5}))[2]
                       for d in (1e-8, 1e-6))
    assert fine["converged"] and 1e-10 < fine["solve_error_estimate"] < 1e-6
    assert fine["ram_pressure"] == pytest.approx(reference["ram_pressure"], rel=1e-5)

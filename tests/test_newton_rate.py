"""The rate rule that lets a rolling run with the friction bound's derivative end (newton.py,
_rate_settled), the stall it suspends, and the message of a run it holds to the end."""
import math
import sys
from types import SimpleNamespace

import pytest

from forming_fenicsx.solvers import messages
from forming_fenicsx.solvers.newton import NewtonSolver

DELTA = 1e-4


def _solver(steps: list[tuple[bool, bool]], tangent: bool = True) -> NewtonSolver:
    """A NewtonSolver holding only what the rule reads: the steps' kinds (frozen, full)."""
    solver = NewtonSolver.__new__(NewtonSolver)
    solver.friction_tangent = object() if tangent else None
    solver._rate_rule = tangent
    solver.settings = SimpleNamespace(tolerance=DELTA, stall_window=40)
    solver._steps, solver._rate, solver._met = steps, math.nan, False
    return solver


FROZEN, NEWTON = (True, True), (False, True)


def test_a_creeping_run_of_frozen_steps_does_not_end():
    """The 2 -> 1.4 mm strip's frozen steps at its stop: 3.1e-5, 2.2e-5, 2.0e-5 (rho 0.92) put
    the answer 2.3e-4 away, above delta, though each met it."""
    solver = _solver([NEWTON] + [FROZEN] * 3)
    assert not solver._rate_settled([1.354e-3, 3.078e-5, 2.186e-5, 2.012e-5])
    assert solver._rate == pytest.approx(2.012e-5 / 2.186e-5, rel=1e-12)
    assert 2.012e-5 * solver._rate / (1 - solver._rate) > DELTA


def test_frozen_steps_that_fall_fast_end_the_run():
    solver = _solver([FROZEN] * 3)
    assert solver._rate_settled([1e-3, 2e-4, 4e-5])  # rho 0.2: 1e-5 away
    assert solver._rate == pytest.approx(0.2, rel=1e-12)


@pytest.mark.parametrize("steps", [[NEWTON, FROZEN, FROZEN], [FROZEN, (True, False), FROZEN],
                                   [FROZEN, FROZEN]])
def test_a_frozen_step_ends_a_run_only_after_a_run_of_full_frozen_steps(steps):
    """A frozen step after a Newton step, or after a cut one, gives no rate."""
    solver = _solver(steps)
    assert not solver._rate_settled([1e-3, 1e-5, 1e-7][-len(steps):])
    assert math.isnan(solver._rate)


def test_rising_frozen_steps_do_not_end_the_run():
    assert not _solver([FROZEN] * 3)._rate_settled([1e-5, 2e-5, 3e-5])


def test_a_newton_step_ends_the_run_only_after_a_step_taken_in_full():
    """The 5 -> 4 mm strip met delta on a Newton step after two cut ones, 0.7 % low."""
    increments = [6.2e-4, 2.4e-3, 4.4e-5]
    assert not _solver([NEWTON, (False, False), NEWTON])._rate_settled(increments)
    assert not _solver([NEWTON])._rate_settled(increments[-1:])
    assert _solver([(False, False), NEWTON, NEWTON])._rate_settled(increments)


def test_without_the_bound_s_derivative_delta_alone_ends_the_run():
    assert _solver([FROZEN] * 3, tangent=False)._rate_settled([1e-5, 2e-5, 3e-5])


def test_no_stall_once_the_increments_have_met_delta():
    solver = _solver([])
    assert solver._stall_window() == 40
    solver._met = True
    assert solver._stall_window() == sys.maxsize


def test_the_slow_message_gives_the_distance_or_says_there_is_none():
    text = messages.slow_convergence(200, [2.2e-5, 2.0e-5], 0.9, DELTA)
    assert "not converged in 200 Newton steps" in text
    assert "fall by only 0.900 a step" in text and "1.8e-04" in text  # 2e-5 * 0.9 / 0.1
    assert "solver.max_iterations" in text
    for rho in (math.nan, 1.2):
        assert "do not fall steadily" in messages.slow_convergence(200, [1e-5], rho, DELTA)

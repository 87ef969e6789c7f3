"""The nonlinear iteration a scene's solver.method names."""
from __future__ import annotations

from typing import Any, Callable

from forming_fenicsx.fem.forms import FlowProblem
from forming_fenicsx.solvers.newton import NewtonSolver
from forming_fenicsx.solvers.secant import SecantSolver


def solver_for(problem: FlowProblem, petsc_options: dict[str, Any] | None = None,
               balance: Callable[[], float] | None = None,
               stop: Callable[[], str | None] | None = None) -> SecantSolver:
    """Newton's method after secant_start direct iterates (newton.py) for solver.method "newton",
    else the secant-modulus iteration, direct (3.13) or modified (3.33) (secant.py); ``balance``
    and ``stop`` as SecantSolver takes them."""
    method = NewtonSolver if problem.scene.solver.method == "newton" else SecantSolver
    return method(problem, petsc_options, balance=balance, stop=stop)

"""The flow through the workpiece's boundary: the throughput through Gamma1 and the flux-weighted
means of a field over the outflow (the product) or the inflow (the stock)."""
from __future__ import annotations

import ufl
from ufl.core.expr import Expr

from forming_fenicsx.core.roles import ROLES
from forming_fenicsx.fem.forms import FlowProblem
from forming_fenicsx.post.integrals import integrate


def throughput(problem: FlowProblem) -> float:
    """|flux through Gamma1|: the volume the model forms per unit time (per unit width of the
    half model in plane strain)."""
    return abs(integrate(problem, ufl.dot(problem.u, problem.n)
                         * problem.ds(ROLES["gamma1_velocity"])))


def _flux_weight(problem: FlowProblem, leaving: bool) -> Expr:
    """|u.n| where the flow leaves (or enters) the workpiece at more than 30 degrees to the
    boundary, else 0 (die walls and free surfaces, which the flow follows, carry none)."""
    flux = ufl.dot(problem.u, problem.n) if leaving else -ufl.dot(problem.u, problem.n)
    return ufl.conditional(ufl.gt(flux, 0.5 * ufl.sqrt(ufl.dot(problem.u, problem.u))), flux, 0.0)


def mean_through(problem: FlowProblem, field: Expr, leaving: bool = True) -> float:
    """The flux-weighted mean of a field leaving (or entering) the workpiece,
    int f |u.n| / int |u.n| over the outflow (inflow): the mean of the product (of the stock)."""
    weight = _flux_weight(problem, leaving)
    return (integrate(problem, field * weight * problem.ds)
            / integrate(problem, weight * problem.ds))


def mean_strain_through(problem: FlowProblem, leaving: bool = True) -> float:
    """The mean equivalent strain of the product (or of the stock, ``leaving`` False)."""
    return mean_through(problem, problem.strain, leaving)

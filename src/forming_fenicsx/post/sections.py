"""Mean stresses over cross-sections x = const of the workpiece, sampled at Gauss points.

The axial force through a section is F(x) = int_0^R sigma_xx(x, y) w(y) dy with w = 2 pi y for a
round bar and w = 1 for a strip (per unit width of the half model); its mean stress F / section(R)
is what Sachs' slab method and Shield's cone flow predict, section by section. The penalty's
hydrostatic stress enters as element means taken with its own (reduced) rule: pointwise, div u/d
carries the spurious pressure modes that the reduced rule does not see.
"""
from __future__ import annotations

import dolfinx.fem
import numpy as np

from forming_fenicsx.core.compat import function_space
from forming_fenicsx.fem.forms import FlowProblem
from forming_fenicsx.mesh.points import PointValues
from forming_fenicsx.fem.projection import cell_means
from forming_fenicsx.fem.projection import project_discontinuous


def values_at(problem: FlowProblem, expr, points: np.ndarray, degree: int) -> np.ndarray:
    """A scalar UFL expression at the points (N, 2), projected element by element onto
    discontinuous Q_degree (L2, with the problem's full rule) and evaluated where each point lies;
    the same array on every rank (collective). A point outside the workpiece raises ValueError."""
    target = dolfinx.fem.Function(function_space(problem.mesh, "DP", degree))
    project_discontinuous(expr, target, problem.full_degree)
    values = PointValues([target]).evaluate(points)[0][:, 0]
    if np.isnan(values).any():
        outside = points[np.isnan(values)][0]
        raise ValueError(f"the point ({outside[0]:.6g}, {outside[1]:.6g}) is not in the workpiece")
    return values


def mean_axial_stress(problem: FlowProblem, x: float, radius: float, points: int = 24) -> float:
    """F(x)/section(R): sigma_xx over the section x = const, 0 < y < ``radius`` (the workpiece's
    half-thickness or radius there), by Gauss-Legendre with ``points`` points (weight 2 pi y when
    axisymmetric)."""
    nodes, weights = np.polynomial.legendre.leggauss(points)
    y = 0.5 * radius * (nodes + 1)
    c = problem.coordinates
    hydrostatic = cell_means(problem.mesh, problem.hydrostatic_stress(), "hydrostatic_stress",
                             problem.volumetric_degree)
    deviator = 2.0 / 3.0 * problem.secant_coefficient() * c.deviatoric(
        problem.strain_rate(problem.u))
    axial = values_at(problem, deviator[0, 0] + hydrostatic,
                      np.column_stack([np.full(points, x), y]), problem.scene.discretisation.degree)
    weight = 2 * np.pi * y if c.axisymmetric else np.ones(points)
    force = 0.5 * radius * float(np.sum(weights * weight * axial))
    return force / c.section(radius)

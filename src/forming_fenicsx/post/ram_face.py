"""The paper's p_av of Example 1: the hydrostatic pressure on the ram face Gamma1, and its model
from the ram pressure for the zone at the ram that the penalty (3.4) compresses."""
from __future__ import annotations

from typing import Any

import numpy as np

from forming_fenicsx.core.roles import ROLES
from forming_fenicsx.fem.forms import FlowProblem
from forming_fenicsx.fem.projection import cell_means
from forming_fenicsx.post.integrals import integrate


def mean_hydrostatic_pressure(problem: FlowProblem) -> float:
    """The paper's p_av: -sigma_H averaged over the ram face Gamma1, sigma_H taken as element means.

    The elements along Gamma1 lie in the rigid zone at the ram, where sigma_H is close to the
    ram pressure; the mean uses the volumetric term's own quadrature.
    """
    pressure = cell_means(problem.mesh, -problem.hydrostatic_stress(), "pressure",
                          problem.volumetric_degree)
    ds = problem.ds(ROLES["gamma1_velocity"])
    return integrate(problem, pressure * ds) / integrate(problem, 1.0 * ds)


def ram_face_pressure_model(law: Any, d: float, ram_pressure: float) -> float:
    """p_av on Gamma1 predicted from the ram pressure, for the zone at the ram that the penalty
    compresses.

    Beside the ram the container holds u_y ~ 0, so the penalty's volumetric rate e = d sigma_H is a
    uniaxial-strain compression of equivalent rate 2/3 |e| and s_xx = 4/9 G e. Below rate1 of (4.5)
    G = sigma_p(rate1)/rate1 and p_ram = p_av (1 + 4/9 G d); above it the zone yields and
    p_ram = p_av + 2/3 sigma_p(2/3 d p_av). As d -> 0, p_av -> p_ram.
    """
    stiff = law.secant(np.array([law.rate1]))[0]
    p_av = ram_pressure / (1 + 4 / 9 * stiff * d)
    if 2 / 3 * d * p_av < law.rate1:
        return p_av
    p_av = ram_pressure
    for _ in range(50):  # fixed point; sigma_p barely depends on the rate here
        p_av = ram_pressure - 2 / 3 * law.flow_stress(np.array([2 / 3 * d * p_av]))[0]
    return p_av

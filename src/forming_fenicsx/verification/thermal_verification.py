"""Problems with exact solutions for the heat equation of thermal.py (docs/thermal.md):

- the 1-D advection-diffusion layer u T' = k T'' on (0, 1), T(0) = 0, T(1) = 1, at Peclet numbers
  Pe = u/k up to 1e5, on a strip one cell thick;
- manufactured solutions in both symmetries with a divergence-free two-dimensional flow, tool and
  inflow conditions, for the orders of convergence of Q1 and Q2;
- the adiabatic limit of the smooth cone (axisymmetric) and wedge (plane strain) radial flows of
  reference section 1: no conduction, no tool contact; the mixing-cup exit temperature rises by
  beta W/(rho c), W = int sigma d(eps) the plastic work per unit volume.
"""
from __future__ import annotations

import math

import dolfinx.fem
import dolfinx.mesh
import numpy as np
import ufl
from mpi4py import MPI

from forming_fenicsx.core.compat import GHOST_MODE, colliding_cells, function_space
from forming_fenicsx.physics.coordinates import CoordinateSystem
from forming_fenicsx.coupled.thermal import (FrictionHeat, HeatExchange, TemperatureField,
                                             ThermalMaterial)

LEFT, RIGHT, BOTTOM, TOP = 1, 2, 3, 4


def rectangle(cells: tuple[int, int], size: tuple[float, float], degree: int,
              comm: MPI.Comm = MPI.COMM_WORLD):
    """[0, size_x] x [0, size_y] in quadrilaterals with its sides tagged LEFT, RIGHT, BOTTOM, TOP,
    and the vector Lagrange space of ``degree`` for a prescribed velocity."""
    mesh = dolfinx.mesh.create_rectangle(comm, [np.zeros(2), np.array(size, dtype=float)],
                                         list(cells), dolfinx.mesh.CellType.quadrilateral,
                                         ghost_mode=GHOST_MODE)
    sides = ((LEFT, lambda x: np.isclose(x[0], 0.0)), (RIGHT, lambda x: np.isclose(x[0], size[0])),
             (BOTTOM, lambda x: np.isclose(x[1], 0.0)), (TOP, lambda x: np.isclose(x[1], size[1])))
    facets = [dolfinx.mesh.locate_entities_boundary(mesh, 1, where) for _, where in sides]
    indices = np.concatenate(facets)
    values = np.concatenate([np.full(len(f), tag, dtype=np.int32)
                             for (tag, _), f in zip(sides, facets)])
    order = np.argsort(indices)  # meshtags wants sorted facets; each facet lies on one side
    tags = dolfinx.mesh.meshtags(mesh, 1, indices[order].astype(np.int32), values[order])
    return mesh, tags, function_space(mesh, "P", degree, (2,))


def layer_exact(peclet: float, x):
    """(e^(Pe x) - 1)/(e^Pe - 1), written to stay finite at Pe = 1e5 (numpy)."""
    return (np.exp(peclet * (x - 1)) - math.exp(-peclet)) / (1 - math.exp(-peclet))


def sample(function: dolfinx.fem.Function, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The values of a scalar Function at those of the points (shape (N, 3)) that lie in this rank's
    cells, and the points' indices."""
    cells = colliding_cells(function.function_space.mesh, points)
    found = np.flatnonzero(cells >= 0)
    return function.eval(points[found], cells[found]).ravel(), found


def layer(peclet: float, cells: int, degree: int, comm: MPI.Comm = MPI.COMM_WORLD
          ) -> dict[str, float]:
    """u T' = k T'' on (0, 1) with u = 1, k = 1/Pe, T(0) = 0 and T(1) = 1 fixed, on ``cells`` square
    cells in a row (the cell Peclet number u h/(2k) = Pe/(2 cells)). Sampled at 20 points per cell
    along the strip's middle line: overshoot max T - 1, undershoot -min T, and the largest error
    outside the last cell (where the exact layer is not resolved when the cell Peclet number is
    large) and where x <= 1/2."""
    mesh, tags, V = rectangle((cells, 1), (1.0, 1.0 / cells), 1, comm)
    u = dolfinx.fem.Function(V)
    u.x.array[0::2] = 1.0
    field = TemperatureField(u, CoordinateSystem(mesh), tags, ThermalMaterial(1.0, 1.0 / peclet),
                             0.0, degree, fixed={LEFT: 0.0, RIGHT: 1.0})
    x = np.linspace(0.0, 1.0, 20 * cells + 1)
    points = np.column_stack([x, np.full_like(x, 0.5 / cells), np.zeros_like(x)])
    values, found = sample(field.solve(u), points)
    error = np.abs(values - layer_exact(peclet, x[found]))
    field.destroy()

    def largest(array) -> float:
        return comm.allreduce(float(array.max(initial=-np.inf)), op=MPI.MAX)
    return {"overshoot": largest(values - 1.0), "undershoot": largest(-values),
            "error_outside_layer": largest(error[x[found] < 1 - 1.0 / cells - 1e-12]),
            "error_first_half": largest(error[x[found] <= 0.5]),
            "cell_peclet": peclet / (2 * cells)}


# -- manufactured solutions ---------------------------------------------------------------------
# On the unit square, x the flow (axis) direction, y the half-thickness (radius): the flow
# u = (1 + a sin(pi x), -y a pi cos(pi x) / m) (m = 2 axisymmetric, 1 plane), divergence-free in its
# symmetry, entering at x = 0, leaving at x = 1, along the symmetry line y = 0, and entering through
# y = 1 at less than 30 degrees (a tool face, not an inflow); T has dT/dn = 0 on x = 0 (Danckwerts's
# inflow condition holds with T_in = T), x = 1 (the insulated exit) and y = 0 (the symmetry line);
# the top is a tool face with heat exchange and friction heat whose ambient temperature makes T
# exact there: kappa dT/dy = -h (T - T_a) + f q_f.
MANUFACTURED = {"amplitude": 0.15, "heat_capacity": 1.0, "conductivity": 0.02, "h": 2.0,
                "heat_fraction": 0.9, "share": 0.6}


def manufactured_velocity(symmetry: str, x, cos=np.cos, sin=np.sin):
    """The flow of the manufactured problem (numpy, or UFL with cos=ufl.cos, sin=ufl.sin)."""
    a, m = MANUFACTURED["amplitude"], 2 if symmetry == "axisymmetric" else 1
    return [1 + a * sin(math.pi * x[0]), -x[1] * a * math.pi * cos(math.pi * x[0]) / m]


def manufactured_temperature(x):
    """T of the manufactured problem (UFL): dT/dn = 0 on x = 0, x = 1 and y = 0."""
    return (1 + 0.5 * ufl.cos(math.pi * x[0]) * ufl.cos(math.pi * x[1] / 2)
            + 0.25 * ufl.cos(2 * math.pi * x[0]) * x[1] ** 2)


def friction_power(v, T):
    """A friction power that depends on the velocity, for the manufactured tool face."""
    return 1 + ufl.dot(v, v)


def manufactured(symmetry: str, degree: int, cells: int, comm: MPI.Comm = MPI.COMM_WORLD
                 ) -> dict[str, float]:
    """The manufactured problem on cells x cells Q_degree elements (the velocity interpolated in
    Q_degree): the L2 and H1-seminorm errors of T in the weighted measure (2 pi y when
    axisymmetric) relative to T's norms, and the heat balance (TemperatureField.energy_balance)."""
    mesh, tags, V = rectangle((cells, cells), (1.0, 1.0), degree, comm)
    coordinates = CoordinateSystem(mesh, symmetry)
    u = dolfinx.fem.Function(V)
    u.interpolate(lambda x: np.vstack(manufactured_velocity(symmetry, x)))
    x = ufl.SpatialCoordinate(mesh)
    exact_u = ufl.as_vector(manufactured_velocity(symmetry, x, ufl.cos, ufl.sin))
    T = manufactured_temperature(x)
    rho_c, kappa, h = (MANUFACTURED[k] for k in ("heat_capacity", "conductivity", "h"))
    beta, share = MANUFACTURED["heat_fraction"], MANUFACTURED["share"]
    source = rho_c * ufl.dot(exact_u, ufl.grad(T)) - coordinates.divergence(kappa * ufl.grad(T))
    ambient = T + (kappa * T.dx(1) - share * friction_power(exact_u, T)) / h
    field = TemperatureField(
        u, coordinates, tags, ThermalMaterial(rho_c, kappa, beta), T, degree,
        plastic_power=lambda v, T: source / beta,
        exchanges=(HeatExchange("tool", (TOP,), h, ambient),),
        friction=FrictionHeat(friction_power, (TOP,), share), initial_temperature=1.0,
        quadrature_degree=2 * degree + 4)
    field.settle(u)
    error = field.T - T
    result = {"l2": math.sqrt(field.integral(error**2, field.dx) / field.integral(T**2, field.dx)),
              "h1": math.sqrt(field.integral(ufl.dot(ufl.grad(error), ufl.grad(error)), field.dx)
                              / field.integral(ufl.dot(ufl.grad(T), ufl.grad(T)), field.dx)),
              **field.energy_balance()}
    field.destroy()
    return result


def orders(errors: list[float]) -> np.ndarray:
    """Observed orders between successive meshes, each twice as fine as the one before."""
    errors = np.asarray(errors)
    return np.log2(errors[:-1] / errors[1:])


# -- the adiabatic limit ------------------------------------------------------------------------
ADIABATIC = {"n": 0.2, "heat_capacity": 2.5, "heat_fraction": 0.9, "inflow_temperature": 700.0}


def adiabatic(symmetry: str, degree: int, cells: int, softening: float | None = None,
              comm: MPI.Comm = MPI.COMM_WORLD) -> dict[str, float]:
    """The exact radial flow through the smooth cone (axisymmetric) or wedge (plane strain) of
    verification.RADIAL, interpolated in Q_degree on the isoparametric sector mesh, with the Norton
    law sigma = K rate^n (plastic power P = K rate^(n+1)), kappa = 0 and no tool contact: along
    every streamline rho c dT/dt = beta P, so T rises by beta W/(rho c) with W = int sigma d(eps) =
    sigma_rr(rho1) - sigma_rr(rho0), the same on every streamline. With ``softening`` theta the
    flow stress falls as exp(-(T - T_in)/theta), a temperature-dependent source coupled by freezing
    (relaxation 1/2) until the change is below 1e-10: exp(dT/theta) - 1 = beta W/(rho c theta).
    Returns the mixing-cup exit rise int (T - T_in) u.n ds / int u.n ds over the exit cap, the
    exact rise, the freezes and the heat balance (without softening, the global one too: the
    drawing power W times the throughput against the heat carried out and the work stored)."""
    from forming_fenicsx.core.roles import ROLES
    from forming_fenicsx.verification.verification import (
        RADIAL, radial_stress_rise, radial_velocity, sector_mesh)

    forming_mesh = sector_mesh(cells, degree, comm)
    mesh = forming_mesh.mesh
    coordinates = CoordinateSystem(mesh, symmetry)
    u = dolfinx.fem.Function(function_space(mesh, "P", degree, (2,)))
    u.interpolate(lambda x: np.vstack(radial_velocity(symmetry, x)))
    n, rho_c, beta, T_in = (ADIABATIC[k] for k in
                            ("n", "heat_capacity", "heat_fraction", "inflow_temperature"))

    def plastic_power(v, T):
        power = RADIAL["K"] * coordinates.equivalent_strain_rate(v) ** (n + 1)
        return power if softening is None else power * ufl.exp(-(T - T_in) / softening)
    field = TemperatureField(u, coordinates, forming_mesh.facet_tags,
                             ThermalMaterial(rho_c, 0.0, beta), T_in, degree,
                             plastic_power=plastic_power)
    freezes, heating = 0, beta * radial_stress_rise(symmetry, n) / rho_c
    if softening is None:
        field.settle(u)
    else:
        while field.change(u) > 1e-10 and freezes < 200:
            field.freeze(u)
            freezes += 1
    exit_cap = field.ds(ROLES["gamma1_velocity"])
    flux = ufl.dot(field.velocity, field.n)
    throughput = field.integral(flux, exit_cap)
    rise = field.integral((field.T - T_in) * flux, exit_cap) / throughput
    exact = heating if softening is None else softening * math.log1p(heating / softening)
    # the drawing power of the frictionless die: the exit stress times the throughput
    drawing_power = radial_stress_rise(symmetry, n) * throughput if softening is None else None
    result = {"exit_rise": rise, "exact_rise": exact, "freezes": freezes, "solves": field.solves,
              **field.energy_balance(drawing_power)}
    field.destroy()
    return result

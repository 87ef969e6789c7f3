"""Steady heat transfer in the workpiece (reference section 4):

    rho c u . grad T = div(kappa grad T) + beta sigma:rate                     in the workpiece,

div and grad those of the coordinate system (the axisymmetric div carries the 1/y d(y .)/dy term;
coordinates.py). Boundary conditions, n the outward normal, (u.n)^- = max(-u.n, 0):
- inflow, where the velocity enters at more than 30 degrees to the boundary (as the strain's
  transport; a die wall or free surface that the flow follows is not an inflow): Danckwerts'
  condition kappa dT/dn = rho c (u.n)^- (T_in - T), the heat that arrives is the heat carried in at
  T_in (T = T_in as kappa -> 0), imposed weakly;
- heat exchange with a tool (die, container) or the air: -kappa dT/dn = h (T - T_a);
- friction heat on the die interface, the power q_f = tau . Delta v per unit area, a share f of it
  into the workpiece (the rest into the die): kappa dT/dn = f q_f;
- optionally a fixed temperature (strongly); every other boundary is insulated (the symmetry line,
  the exit).

Weak form, W the measure weight (2 pi y when axisymmetric), R(T) the residual of the equation,
  int (rho c u.grad T - beta P) w W dx + int kappa grad T . grad w W dx
  + int tau (u . grad w) R(T) W dx,       R(T) = rho c u.grad T - div(kappa grad T) - beta P,
  + int rho c (u.n)^- (T - T_in) w W ds + sum int h (T - T_a) w W ds - int f q_f w W ds = 0:
Galerkin plus SUPG (streamline-upwind Petrov-Galerkin), consistent: the exact T makes R vanish,
the second derivatives of the trial function included (they matter for Q2 and on distorted Q1).
tau is the doubly asymptotic approximation of the optimal (coth(Pe) - 1/Pe) h/(2|u|),
  tau = [(2 |u| / h)^2 + (12 kappa / (rho c h^2))^2]^(-1/2),   h = |u| / (p |J^-1 u|),
h the length of the cell along the streamline (J the cell map of the reference square [0, 1]^2)
over the degree p: h/(2|u|) when advection dominates (cell Peclet >> 1), h^2 rho c/(12 kappa) when
diffusion does; it stays finite with kappa = 0 (pure advection: the adiabatic limit).

Units: a consistent system (scene units L, T, S); heat is work, S L^3 (with mm, s, MPa: mJ = N mm).
Then rho c is in S/K (MPa/K = N/(mm^2 K): aluminium's 2800 kg/m^3 x 1064 J/(kg K) = 2.98 MPa/K),
kappa in S L^2/(T K) (N/(s K), numerically W/(m K): 201 for aluminium), h in S L/(T K)
(N/(mm s K) = 1000 W/(m^2 K)), the plastic power density sigma:rate in S/T (MPa/s = mW/mm^3) and
the friction power in S L/T (N/(mm s)). Temperatures in kelvin when a law reads them
(Zener-Hollomon).

One linear solve (MUMPS LU, option prefix ``thermal_``) per velocity (and frozen temperature, when
the heat source depends on it); docs/thermal.md has the measured orders, overshoots and balances.
"""
from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import dolfinx.fem
import dolfinx.mesh
import numpy as np
import ufl
from petsc4py import PETSc

from forming_fenicsx.core.anderson import AndersonMixing
from forming_fenicsx.core.compat import function_space
from forming_fenicsx.coupled.cached_solve import CachedSolve
from forming_fenicsx.fem.linear_problem import DIRECT, LinearProblem
from forming_fenicsx.physics.coordinates import CoordinateSystem

PREFIX = "thermal"
INFLOW_SINE = 0.5  # the flow enters at more than 30 degrees to the boundary (sin 30 = 0.5)

# A field of the velocity v and the frozen temperature T (the Functions the temperature's forms
# read): a UFL expression, e.g. the flow stress sigma(rate(v), T) times rate(v)
FieldExpression = Callable[[dolfinx.fem.Function, dolfinx.fem.Function], ufl.core.expr.Expr]


@dataclass(frozen=True)
class ThermalMaterial:
    """rho c (S/K), kappa (S L^2/(T K)) and beta, the fraction of the plastic work turned into heat
    (0.9 to 0.95 for metals, reference section 4)."""

    heat_capacity: float
    conductivity: float
    heat_fraction: float = 0.9


@dataclass(frozen=True)
class HeatExchange:
    """-kappa dT/dn = h (T - temperature) on the facets tagged ``tags`` (a tool or the air); the
    temperature may be a number or a UFL expression."""

    name: str
    tags: tuple[int, ...]
    h: float
    temperature: float | ufl.core.expr.Expr


@dataclass(frozen=True)
class FrictionHeat:
    """The friction power per unit area q_f(v, T) on the facets tagged ``tags`` (tau . Delta v of
    the flow's friction law), ``workpiece_share`` of it into the workpiece (1/2 unless given; see
    effusivity_share), the rest into the die."""

    power: FieldExpression
    tags: tuple[int, ...]
    workpiece_share: float = 0.5


def effusivity_share(workpiece: ThermalMaterial, die: ThermalMaterial) -> float:
    """The workpiece's share of the friction heat by Blok's rule for two bodies in sliding contact,
    e_w / (e_w + e_d) with the effusivities e = sqrt(kappa rho c) (aluminium on H13 steel: 0.72)."""
    e_w, e_d = (math.sqrt(m.conductivity * m.heat_capacity) for m in (workpiece, die))
    return e_w / (e_w + e_d)


def inflow_rate(v, n):
    """(u.n)^- where the velocity enters at more than 30 degrees to the boundary, else 0."""
    entering = -ufl.dot(v, n)
    return ufl.conditional(ufl.gt(entering, INFLOW_SINE * ufl.sqrt(ufl.dot(v, v))), entering, 0.0)


def supg_parameter(v, diffusivity: float, degree: int, mesh):
    """tau = [(2|v|/h)^2 + (12 diffusivity/h^2)^2]^(-1/2), h = |v| / (p |J^-1 v|) the cell length
    along the streamline over the degree (sqrt|det J| / p where v = 0); 0 where both terms
    vanish."""
    speed = ufl.sqrt(ufl.dot(v, v))
    along = ufl.JacobianInverse(mesh) * v
    reference_speed = ufl.sqrt(ufl.dot(along, along))
    h = ufl.conditional(ufl.gt(reference_speed, 0.0), speed / (reference_speed + 1e-300),
                        ufl.sqrt(abs(ufl.JacobianDeterminant(mesh)))) / degree
    inverse = ufl.sqrt((2 * speed / h) ** 2 + (12 * diffusivity / h**2) ** 2)
    return ufl.conditional(ufl.gt(inverse, 0.0), 1.0 / (inverse + 1e-300), 0.0)


class TemperatureField:
    """The steady temperature T (Lagrange of ``degree``) of a velocity field, and the
    frozen-coefficient protocol (frozen.py) that couples it to the flow: ``freeze(u)`` solves the
    heat equation with u (and the source at the current frozen T) and moves T ``relaxation`` of the
    way to it; ``change(u)`` is ||T(u) - T|| / ||T(u) - T_0|| in the weighted L2 norm: relative to
    the temperature change the flow makes (T_0 the initial temperature; in kelvin a change of T
    itself would be a few 1e-3 of the rise's size).

    ``plastic_power(v, T)``: sigma:rate of the velocity v at the frozen temperature T (flow stress
    times equivalent rate), UFL; beta of ``material`` times it is the heat source.
    ``inflow_temperature`` T_in: a number or UFL; T starts at ``initial_temperature``, a number
    (T_in unless given), which is also the reference of the advected heat (energy_balance).
    ``fixed``: facet tag -> temperature imposed strongly (none in a forming scene: every condition
    there is a flux; the 1-D verification fixes both ends).
    """

    name = "temperature"
    coupled = True  # a field of its own, unlike the friction bound (FlowProblem.coupled_settled)
    tangent = False  # Newton's step does not carry its derivative

    def __init__(self, u: dolfinx.fem.Function, coordinates: CoordinateSystem, facet_tags,
                 material: ThermalMaterial, inflow_temperature, degree: int,
                 plastic_power: FieldExpression | None = None,
                 exchanges: tuple[HeatExchange, ...] = (), friction: FrictionHeat | None = None,
                 fixed: dict[int, float] | None = None, initial_temperature: float | None = None,
                 quadrature_degree: int | None = None, relaxation: float = 0.5,
                 options: dict | None = None, temperature: dolfinx.fem.Function | None = None,
                 anderson_depth: int = 4):
        mesh = u.function_space.mesh
        self.mesh, self.material, self.coordinates = mesh, material, coordinates
        self.exchanges, self.friction = exchanges, friction
        self.inflow_temperature = inflow_temperature
        self.space = function_space(mesh, "P", degree)
        start = inflow_temperature if initial_temperature is None else initial_temperature
        # the flow's own T when a flow law reads it (forms.py builds it first)
        self.T = temperature or dolfinx.fem.Function(self.space, name="temperature")
        self.reference_temperature = float(start)  # a number: the inflow's unless given
        self.T.x.array[:] = self.reference_temperature
        self._candidate = dolfinx.fem.Function(self.space)
        self.velocity = dolfinx.fem.Function(u.function_space)  # the velocity T belongs to
        v = self.velocity
        T, w = ufl.TrialFunction(self.space), ufl.TestFunction(self.space)
        metadata = {"quadrature_degree": quadrature_degree or 2 * degree + 2}
        self.dx = coordinates.measure(ufl.dx(domain=mesh, metadata=metadata))
        self.ds = coordinates.measure(ufl.Measure("ds", domain=mesh, subdomain_data=facet_tags,
                                                  metadata=metadata))
        self.n = ufl.FacetNormal(mesh)
        rho_c = material.heat_capacity
        # a Constant, so that kappa = 0 (pure advection) keeps the diffusion terms' shapes in UFL
        kappa = dolfinx.fem.Constant(mesh, PETSc.ScalarType(material.conductivity))
        self.inflow = inflow_rate(v, self.n)
        self.plastic_power = (plastic_power(v, self.T) if plastic_power is not None
                              else ufl.as_ufl(0.0))
        self.source = material.heat_fraction * self.plastic_power
        tau = supg_parameter(v, kappa / rho_c, degree, mesh)
        streamline = tau * ufl.dot(v, ufl.grad(w))
        advection = rho_c * ufl.dot(v, ufl.grad(T))
        residual = advection - coordinates.divergence(kappa * ufl.grad(T))
        a = ((advection * w + kappa * ufl.dot(ufl.grad(T), ufl.grad(w)) + residual * streamline)
             * self.dx + rho_c * self.inflow * T * w * self.ds)
        zero = dolfinx.fem.Constant(mesh, PETSc.ScalarType(0.0))  # keeps L a form when data are 0
        L = ((self.source * (w + streamline) + zero * w) * self.dx
             + rho_c * self.inflow * inflow_temperature * w * self.ds)
        for exchange in exchanges:
            for tag in exchange.tags:
                a += exchange.h * T * w * self.ds(tag)
                L += exchange.h * exchange.temperature * w * self.ds(tag)
        if friction is not None:
            self.friction_power = friction.power(v, self.T)
            for tag in friction.tags:
                L += friction.workpiece_share * self.friction_power * w * self.ds(tag)
        fdim = mesh.topology.dim - 1
        self.bcs = [dolfinx.fem.dirichletbc(
            PETSc.ScalarType(value), dolfinx.fem.locate_dofs_topological(
                self.space, fdim, facet_tags.indices[facet_tags.values == tag]), self.space)
            for tag, value in (fixed or {}).items()]
        self._system = LinearProblem(dolfinx.fem.form(a), [dolfinx.fem.form(L)], self._candidate,
                                     self.bcs, prefix=PREFIX, options={**DIRECT, **(options or {})},
                                     fallback=True)
        self._cached = CachedSolve(self._system, self.velocity, self.T, "temperature", (self.T,))
        self._mixing = AndersonMixing(mesh.comm, self.space.dofmap.index_map.size_local,
                                      anderson_depth, relaxation)
        self._norm = dolfinx.fem.form((self._candidate - self.reference_temperature) ** 2 * self.dx)
        self._difference = dolfinx.fem.form((self._candidate - self.T) ** 2 * self.dx)

    @property
    def solves(self) -> int:
        """The heat equation's linear solves so far."""
        return self._cached.solves

    def solve(self, u: dolfinx.fem.Function) -> dolfinx.fem.Function:
        """T of the velocity u with the source at the frozen T (into ``_candidate``; collective),
        kept for the next call at the same u and T (cached_solve.py); a velocity that is zero
        everywhere (before the first flow solve) leaves T as it is."""
        return self._cached.solve(u)

    def freeze(self, u: dolfinx.fem.Function) -> None:
        """T moved towards T(u): ``relaxation`` of the way, Anderson-accelerated over the freezes
        (anderson.py; ``anderson_depth`` 0: the relaxed step alone)."""
        self.T.x.array[:] = self._mixing.step(self.T.x.array, self.solve(u).x.array)
        self.T.x.scatter_forward()

    def snapshot(self) -> object:
        return self.T.x.array.copy()

    def restore(self, saved: object) -> None:
        """T as it was, the acceleration's history dropped."""
        self.T.x.array[:] = saved
        self._mixing = AndersonMixing(self._mixing.comm, self._mixing.owned, self._mixing.depth,
                                      self._mixing.damping)
        self._cached.forget()

    def start_at(self, u: dolfinx.fem.Function) -> None:
        """Nothing: T(u) needs the temperature the start came with, which a start from another
        mesh's velocity does not carry; T starts at the inflow temperature as for a cold start."""

    def settle(self, u: dolfinx.fem.Function) -> None:
        """T <- T(u), the solution at u itself: a one-way computation (freeze moves T
        ``relaxation`` of the way)."""
        self.T.x.array[:] = self.solve(u).x.array
        self.T.x.scatter_forward()

    def change(self, u: dolfinx.fem.Function) -> float:
        self.solve(u)
        norm = self.mesh.comm.allreduce(dolfinx.fem.assemble_scalar(self._norm))
        difference = self.mesh.comm.allreduce(dolfinx.fem.assemble_scalar(self._difference))
        return float(np.sqrt(difference / norm)) if norm > 0 else 0.0

    def integral(self, integrand, measure) -> float:
        """int integrand (weighted measure), summed over the ranks."""
        value = dolfinx.fem.assemble_scalar(dolfinx.fem.form(integrand * measure))
        return float(self.mesh.comm.allreduce(value))

    def energy_balance(self, process_power: float | None = None) -> dict[str, float]:
        """The heat balance of the frozen T and velocity (per unit width in plane strain, of the
        whole body when axisymmetric), every term a power:
        advected = int rho c (T - T_0) u.n ds with T_in for T where the flow enters (the heat
        carried out - in; T_0 the initial temperature: equal for a divergence-free u, and the
        discrete flow's volume change int div u then carries T - T_0, not the whole T),
        exchange_<name> = int h (T - T_a) ds (heat to a tool or the air), plastic_power =
        int P dx, generated = beta times it, friction_to_workpiece = f int q_f ds; ``residual`` =
        (advected + exchanges - generated - friction_to_workpiece) / (generated +
        friction_to_workpiece), zero for the exact T of a divergence-free u (discretely, up to
        int rho c (T - T_0) div u and quadrature).
        With ``process_power`` (ram or drawing force times the process velocity) also the global
        balance: it must equal the heat leaving (advected + exchanges + friction_to_die) plus the
        work stored, (1 - beta) int P dx: ``global_residual`` is the difference over it."""
        T, v, rho_c = self.T, self.velocity, self.material.heat_capacity
        beta = self.material.heat_fraction
        plastic = self.integral(self.plastic_power, self.dx)
        # enthalpy from the initial (inflow) temperature: the volume a discrete flow gains or loses
        # (int div u) then carries T - T_ref, not T
        T_ref = self.reference_temperature
        advected = rho_c * (ufl.dot(v, self.n) * (T - T_ref)
                            + self.inflow * (T - self.inflow_temperature))
        terms = {"advected": self.integral(advected, self.ds),
                 "plastic_power": plastic, "generated": beta * plastic}
        for exchange in self.exchanges:
            terms[f"exchange_{exchange.name}"] = sum(self.integral(
                exchange.h * (T - exchange.temperature), self.ds(tag)) for tag in exchange.tags)
        friction = 0.0
        if self.friction is not None:
            friction = sum(self.integral(self.friction_power, self.ds(tag))
                           for tag in self.friction.tags)
        share = self.friction.workpiece_share if self.friction is not None else 0.0
        terms["friction_to_workpiece"] = share * friction
        terms["friction_to_die"] = (1 - share) * friction
        leaving = terms["advected"] + sum(terms[f"exchange_{e.name}"] for e in self.exchanges)
        put_in = terms["generated"] + terms["friction_to_workpiece"]
        terms["residual"] = (leaving - put_in) / put_in if put_in != 0 else float("nan")
        if process_power is not None:
            stored = (1 - beta) * plastic
            terms["process_power"], terms["stored"] = process_power, stored
            heat_out = leaving + terms["friction_to_die"] + stored
            terms["global_residual"] = (process_power - heat_out) / process_power
        return terms

    def destroy(self) -> None:
        self._system.destroy()

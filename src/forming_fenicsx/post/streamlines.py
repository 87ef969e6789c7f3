"""Streamlines of the steady velocity, and the equivalent strain carried along them.

A material point moves by x' = u(x) and its equivalent strain grows at the equivalent strain rate,
eps' = rate(x): from where it entered, x0 at time 0, to x(t),

    eps(x(t)) = eps_in(x0) + int_0^t rate(x(s)) ds,

the Lagrangian form of u . grad(eps) = rate (strain_transport.py). ``streamline_strain`` integrates
it backward from points of a section to the entry, (x, g)' = (-u(x), rate(x)) with g the strain
gained since the entry, by classical Runge-Kutta (RK4), the velocity and the strain rate of the
finite-element flow at the stages (points.py; the rate projected element by element onto
discontinuous Q_p). Each step moves a point by a fixed fraction of the local cell size (dt =
h / (steps_per_cell |u|)), so a point slows down through no more steps than it travels cells.

A point on the product's surface follows the workpiece's boundary back to the entry (free
surfaces, land, die: the fixed-domain model makes them streamlines). The discrete velocity crosses
the boundary slightly (the penalty contact, free_surface_crossing), and a stage beyond it takes the
values on the boundary of the nearest cell; a step that ends beyond it is moved back onto it
(points.PointValues, ``outside="onto_cell"``), so the surface point's strain is the flow's strain
rate integrated along the wall. Within about two elements of a sharp die entry that strain is not
resolved (the velocity smears the entry's shear unevenly over the streamlines near the corner, at
any mesh size: the transported field and the traced strain dip alike, docs/hardening.md), so the
product's profile takes those elements' mean (exit_profiles.exit_strain_profile).
"""
from __future__ import annotations

from typing import TYPE_CHECKING, Callable

import dolfinx.fem
import numpy as np
import ufl
from mpi4py import MPI

from forming_fenicsx.core.compat import function_space
from forming_fenicsx.mesh.points import PointValues
from forming_fenicsx.fem.projection import project_discontinuous

if TYPE_CHECKING:
    from forming_fenicsx.fem.forms import FlowProblem

# Steps of a quarter cell; where a step gains less than STEP_STRAIN (the rigid stock and product)
# up to LONGEST cells, retaken at a quarter cell if it gained more: a quarter of the steps for an
# exit strain 4e-4 from quarter cells alone (the steel wire; docs/hardening.md)
STEPS_PER_CELL = 4
STEP_STRAIN = 1e-4
LONGEST = 2.0
# the projection's Gauss degree over 2 p: the flow's own rule (2 p + 1) leaves the surface strain
# lower (docs/hardening.md)
RULE_ABOVE = 4


def rk4_step(field: Callable[[np.ndarray], np.ndarray], state: np.ndarray, dt,
             slope: np.ndarray | None = None) -> np.ndarray:
    """One classical Runge-Kutta step of state' = field(state): state + dt/6 (k1 + 2 k2 + 2 k3 +
    k4), k1 = field(state) (or ``slope``), k2 = field(state + dt k1/2), k3 = field(state + dt
    k2/2), k4 = field(state + dt k3); dt a number or a column of one per row of state."""
    k1 = field(state) if slope is None else slope
    k2 = field(state + 0.5 * dt * k1)
    k3 = field(state + 0.5 * dt * k2)
    k4 = field(state + dt * k3)
    return state + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4)


def streamline_strain(problem: FlowProblem, points: np.ndarray,
                      entry_distance: Callable[[np.ndarray], np.ndarray] | None = None,
                      steps_per_cell: int = STEPS_PER_CELL) -> np.ndarray:
    """The equivalent strain at the points (N, 2) of a hardening run's flow: the entry strain
    (the strain field's ``entry_strain``) where the streamline through each point enters, plus the
    strain rate integrated along it (module docstring). ``entry_distance`` of points (N, 2) is
    positive downstream of the entry and zero on it (by default x less the workpiece's smallest x);
    the step that crosses it is cut there. Collective, the same array on every rank; nan where the
    streamline does not reach the entry (a closed streamline: it stops after ``4 steps_per_cell``
    times the workpiece's length and height in steps of a smallest cell)."""
    mesh, comm = problem.mesh, problem.comm
    degree = problem.scene.discretisation.degree
    # u, the strain rate and the cell size h = sqrt|det J| in one discontinuous Q_p function
    # (one evaluation a stage; u's projection is u itself)
    fields = dolfinx.fem.Function(function_space(mesh, "DP", degree, (4,)))
    size = ufl.sqrt(abs(ufl.JacobianDeterminant(mesh)))
    project_discontinuous(ufl.as_vector([problem.u[0], problem.u[1],
                                         problem.equivalent_strain_rate(problem.u), size]),
                          fields, 2 * degree + RULE_ABOVE)
    evaluate = PointValues([fields])
    low = np.min(comm.allgather(mesh.geometry.x[:, :2].min(axis=0)), axis=0)
    high = np.max(comm.allgather(mesh.geometry.x[:, :2].max(axis=0)), axis=0)
    if entry_distance is None:
        entry_distance = lambda p: p[:, 0] - low[0]  # noqa: E731
    smallest = comm.allreduce(float(fields.x.array[3::4].min(initial=np.inf)), op=MPI.MIN)
    shortest = 1.0 / steps_per_cell  # a step's length in cells

    def slopes(values: np.ndarray) -> np.ndarray:
        return np.column_stack([-values[:, :2], values[:, 2]])  # backward: (-u, rate)

    def field(state: np.ndarray) -> np.ndarray:
        return slopes(evaluate.evaluate(state[:, :2], "onto_cell")[0])

    state = np.column_stack([points, np.zeros(len(points))])
    cells = np.full(len(points), shortest)  # the next step's length
    active = entry_distance(state[:, :2]) > 0
    for _ in range(int(4 * np.sum(high - low) / (shortest * smallest))):
        if not active.any():
            break
        index = np.flatnonzero(active)
        values, where = evaluate.evaluate(state[index, :2], "onto_cell")
        state[index, :2] = where  # a step that ended beyond the wall: back onto it
        start, slope = state[index], slopes(values)
        crossing = values[:, 3] / np.maximum(np.hypot(values[:, 0], values[:, 1]), 1e-300)
        length = cells[index]
        end = rk4_step(field, start, (length * crossing)[:, None], slope)
        retake = (length > shortest) & (end[:, 2] - start[:, 2] > STEP_STRAIN)
        if retake.any():
            length[retake] = shortest
            end[retake] = rk4_step(field, start[retake], (shortest * crossing[retake])[:, None],
                                   slope[retake])
        gained = (end[:, 2] - start[:, 2]) / length  # per cell
        cells[index] = np.clip(STEP_STRAIN / np.maximum(gained, 1e-300), shortest, LONGEST)
        before, after = entry_distance(start[:, :2]), entry_distance(end[:, :2])
        entered = after <= 0
        fraction = np.ones(len(index))
        fraction[entered] = before[entered] / (before[entered] - after[entered])
        state[index] = start + fraction[:, None] * (end - start)
        active[index[entered]] = False
    gained = np.where(active, np.nan, state[:, 2])
    return problem.field("strain").entry_strain(state[:, :2]) + gained

"""A free surface made a streamline by least squares: the surface form that carries over to 3D.

The steady free surface y = h(x) satisfies v.n = 0, u_x h' - u_y = 0 (x along the axis, y the
half-size or radius). With h a Lagrange function on a mesh of the surface's stations (an interval
mesh, COMM_SELF: every rank holds the whole surface) and u sampled on the surface, h minimises

    J(h) = int w (u_T . grad h - u_N)^2 ds,   h = y0 where the contact ends (the inflow end),

the squared volume flux across it (w = y axisymmetric, 1 in plane strain; u_T = u_x, u_N = u_y):
a(h, g) = int w (u_T . grad h)(u_T . grad g), L(g) = int w u_N (u_T . grad g). On a surface
y = h(x, z) of a 3D product the same form holds with u_T = (u_x, u_z) over a mesh of (x, z): the
least-squares surface equation of Ripert, Fourment and Chenot (AMSES 2:15, 2015), which they
found to work where plain Galerkin diverges. Since u is sampled at (x, h(x)), J depends on h
through the samples too: the samples are taken on the last h and the problem solved again
(a fixed point) until h moves by less than FIXED_POINT_TOLERANCE of y0.

In 2D the minimiser makes each element's mean slope int w u_x u_y / int w u_x^2: an upwind march
from the inflow end, exact for a divergence-free field's streamline as the elements shrink
(tests/test_surface_least_squares.py). The flux level (free_surface.flux_surface) is the 2D
default; docs/free_surface.md compares the two.
"""
from __future__ import annotations

from typing import Callable

import dolfinx.fem
import dolfinx.mesh
import numpy as np
import ufl
from mpi4py import MPI

from forming_fenicsx.config.die_profile import DieProfile
from forming_fenicsx.core.compat import (basix_element, cell_dofs, cell_geometry_nodes,
                                         function_space, quadrature_points, quadrature_space)
from forming_fenicsx.fem.linear_problem import DIRECT, LinearProblem
from forming_fenicsx.mesh.columns import ColumnValues
from forming_fenicsx.mesh.free_shape import onto_wall

FIXED_POINT_TOLERANCE = 1e-10
FIXED_POINT_STEPS = 30


class StandingSurface(ValueError):
    """The flow along the surface stands or runs back (u_x <= 0 over an element): no graph y(x)
    is its streamline there."""


def least_squares_surface(u: dolfinx.fem.Function, stations: np.ndarray,
                          start: tuple[float, float], top: Callable[[np.ndarray], np.ndarray],
                          axisymmetric: bool, degree: int = 1, wall: DieProfile | None = None,
                          guess: Callable[[np.ndarray], np.ndarray] | None = None
                          ) -> tuple[np.ndarray, float | None]:
    """The surface y = h(x) over the ``stations`` (increasing x, the first ``start``'s) that
    minimises J (module docstring) with h = start's y at the first station, h of the given
    Lagrange ``degree``, u sampled on it and above the mesh's ``top(x)`` as at the top, from the
    surface ``guess(x)`` (default ``top``). With ``wall``, a station past the die wall is put back
    onto it. Returns h at the stations (N, 2) and the last x put on the wall (None if none was);
    raises StandingSurface. Collective (the velocity's evaluation)."""
    surface = _surface_mesh(stations)
    space = function_space(surface, "P", degree)
    h, g = ufl.TrialFunction(space), ufl.TestFunction(space)
    height = dolfinx.fem.Function(space)
    height.interpolate(lambda p: (top if guess is None else guess)(p[0]))
    rule = 2 * degree + 2
    along, across = (dolfinx.fem.Function(quadrature_space(surface, rule, ())) for _ in "xy")
    weight = dolfinx.fem.Function(quadrature_space(surface, rule, ()))
    weight.x.array[:] = 1.0
    dx = ufl.dx(metadata={"quadrature_degree": rule})
    a = dolfinx.fem.form(weight * along * h.dx(0) * along * g.dx(0) * dx)
    L = dolfinx.fem.form(weight * across * along * g.dx(0) * dx)
    first = dolfinx.fem.locate_dofs_geometrical(space, lambda p: np.isclose(p[0], stations[0]))
    inflow = dolfinx.fem.dirichletbc(dolfinx.fem.Constant(surface, float(start[1])), first, space)
    solution = dolfinx.fem.Function(space)
    problem = LinearProblem(a, [L], solution, [inflow], prefix="surface_least_squares",
                            options=DIRECT)
    sample = _Sampler(surface, space, rule, ColumnValues(u), top)
    try:
        for _ in range(FIXED_POINT_STEPS):
            values = sample(height)
            standing = sample.standing(values)
            if np.any(standing):
                x = float(sample.cell_x[np.argmax(standing)])
                raise StandingSurface(f"the flow along the surface stands or runs back at x = "
                                      f"{x:.6g}")
            sample.place(along, values[:, :1])
            sample.place(across, values[:, 1:])
            if axisymmetric:
                sample.place(weight, sample.heights[:, None])
            problem.solve()
            change = np.max(np.abs(solution.x.array - height.x.array))
            height.x.array[:] = solution.x.array
            if change < FIXED_POINT_TOLERANCE * abs(start[1]):
                break
    finally:
        problem.destroy()
    found = height.eval(np.column_stack([stations, np.zeros((len(stations), 2))]),
                        _cells_of(surface, stations))[:, 0]
    found[0] = start[1]
    line = np.column_stack([stations, found])
    return line, None if wall is None else onto_wall(line, wall)


def _surface_mesh(stations: np.ndarray) -> dolfinx.mesh.Mesh:
    """An interval mesh (COMM_SELF) whose nodes are the stations."""
    count = len(stations) - 1
    mesh = dolfinx.mesh.create_interval(MPI.COMM_SELF, count, [0.0, 1.0])
    x = mesh.geometry.x
    x[:, 0] = np.interp(x[:, 0], np.linspace(0.0, 1.0, count + 1), stations)
    return mesh


def _cells_of(mesh: dolfinx.mesh.Mesh, xs: np.ndarray) -> np.ndarray:
    """The cell of the interval mesh holding each x (the last one at the end)."""
    nodes = cell_geometry_nodes(mesh)
    left = np.min(mesh.geometry.x[nodes, 0], axis=1)
    order = np.argsort(left)
    index = np.clip(np.searchsorted(left[order], xs, "right") - 1, 0, len(order) - 1)
    return order[index].astype(np.int32)


class _Sampler:
    """The velocity at the Gauss points of the surface mesh, on the surface y = h(x) (at most the
    mesh's ``top``): the points (``points``, cell by cell in the quadrature space's order) and h
    there (``heights``)."""

    def __init__(self, mesh: dolfinx.mesh.Mesh, space, rule: int, velocity: ColumnValues,
                 top: Callable[[np.ndarray], np.ndarray]):
        reference = quadrature_points(mesh, rule)
        nodes = mesh.geometry.x[cell_geometry_nodes(mesh)][:, :2, 0]  # (cells, 2): the ends
        self._x = (nodes[:, :1] + reference[:, 0][None, :] * (nodes[:, 1:2] - nodes[:, :1]))
        self._top = top(self._x.ravel())
        element = basix_element(space)
        self._basis = element.tabulate(0, reference)[0, :, :, 0]  # (points, dofs)
        self._dofs = cell_dofs(space.dofmap)
        self._velocity = velocity
        self.points = np.zeros((self._x.size, 2))
        self.heights = np.zeros(self._x.size)

    def __call__(self, height: dolfinx.fem.Function) -> np.ndarray:
        """(u_x, u_y) at the Gauss points on the surface h (cells x points, 2), above the
        mesh's top as at the top (the polynomial extended beyond a sticking corner's cells ran
        back)."""
        self.heights = np.einsum("pd,cd->cp", self._basis,
                                 height.x.array[self._dofs]).ravel()
        self.points = np.column_stack([self._x.ravel(), np.minimum(self.heights, self._top)])
        values, _ = self._velocity.evaluate(self.points, outside="column")
        return values[:, :2]

    @staticmethod
    def place(function: dolfinx.fem.Function, values: np.ndarray) -> None:
        """A quadrature function's values at the Gauss points, from ``values`` (cells x points,
        components) in the order of ``points``."""
        dofs = cell_dofs(function.function_space.dofmap)
        function.x.array.reshape(-1, values.shape[1])[dofs.ravel()] = values

    def standing(self, values: np.ndarray) -> np.ndarray:
        """Per cell: the flow along the surface runs back or stands at every Gauss point (u_x
        not positive). Where it runs forward at some, a streamline passes; backflow at others is
        the noise of a sticking corner's stagnation point, where v.n = 0 holds in either
        direction."""
        return np.all(values[:, 0].reshape(self._x.shape) <= 0.0, axis=1)

    @property
    def cell_x(self) -> np.ndarray:
        """Each cell's first Gauss point's x."""
        return self._x[:, 0]

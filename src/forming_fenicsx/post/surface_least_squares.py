"""A free surface made a streamline by least squares: the surface form that carries over to 3D.

The steady free surface y = h(x) satisfies v.n = 0, u_x h' - u_y = 0 (x along the axis, y the
half-size or radius). With h a Lagrange function on a mesh of the surface's stations (an interval
mesh, COMM_SELF: every rank holds the whole surface) and u sampled on the surface, h minimises

    J(h) = int w (u_T . grad h - u_N)^2 ds,   h = y0 where the contact ends (the inflow end),

the squared volume flux across it (w = y axisymmetric, 1 in plane strain; u_T = u_x, u_N = u_y):
a(h, g) = int w (u_T . grad h)(u_T . grad g), L(g) = int w u_N (u_T . grad g). On a surface
y = h(x, z) of a 3D product the same form holds with u_T = (u_x, u_z) over a mesh of (x, z)
(surface_by_least_squares takes either; checked on a 3D field, the 3D update not built): the
surface equation of Ripert, Fourment and Chenot (AMSES 2:15, 2015) by plain least squares (they
report plain Galerkin diverging, plain least squares failing at contact and an upwind
least-squares form working; the upwind form is not built). Since u is sampled at (x, h(x)), J
depends on h through the samples too: the samples are taken on the last h and the problem solved
again (a fixed point) until h moves by less than FIXED_POINT_TOLERANCE of y0.

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
    is its streamline there; ``x`` where."""

    def __init__(self, x: float):
        super().__init__(f"the flow along the surface stands or runs back at x = {x:.6g}")
        self.x = x


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
    surface = _interval_mesh(stations)
    velocity = ColumnValues(u)

    def sample(params: np.ndarray, heights: np.ndarray) -> np.ndarray:
        points = np.column_stack([params[:, 0], np.minimum(heights, top(params[:, 0]))])
        return velocity.evaluate(points, outside="column")[0][:, :2]

    height = surface_by_least_squares(
        surface, degree, sample, lambda p: np.isclose(p[0], stations[0]),
        lambda p: np.full(p.shape[1], float(start[1])),
        lambda p: (top if guess is None else guess)(p[0]), axisymmetric,
        FIXED_POINT_TOLERANCE * abs(start[1]))
    # the stations are the mesh's vertices: h's degrees of freedom there
    at = height.function_space.tabulate_dof_coordinates()[:, 0]
    order = np.argsort(at)
    found = np.interp(stations, at[order], height.x.array[order])
    found[0] = start[1]
    line = np.column_stack([stations, found])
    return line, None if wall is None else onto_wall(line, wall)


def surface_by_least_squares(surface: dolfinx.mesh.Mesh, degree: int,
                             sample: Callable[[np.ndarray, np.ndarray], np.ndarray],
                             inflow: Callable[[np.ndarray], np.ndarray],
                             inflow_height: Callable[[np.ndarray], np.ndarray],
                             guess: Callable[[np.ndarray], np.ndarray], weighted: bool,
                             tolerance: float) -> dolfinx.fem.Function:
    """h over the parameter mesh ``surface`` (x, or (x, z) of a 3D product's surface y = h(x, z);
    COMM_SELF) minimising J (module docstring) with h = ``inflow_height`` where ``inflow``, by the
    fixed point on the velocity samples from ``guess`` (the three take the parameters' points
    (3, N), as dolfinx's interpolation and locators): ``sample(params (N, d), heights (N,))``
    gives (u_T..., u_N) (N, d + 1) at the surface points; ``weighted``: w = h (a round
    product's). Stops when h moves by less than ``tolerance``; raises StandingSurface."""
    space = function_space(surface, "P", degree)
    h, g = ufl.TrialFunction(space), ufl.TestFunction(space)
    height, solution = dolfinx.fem.Function(space), dolfinx.fem.Function(space)
    height.interpolate(guess)
    rule = 2 * degree + 2
    dim = surface.topology.dim
    scalar = quadrature_space(surface, rule, ())
    tangent = [dolfinx.fem.Function(scalar) for _ in range(dim)]
    normal, weight = dolfinx.fem.Function(scalar), dolfinx.fem.Function(scalar)
    weight.x.array[:] = 1.0
    dx = ufl.dx(metadata={"quadrature_degree": rule})

    def along(f):  # u_T . grad f
        return sum(t * f.dx(i) for i, t in enumerate(tangent))

    a = dolfinx.fem.form(weight * along(h) * along(g) * dx)
    L = dolfinx.fem.form(weight * normal * along(g) * dx)
    given = dolfinx.fem.Function(space)
    given.interpolate(inflow_height)
    bc = dolfinx.fem.dirichletbc(given, dolfinx.fem.locate_dofs_geometrical(space, inflow))
    problem = LinearProblem(a, [L], solution, [bc], prefix="surface_least_squares",
                            options=DIRECT)
    points = _GaussPoints(surface, space, rule)
    try:
        for _ in range(FIXED_POINT_STEPS):
            heights = points.values(height)
            values = sample(points.params, heights)
            standing = points.standing(values[:, 0])
            if np.any(standing):
                raise StandingSurface(float(points.params[points.first(standing), 0]))
            for i, t in enumerate(tangent):
                points.place(t, values[:, i])
            points.place(normal, values[:, dim])
            if weighted:
                points.place(weight, heights)
            problem.solve()
            change = np.max(np.abs(solution.x.array - height.x.array))
            height.x.array[:] = solution.x.array
            if change < tolerance:
                break
    finally:
        problem.destroy()
    return height


def _interval_mesh(stations: np.ndarray) -> dolfinx.mesh.Mesh:
    """An interval mesh (COMM_SELF) whose nodes are the stations."""
    count = len(stations) - 1
    mesh = dolfinx.mesh.create_interval(MPI.COMM_SELF, count, [0.0, 1.0])
    x = mesh.geometry.x
    x[:, 0] = np.interp(x[:, 0], np.linspace(0.0, 1.0, count + 1), stations)
    return mesh


class _GaussPoints:
    """The Gauss points of a parameter mesh's cells: their parameters (``params`` (N, d), cell by
    cell in the quadrature space's order), a function of the mesh's space there, and values
    placed into a quadrature function."""

    def __init__(self, mesh: dolfinx.mesh.Mesh, space, rule: int):
        reference = quadrature_points(mesh, rule)
        geometry = basix_element(mesh)
        nodes = mesh.geometry.x[cell_geometry_nodes(mesh)][:, :, :mesh.topology.dim]
        self._shape = (len(nodes), len(reference))
        self.params = np.einsum("pn,cnd->cpd", geometry.tabulate(0, reference)[0, :, :, 0],
                                nodes).reshape(-1, mesh.topology.dim)
        self._basis = basix_element(space).tabulate(0, reference)[0, :, :, 0]
        self._dofs = cell_dofs(space.dofmap)

    def values(self, function: dolfinx.fem.Function) -> np.ndarray:
        """The function at the points (N,)."""
        return np.einsum("pd,cd->cp", self._basis, function.x.array[self._dofs]).ravel()

    @staticmethod
    def place(function: dolfinx.fem.Function, values: np.ndarray) -> None:
        """A scalar quadrature function's values at the points, from ``values`` (N,)."""
        function.x.array[cell_dofs(function.function_space.dofmap).ravel()] = values

    def standing(self, along: np.ndarray) -> np.ndarray:
        """Per cell: the flow along the surface (``along``, u_x at the points) runs back or stands
        at every Gauss point. Where it runs forward at some, a streamline passes; backflow at
        others is the noise of a sticking corner's stagnation point, where v.n = 0 holds in
        either direction."""
        return np.all(along.reshape(self._shape) <= 0.0, axis=1)

    def first(self, cells: np.ndarray) -> int:
        """The first Gauss point of the first cell marked."""
        return int(np.argmax(cells)) * self._shape[1]

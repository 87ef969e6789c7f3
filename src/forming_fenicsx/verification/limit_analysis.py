"""Rigorous bounds on the frictionless drawing load by limit analysis (a check of Example 2).

Section 4, Example 2 compares the computed die pressure with a quoted slip-line value q = 2.5 k.
In the rigid-perfectly plastic limit of (2.10) (|s| = k in plastic flow) with mu = 0, the steady
load of the strip as meshed (straight free surfaces, a die with (2.8) and no friction, the entry
face free, the exit pulled at a uniform velocity U as in (2.5)) is bracketed from both sides:

- lower bound: any stress field in equilibrium that meets the traction conditions (free entry
  face and surfaces, no shear on the symmetry line, the die and the exit face, sigma_N <= 0 on the
  die) and nowhere exceeds the yield condition carries a pulling force F <= F_true. (Virtual work
  with the true velocity u*: F U = int sigma:e(u*) - int_die sigma_N u*_N <= D(u*) = F_true U, as
  sigma_N u*_N >= 0.) Stresses linear in each triangle, discontinuous between them (Sloan 1988),
  the yield circle replaced by an inscribed regular polygon: the bound stays rigorous.
- upper bound: any incompressible velocity field with u = U on the exit face, u_y = 0 on the
  symmetry line and u_N <= 0 on the die dissipates D(u) >= F_true U. Velocities linear in each
  triangle of a crossed-diagonal mesh (exactly incompressible in each triangle without locking,
  Nagtegaal et al. 1974), the dissipation k |gamma_max| bounded from above by a circumscribed
  polygon.

Both are linear programmes (scipy's HiGHS). By the frictionless force balance a bound on F is one on
the die pressure, q = F / ((h0 - h1)/2)."""
from __future__ import annotations

import logging
import math
import time
from dataclasses import dataclass

import numpy as np

from forming_fenicsx.core.errors import SceneError
from forming_fenicsx.config.geometry import DrawingGeometry

logger = logging.getLogger(__name__)


@dataclass
class Bound:
    """One bound for one triangulation (per unit width of the half model)."""

    kind: str
    pulling_force: float
    die_pressure: float
    drawing_stress: float
    triangles: int
    sides: int
    seconds: float
    status: str


def _graded(a: float, b: float, size_min: float, size_max: float, growth: float,
            corners: tuple[float, ...], zone: float = math.inf) -> np.ndarray:
    """Points from a to b (both kept) whose spacing grows from size_min at the corners by ``growth``
    per unit distance, up to size_max within ``zone`` of a corner and up to 4 size_max beyond."""
    points = [a]
    while True:
        x = points[-1]
        distance = min(abs(x - c) for c in corners)
        cap = size_max if distance <= zone else min(4 * size_max, size_max + distance - zone)
        step = min(cap, size_min + growth * distance)
        if x + 1.5 * step >= b:
            break
        points.append(x + step)
    points.append(b)
    # spread the remainder evenly: the last step may be up to 1.5 steps long otherwise
    points = np.asarray(points)
    return a + (points - a) * (b - a) / (points[-1] - a)


def strip_triangulation(geometry: DrawingGeometry, size_min: float, size_max: float,
                        growth: float = 0.5
                        ) -> tuple[np.ndarray, np.ndarray, dict[str, np.ndarray]]:
    """Triangles of the half strip (entry face, cone, land, exit) refined toward the die corners.

    Columns at x-points (the die entry, cone end and land end among them), coarser beyond a strip
    thickness from the die where the strip moves as a rigid body, with rows at fractions of
    the local half-thickness, each quadrilateral cut into four triangles where its diagonals cross
    (a crossed-diagonal mesh, which does not lock under incompressibility). Returns the points,
    the triangles (vertex indices) and the boundary edges by role: free, die, symmetry, exit. The
    bounds are those of plane strain through a straight cone: a round bar's (symmetry =
    "axisymmetric") and other die profiles are refused.
    """
    if geometry.axisymmetric:
        raise SceneError("geometry.symmetry",
                         "the limit-analysis bounds are built for plane strain "
                         '(triangles of the strip); not for symmetry = "axisymmetric"')
    if len(geometry.profile().segments) > 2 or geometry.entry_radius:
        raise SceneError("geometry.die_profile_file" if geometry.die_profile_file
                         else "geometry.die_angle",
                         "the limit-analysis bounds are built for a straight cone with a land; "
                         "not for an entry radius, a second angle or a CSV profile")
    h0, h1 = 0.5 * geometry.entry_thickness, 0.5 * geometry.exit_thickness
    xa = geometry.die_entry
    xb, xc, length = xa + geometry.cone_length, geometry.die_exit, geometry.length
    corners = (xa, xb, xc)
    cuts = sorted({0.0, xa, xb, xc, length})
    xs = np.unique(np.concatenate([_graded(p, q, size_min, size_max, growth, corners, zone=2 * h0)
                                   for p, q in zip(cuts, cuts[1:], strict=False)]))
    depth = _graded(0.0, h0, size_min, size_max, growth, (0.0,))  # distance below the top surface
    eta = np.sort(1.0 - depth / h0)  # fractions of the half-thickness

    def top(x: np.ndarray) -> np.ndarray:
        return np.interp(x, [0.0, xa, xb, length], [h0, h0, h1, h1])

    nx, ny = len(xs), len(eta)
    X = np.repeat(xs[:, None], ny, axis=1)
    Y = eta[None, :] * top(xs)[:, None]
    grid = np.arange(nx * ny).reshape(nx, ny)
    corner = np.column_stack([grid[:-1, :-1].ravel(), grid[1:, :-1].ravel(),
                              grid[1:, 1:].ravel(), grid[:-1, 1:].ravel()])   # counter-clockwise
    vertices = np.column_stack([X.ravel(), Y.ravel()])
    q = vertices[corner]
    d1, d2 = q[:, 2] - q[:, 0], q[:, 3] - q[:, 1]
    cross = d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0]
    along = ((q[:, 1, 0] - q[:, 0, 0]) * d2[:, 1] - (q[:, 1, 1] - q[:, 0, 1]) * d2[:, 0]) / cross
    centres = q[:, 0] + along[:, None] * d1
    centre_index = len(vertices) + np.arange(len(corner))
    points = np.vstack([vertices, centres])
    triangles = np.vstack([np.column_stack([corner[:, i], corner[:, (i + 1) % 4], centre_index])
                           for i in range(4)])
    top_x = xs[:-1] + 0.5 * np.diff(xs)
    on_die = (top_x > xa) & (top_x < xc)
    top_edges = np.column_stack([grid[1:, -1], grid[:-1, -1]])
    edges = {"free": np.vstack([top_edges[~on_die],
                                np.column_stack([grid[0, :-1], grid[0, 1:]])[:, ::-1]]),
             "die": top_edges[on_die],
             "symmetry": np.column_stack([grid[:-1, 0], grid[1:, 0]]),
             "exit": np.column_stack([grid[-1, :-1], grid[-1, 1:]])}
    return points, triangles, edges


class _Rows:
    """Sparse rows of a constraint matrix, collected as (row, column, value) triples."""

    def __init__(self) -> None:
        self.rows: list[np.ndarray] = []
        self.cols: list[np.ndarray] = []
        self.vals: list[np.ndarray] = []
        self.count = 0

    def add(self, columns: list[np.ndarray], values: list[np.ndarray]) -> None:
        """One new row per entry of the arrays: sum_j values[j][i] * x[columns[j][i]]."""
        n = len(columns[0])
        rows = self.count + np.arange(n)
        for c, v in zip(columns, values, strict=True):
            self.rows.append(rows)
            self.cols.append(np.asarray(c))
            self.vals.append(np.broadcast_to(np.asarray(v, dtype=float), (n,)))
        self.count += n

    def matrix(self, columns: int):
        from scipy.sparse import coo_matrix
        return coo_matrix((np.concatenate(self.vals),
                           (np.concatenate(self.rows), np.concatenate(self.cols))),
                          shape=(self.count, columns)).tocsr()


def _edge_owners(triangles: np.ndarray) -> dict[tuple[int, int], list[tuple[int, int]]]:
    """For each undirected edge, the (triangle, local edge) pairs that have it."""
    owners: dict[tuple[int, int], list[tuple[int, int]]] = {}
    for t, tri in enumerate(triangles.tolist()):
        for i in range(3):
            a, b = tri[i], tri[(i + 1) % 3]
            owners.setdefault((min(a, b), max(a, b)), []).append((t, i))
    return owners


def _gradients(points: np.ndarray, triangles: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """b, c with 2A dN_i/dx = b_i and 2A dN_i/dy = c_i for the linear shape functions of each
    triangle."""
    p = points[triangles]
    b = np.roll(p[:, :, 1], -1, axis=1) - np.roll(p[:, :, 1], -2, axis=1)
    c = np.roll(p[:, :, 0], -2, axis=1) - np.roll(p[:, :, 0], -1, axis=1)
    return b, c


def _outward(points: np.ndarray, triangles: np.ndarray, owners: dict, edges: np.ndarray
             ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The triangle owning each boundary edge, the edges' unit tangents, unit outward normals and
    lengths."""
    owner = np.array([owners[(min(a, b), max(a, b))][0][0] for a, b in edges.tolist()])
    tangent = points[edges[:, 1]] - points[edges[:, 0]]
    length = np.linalg.norm(tangent, axis=1)
    tangent = tangent / length[:, None]
    normal = np.column_stack([tangent[:, 1], -tangent[:, 0]])
    away = np.einsum("ij,ij->i", normal,
                     points[edges[:, 0]] - points[triangles[owner]].mean(axis=1))
    return owner, tangent, normal * np.sign(away)[:, None], length


def _solve(kind: str, objective: np.ndarray, upper: _Rows, rhs_upper: np.ndarray, equal: _Rows,
           rhs_equal: np.ndarray, geometry: DrawingGeometry, triangles: int, sides: int,
           start: float, sign: float) -> Bound:
    """Solve the linear programme min objective.x and return F = sign * the minimum as a Bound."""
    from scipy.optimize import linprog

    n = len(objective)
    result = linprog(objective, A_ub=upper.matrix(n), b_ub=rhs_upper, A_eq=equal.matrix(n),
                     b_eq=rhs_equal, bounds=(None, None), method="highs-ipm")
    seconds = time.perf_counter() - start
    force = sign * result.fun if result.status == 0 else math.nan
    h0, h1 = 0.5 * geometry.entry_thickness, 0.5 * geometry.exit_thickness
    logger.info("%s bound: %d triangles, %d sides: F = %.6g (%s, %.1f s)", kind, triangles, sides,
                force, result.message, seconds)
    return Bound(kind=kind, pulling_force=force,
                 die_pressure=force / (h0 - h1) if h0 > h1 else math.nan,
                 drawing_stress=force / h1, triangles=triangles, sides=sides, seconds=seconds,
                 status=result.message)


def lower_bound(geometry: DrawingGeometry, k: float, size_min: float, size_max: float,
                growth: float = 0.5, sides: int = 48) -> Bound:
    """Maximise the pulling force over statically admissible stress fields (see the module
    docstring).

    Unknowns: sigma_xx, sigma_yy, sigma_xy at the three vertices of every triangle (index
    9 t + 3 i + c).
    """
    start = time.perf_counter()
    points, triangles, boundary = strip_triangulation(geometry, size_min, size_max, growth)
    n_tri = len(triangles)
    # the first unknown of each vertex
    var = (9 * np.arange(n_tri))[:, None] + 3 * np.arange(3)[None, :]

    def first_of(owner: np.ndarray, vertex: np.ndarray) -> np.ndarray:
        """The first unknown of each given vertex in the triangle of the same index in ``owner``."""
        return var[owner, np.where(triangles[owner] == vertex[:, None])[1]]

    equal, upper = _Rows(), _Rows()

    # equilibrium in each triangle: div sigma = 0 with the constant gradients of the linear field
    b, c = _gradients(points, triangles)
    equal.add([var[:, i] + j for i in range(3) for j in (0, 2)],
              [b[:, i] if j == 0 else c[:, i] for i in range(3) for j in (0, 2)])
    equal.add([var[:, i] + j for i in range(3) for j in (2, 1)],
              [b[:, i] if j == 2 else c[:, i] for i in range(3) for j in (2, 1)])

    def traction(first: np.ndarray, n: np.ndarray, direction: np.ndarray) -> tuple[list, list]:
        """Columns and coefficients of direction . sigma n at the vertices whose unknowns start at
        first."""
        sxx = direction[:, 0] * n[:, 0]
        syy = direction[:, 1] * n[:, 1]
        sxy = direction[:, 0] * n[:, 1] + direction[:, 1] * n[:, 0]
        return [first, first + 1, first + 2], [sxx, syy, sxy]

    axes = (np.array([1.0, 0.0]), np.array([0.0, 1.0]))
    # traction continuity across every interior edge, at both of its vertices
    owners = _edge_owners(triangles)
    # ((t1, i1), (t2, i2))
    pairs = np.array([(o[0], o[1]) for o in owners.values() if len(o) == 2])
    t1, i1, t2 = pairs[:, 0, 0], pairs[:, 0, 1], pairs[:, 1, 0]
    a_pts, b_pts = triangles[t1, i1], triangles[t1, (i1 + 1) % 3]
    tangent = points[b_pts] - points[a_pts]
    normal = (np.column_stack([tangent[:, 1], -tangent[:, 0]])
              / np.linalg.norm(tangent, axis=1)[:, None])
    for vertex in (a_pts, b_pts):
        first1, first2 = first_of(t1, vertex), first_of(t2, vertex)
        for axis in axes:
            d = np.broadcast_to(axis, normal.shape)
            cols1, vals1 = traction(first1, normal, d)
            cols2, vals2 = traction(first2, normal, d)
            equal.add(cols1 + cols2, vals1 + [-v for v in vals2])

    # boundary tractions, applied at both vertices of each boundary edge in the triangle owning it
    objective = np.zeros(9 * n_tri)
    for role, edges in boundary.items():
        owner, tangent, normal, length = _outward(points, triangles, owners, edges)
        for end in (0, 1):
            first = first_of(owner, edges[:, end])
            if role == "free":
                for axis in axes:
                    equal.add(*traction(first, normal, np.broadcast_to(axis, normal.shape)))
            else:   # die, symmetry and exit face: no shear (mu = 0, symmetry, (2.5))
                equal.add(*traction(first, normal, tangent))
            if role == "die":   # sigma_N <= 0
                upper.add(*traction(first, normal, normal))
            # maximise the integral of sigma_xx over the exit face (trapezoidal, exact)
            if role == "exit":
                np.add.at(objective, first, -0.5 * length)

    # the yield condition at every vertex: an inscribed polygon of the circle |s| <= k
    first = var.ravel()
    for angle in 2 * math.pi * np.arange(sides) / sides:
        upper.add([first, first + 1, first + 2],
                  [0.5 * math.cos(angle), -0.5 * math.cos(angle), math.sin(angle)])
    rhs_upper = np.zeros(upper.count)
    rhs_upper[-sides * len(first):] = k * math.cos(math.pi / sides)
    return _solve("lower", objective, upper, rhs_upper, equal, np.zeros(equal.count), geometry,
                  n_tri, sides, start, sign=-1.0)


def upper_bound(geometry: DrawingGeometry, k: float, size_min: float, size_max: float,
                growth: float = 0.5, sides: int = 48) -> Bound:
    """Minimise the dissipation over kinematically admissible velocity fields with U = 1 on the
    exit face (see the module docstring); F_true <= k * sum over triangles of A |gamma_max|.

    Unknowns: u_x, u_y at every point (index 2 p + c), then one dissipation bound t_e per triangle.
    """
    start = time.perf_counter()
    points, triangles, boundary = strip_triangulation(geometry, size_min, size_max, growth)
    n_tri, n_pts = len(triangles), len(points)
    ux, uy, t = 2 * triangles, 2 * triangles + 1, 2 * n_pts + np.arange(n_tri)
    equal, upper = _Rows(), _Rows()
    b, c = _gradients(points, triangles)
    # incompressible in each triangle: 2A (e_xx + e_yy) = sum b_i u_i + c_i v_i = 0
    equal.add([ux[:, i] for i in range(3)] + [uy[:, i] for i in range(3)],
              [b[:, i] for i in range(3)] + [c[:, i] for i in range(3)])
    # A |gamma_max| = |(2A (e_xx - e_yy), 2A gamma_xy)| / 2 <= t cos(pi/sides): a circumscribed
    # polygon
    for angle in 2 * math.pi * np.arange(sides) / sides:
        cos, sin = 0.5 * math.cos(angle), 0.5 * math.sin(angle)
        upper.add([ux[:, i] for i in range(3)] + [uy[:, i] for i in range(3)] + [t],
                  [cos * b[:, i] + sin * c[:, i] for i in range(3)] +
                  [-cos * c[:, i] + sin * b[:, i] for i in range(3)] + [-math.cos(math.pi / sides)])
    rhs_equal = [np.zeros(equal.count)]
    owners = _edge_owners(triangles)
    for role, edges in boundary.items():
        ends = np.unique(edges)
        if role == "symmetry":
            equal.add([2 * ends + 1], [1.0])
            rhs_equal.append(np.zeros(len(ends)))
        elif role == "exit":
            equal.add([2 * ends], [1.0])
            rhs_equal.append(np.ones(len(ends)))
        elif role == "die":   # u . n <= 0 at both ends of each die edge
            _, _, normal, _ = _outward(points, triangles, owners, edges)
            for end in (0, 1):
                upper.add([2 * edges[:, end], 2 * edges[:, end] + 1], [normal[:, 0], normal[:, 1]])
    objective = np.zeros(2 * n_pts + n_tri)
    objective[t] = k
    return _solve("upper", objective, upper, np.zeros(upper.count), equal,
                  np.concatenate(rhs_equal), geometry, n_tri, sides, start, sign=1.0)

"""The strain transport u . grad(eps) = rate (strain_transport.py) on prescribed velocities whose
strain is exact (round-products reference, section 1), for both schemes, Q1 and Q2, both symmetries:

- homogeneous extension between streamlines, u = (x, -y) (plane strain: eps = eps0 + 2/sqrt3 ln x)
  or u = (x, -y/2) (axisymmetric: eps = eps0 + ln x), on 1 < x < 2; the velocity is linear, so
  its interpolant and strain rate are exact and the error is the scheme's;
- the radial flows of the sector mesh (verification.sector_mesh): the wedge, u = -(1/r) e_r,
  eps = eps0 + 2/sqrt3 ln(r0/r), and the cone, u = -(1/rho^2) e_rho, eps = eps0 + 2 ln(rho0/rho);
- a step of the inflow strain (JUMP) across the inflow boundary, carried by a parallel flow along
  or across the mesh lines or by the cone flow: the over- and undershoot relative to the jump;
- (printed only) a smooth inflow strain carried by a parallel flow at 20 and 40 degrees to an
  inflow side: the side gets its condition only where the flow enters at more than 30 degrees.

The exact strain is the inflow strain (a UFL profile), so the only errors are the scheme's and the
velocity's. ``python tests/test_strain_transport.py`` (or under mpirun) prints the tables of
docs/strain_transport.md: errors and orders on four meshes, the oblique inflow side, the overshoot
at ten step positions, and the cost of each scheme.
"""
from __future__ import annotations

import functools
import time
from dataclasses import dataclass

import dolfinx.fem
import dolfinx.mesh
import numpy as np
import pytest
import ufl
from mpi4py import MPI

from forming_fenicsx.core.compat import GHOST_MODE, atan2, function_space
from forming_fenicsx.physics.coordinates import CoordinateSystem
from forming_fenicsx.coupled.strain_transport import StrainField
from forming_fenicsx.verification.verification import RADIAL, radial_velocity, sector_mesh

EPS0, JUMP = 0.2, 0.5
SCHEMES, DEGREES, SYMMETRIES = ("supg", "upwind"), (1, 2), ("plane_strain", "axisymmetric")
STEP_FLOWS = ("along", "across", "cone")


def rate_factor(symmetry: str) -> float:
    """The equivalent strain rate over the extension rate: 1 for a bar, 2/sqrt3 in plane strain."""
    return 1.0 if symmetry == "axisymmetric" else 2.0 / np.sqrt(3.0)


@dataclass
class Case:
    """A prescribed velocity ``u`` with its exact strain: ``smooth`` (UFL) plus JUMP where
    ``stepped`` (UFL, 1 or 0; None without a step); ``smooth_at`` is the smooth part at numpy
    points (3, N). ``step`` is the position of the step (a Constant the tests change)."""
    coordinates: CoordinateSystem
    u: dolfinx.fem.Function
    smooth: object
    smooth_at: object
    stepped: object = None
    step: dolfinx.fem.Constant | None = None

    @property
    def mesh(self):
        return self.u.function_space.mesh

    @property
    def inflow(self):
        return self.smooth if self.stepped is None else self.smooth + JUMP * self.stepped


def interpolated(mesh, degree: int, velocity) -> dolfinx.fem.Function:
    """The vector Lagrange interpolant of degree ``degree`` of ``velocity`` (numpy points to a
    list of components)."""
    u = dolfinx.fem.Function(function_space(mesh, "P", degree, (2,)))
    u.interpolate(lambda x: np.vstack(velocity(x)))
    return u


def extension_case(symmetry: str, cells: int, degree: int) -> Case:
    """Extension at unit rate on 1 < x < 2 between the axis and the streamline through (1, 1/2):
    y x^k = const, k = 1 (plane strain) or 1/2 (axisymmetric); ``cells`` x cells/2 elements."""
    mesh = dolfinx.mesh.create_rectangle(MPI.COMM_WORLD, [np.array([1.0, 0.0]),
                                                          np.array([2.0, 0.5])],
                                         [cells, max(1, cells // 2)],
                                         dolfinx.mesh.CellType.quadrilateral, ghost_mode=GHOST_MODE)
    k = 0.5 if symmetry == "axisymmetric" else 1.0
    mesh.geometry.x[:, 1] *= mesh.geometry.x[:, 0] ** -k
    x = ufl.SpatialCoordinate(mesh)
    c = rate_factor(symmetry)
    return Case(CoordinateSystem(mesh, symmetry),
                interpolated(mesh, degree, lambda p: [p[0], -k * p[1]]),
                EPS0 + c * ufl.ln(x[0]), lambda p: EPS0 + c * np.log(p[0]))


@functools.lru_cache(maxsize=None)
def sector(cells: int, degree: int):
    """The mesh of verification.sector_mesh, made once."""
    return sector_mesh(cells, degree).mesh


def radial_case(symmetry: str, cells: int, degree: int, velocity_degree: int,
                stepped: bool = False) -> Case:
    """The wedge (plane strain) or cone (axisymmetric) flow on the sector mesh of Q_degree with
    ``cells`` elements across the angle, the velocity of degree ``velocity_degree``; with
    ``stepped``, JUMP more on the streamlines at angles above ``step`` times the die angle."""
    mesh = sector(cells, degree)
    c = 2.0 if symmetry == "axisymmetric" else 2.0 / np.sqrt(3.0)
    x = ufl.SpatialCoordinate(mesh)
    rho = ufl.sqrt(x[0] ** 2 + x[1] ** 2)
    case = Case(CoordinateSystem(mesh, symmetry),
                interpolated(mesh, velocity_degree, lambda p: radial_velocity(symmetry, p)),
                EPS0 + c * ufl.ln(RADIAL["rho0"] / rho),
                lambda p: EPS0 + c * np.log(RADIAL["rho0"] / np.hypot(p[0], p[1])))
    if stepped:
        case.step = dolfinx.fem.Constant(mesh, 0.5)
        angle = np.radians(RADIAL["alpha"]) * case.step
        case.stepped = ufl.conditional(ufl.gt(atan2(x[1], -x[0]), angle), 1.0, 0.0)
    return case


def parallel_case(angle: float, cells: int, degree: int) -> Case:
    """u = (cos a, sin a) on the unit square of cells x cells elements (plane strain, no strain
    rate): JUMP above y = ``step`` on the inflow side x = 0, none on the inflow side y = 0."""
    mesh = dolfinx.mesh.create_unit_square(MPI.COMM_WORLD, cells, cells,
                                           dolfinx.mesh.CellType.quadrilateral,
                                           ghost_mode=GHOST_MODE)
    a = np.radians(angle)
    step = dolfinx.fem.Constant(mesh, 0.5)
    y = ufl.SpatialCoordinate(mesh)[1]
    return Case(CoordinateSystem(mesh, "plane_strain"),
                interpolated(mesh, degree, lambda p: [np.full_like(p[0], np.cos(a)),
                                                      np.full_like(p[0], np.sin(a))]),
                ufl.as_ufl(0.0), lambda p: np.zeros_like(p[0]),
                ufl.conditional(ufl.gt(y, step), 1.0, 0.0), step)


def oblique_case(angle: float, cells: int, degree: int) -> Case:
    """The parallel flow at ``angle`` to the side y = 0 with a smooth inflow strain, constant
    along the flow: eps = 0.2 + 0.3 sin(2 (y - x tan a)) on both inflow sides and everywhere."""
    case = parallel_case(angle, cells, degree)
    x = ufl.SpatialCoordinate(case.mesh)
    tangent = np.tan(np.radians(angle))
    case.smooth = 0.2 + 0.3 * ufl.sin(2 * (x[1] - x[0] * tangent))
    case.smooth_at = lambda p: 0.2 + 0.3 * np.sin(2 * (p[1] - p[0] * tangent))
    case.stepped = case.step = None
    return case


def step_case(flow: str, cells: int, degree: int) -> Case:
    """A step of the inflow strain carried along the mesh lines (parallel flow at 0 degrees),
    across them (45 degrees), or by the cone flow."""
    if flow == "cone":
        return radial_case("axisymmetric", cells, degree, degree, stepped=True)
    return parallel_case({"along": 0.0, "across": 45.0}[flow], cells, degree)


def transport(case: Case, degree: int, scheme: str) -> StrainField:
    """The transport of the case's inflow strain by its velocity, quadrature degree 2p + 2."""
    return StrainField(case.u, case.coordinates, case.inflow, degree, 2 * degree + 2, scheme)


def l2_error(case: Case, eps: dolfinx.fem.Function) -> float:
    """||eps - exact|| / ||exact|| in the weighted L2 norm (2 pi y dx when axisymmetric)."""
    dx = case.coordinates.measure(ufl.dx(domain=case.mesh, metadata={"quadrature_degree": 10}))

    def integral(integrand) -> float:
        value = dolfinx.fem.assemble_scalar(dolfinx.fem.form(integrand * dx))
        return case.mesh.comm.allreduce(value)
    return float(np.sqrt(integral((eps - case.smooth) ** 2) / integral(case.smooth ** 2)))


def extremes(eps: dolfinx.fem.Function, smooth: dolfinx.fem.Function) -> tuple[float, float]:
    """(overshoot, undershoot) / JUMP: the largest eps - smooth - JUMP and smooth - eps at the
    nodes of the space of ``smooth`` (the smooth part of the exact strain interpolated)."""
    values = dolfinx.fem.Function(smooth.function_space)
    values.interpolate(eps)
    owned = smooth.function_space.dofmap.index_map.size_local
    relative = (values.x.array - smooth.x.array)[:owned]
    comm = smooth.function_space.mesh.comm
    return (comm.allreduce(float(relative.max()) - JUMP, op=MPI.MAX) / JUMP,
            comm.allreduce(-float(relative.min()), op=MPI.MAX) / JUMP)


def errors(make, cells: tuple[int, ...], degree: int, scheme: str) -> np.ndarray:
    """The L2 errors of the cases ``make(cells)``."""
    result = []
    for count in cells:
        case = make(count)
        field = transport(case, degree, scheme)
        result.append(l2_error(case, field.solve(case.u)))
        field.destroy()
    return np.array(result)


def orders(values: np.ndarray) -> np.ndarray:
    return np.log2(values[:-1] / values[1:])


@functools.lru_cache(maxsize=None)
def step_extremes(flow: str, cells: int, degree: int, scheme: str,
                  positions: tuple[float, ...]) -> np.ndarray:
    """(overshoot, undershoot) / JUMP for each position of the step within the middle cell of
    the inflow side (0 its lower side, 1 its upper side); rows: positions (computed once). The
    extremes are taken at the nodes of discontinuous Q_(p+2): a lattice in every cell, its sides
    included."""
    case = step_case(flow, cells, degree)
    smooth = dolfinx.fem.Function(function_space(case.mesh, "DP", degree + 2))
    smooth.interpolate(case.smooth_at)
    result = []
    for position in positions:
        case.step.value = (cells // 2 + position) / cells
        field = transport(case, degree, scheme)
        result.append(extremes(field.solve(case.u), smooth))
        field.destroy()
    return np.array(result)


# -- the tests ---------------------------------------------------------------------------------
# observed orders (measured in docs/strain_transport.md) less a margin
ORDER = {1: 1.85, 2: 2.8}


@pytest.mark.parametrize("scheme", SCHEMES)
@pytest.mark.parametrize("degree", DEGREES)
@pytest.mark.parametrize("symmetry", SYMMETRIES)
def test_extension_orders(symmetry, degree, scheme):
    """Homogeneous extension (the velocity exact in Q1): order p + 1 between 4, 8 and 16 cells
    (measured 1.98 to 2.11 for Q1, 2.90 to 2.99 for Q2)."""
    values = errors(lambda cells: extension_case(symmetry, cells, degree), (4, 8, 16), degree,
                    scheme)
    assert orders(values).min() > ORDER[degree], (values, orders(values))


@pytest.mark.parametrize("scheme", SCHEMES)
@pytest.mark.parametrize("degree", DEGREES)
@pytest.mark.parametrize("symmetry", SYMMETRIES)
def test_radial_orders(symmetry, degree, scheme):
    """Wedge and cone flows with the velocity of degree p + 2 (its strain rate accurate to
    O(h^(p+2))): the scheme's order p + 1 between 6, 12 and 24 cells across the angle (measured
    2.00 to 2.08 for Q1, 2.99 to 3.20 for Q2)."""
    values = errors(lambda cells: radial_case(symmetry, cells, degree, degree + 2), (6, 12, 24),
                    degree, scheme)
    assert orders(values).min() > ORDER[degree], (values, orders(values))


@pytest.mark.parametrize("symmetry", SYMMETRIES)
def test_radial_orders_q2_velocity(symmetry):
    """With the velocity interpolated in Q2, as the flow solver gives it, the strain rate is
    O(h^2) and the Q2 strain converges at order 2 (measured 1.95 to 1.98), as Q1 does: the
    velocity, not the scheme, limits Q2."""
    values = errors(lambda cells: radial_case(symmetry, cells, 2, 2), (6, 12, 24), 2, "supg")
    assert orders(values).min() > 1.85, (values, orders(values))
    assert orders(values).max() < 2.3, (values, orders(values))


# the largest over- or undershoot / jump measured over the step flows and positions
# (docs/strain_transport.md), rounded up
OVERSHOOT = {("supg", 1): 0.24, ("supg", 2): 0.20, ("upwind", 1): 0.41, ("upwind", 2): 0.40}
# the results change only where the step passes a quadrature point of the inflow side: these
# positions meet every range of equal results of Q1 and Q2 but the two at the cell's sides, which
# never gave the largest (docs/strain_transport.md)
POSITIONS = (0.25, 0.55, 0.85)


@pytest.mark.parametrize("scheme", SCHEMES)
@pytest.mark.parametrize("degree", DEGREES)
@pytest.mark.parametrize("flow", STEP_FLOWS)
def test_step_overshoot(flow, degree, scheme):
    """A step of the inflow strain at three positions within a cell: over- and undershoot within
    the stated bound of the scheme and element."""
    values = step_extremes(flow, 8, degree, scheme, POSITIONS)
    assert values.max() < OVERSHOOT[scheme, degree], values


def test_supg_overshoots_less_than_upwind():
    """The measured reason SUPG is the default: at every step position, carried across the
    mesh lines, SUPG's largest over- or undershoot is below upwind DG's (Q1 and Q2)."""
    for degree in DEGREES:
        supg, upwind = (step_extremes("across", 8, degree, scheme, POSITIONS).max(axis=1)
                        for scheme in SCHEMES)
        assert (supg < upwind).all(), (degree, supg, upwind)


def test_velocity_changed_on_one_rank():
    """A velocity changed on the last rank's dofs only is a new velocity on every rank (the
    cached solve is collective): eps is that of a fresh field, to 1e-12."""
    case = extension_case("plane_strain", 4, 1)
    field = transport(case, 1, "supg")
    field.solve(case.u)
    comm = case.mesh.comm
    index_map = case.u.function_space.dofmap.index_map
    ghosted = np.concatenate(comm.allgather(index_map.ghosts))  # global node numbers
    if comm.rank == comm.size - 1:  # a node no other rank holds
        start = index_map.local_range[0]
        node = next(i for i in range(index_map.size_local) if start + i not in ghosted)
        case.u.x.array[2 * node] *= 1.1
    fresh = transport(case, 1, "supg")
    difference = field.solve(case.u).x.array - fresh.solve(case.u).x.array
    assert comm.allreduce(np.abs(difference).max(), op=MPI.MAX) < 1e-12
    field.destroy()
    fresh.destroy()


def test_failed_iterative_solve_falls_back_to_lu():
    """The SUPG transport's GMRES with ILU(1) (strain_transport.SOLVER) agrees with MUMPS LU to
    1e-9 of the strain on the Q2 cone; held to 1 iteration it fails, repeats the solve by MUMPS LU
    (the same strain to rounding) and keeps LU for the next solves."""
    case = radial_case("axisymmetric", 8, 2, 2)
    strains = {}
    for name, options in (("lu", {"ksp_type": "preonly", "pc_type": "lu"}), ("ilu", None),
                          ("failing", {"ksp_max_it": 1, "ksp_rtol": 1e-14})):
        field = StrainField(case.u, case.coordinates, case.inflow, 2, 6, options=options)
        strains[name] = field.solve(case.u).x.array.copy()
        strains[name + " type"] = field._system.ksp.getType()
        field.destroy()
    scale = np.abs(strains["lu"]).max()
    assert strains["ilu type"] == "gmres" and strains["failing type"] == "preonly"
    assert np.abs(strains["ilu"] - strains["lu"]).max() < 1e-9 * scale
    assert np.abs(strains["failing"] - strains["lu"]).max() < 1e-12 * scale


# -- the tables of docs/strain_transport.md ----------------------------------------------------


def report() -> None:
    """Print errors and orders on four meshes, overshoots at ten step positions and the cost."""
    comm = MPI.COMM_WORLD

    def say(*text) -> None:
        if comm.rank == 0:
            print(*text, flush=True)
    say("relative L2 errors on the meshes of the tests and one finer, orders")
    for symmetry in SYMMETRIES:
        for degree in DEGREES:
            for scheme in SCHEMES:
                for name, cells, make in (
                        ("extension", (4, 8, 16, 32),
                         lambda n: extension_case(symmetry, n, degree)),
                        ("radial v p+2", (6, 12, 24, 48),
                         lambda n: radial_case(symmetry, n, degree, degree + 2)),
                        ("radial v p", (6, 12, 24, 48),
                         lambda n: radial_case(symmetry, n, degree, degree))):
                    values = errors(make, cells, degree, scheme)
                    say(f"{symmetry:13} Q{degree} {scheme:6} {name:13} {cells}",
                        " ".join(f"{v:.3e}" for v in values), np.round(orders(values), 2))
    say("a smooth inflow strain 0.2 + 0.3 sin(2 s), s = y - x tan(a), carried by the parallel flow"
        " at a to the inflow side y = 0 (8, 16, 32 cells): errors, orders")
    for angle in (20.0, 40.0):
        for degree in DEGREES:
            for scheme in SCHEMES:
                values = errors(lambda n: oblique_case(angle, n, degree), (8, 16, 32), degree,
                                scheme)
                say(f"{angle:4} deg Q{degree} {scheme:6}", " ".join(f"{v:.3e}" for v in values),
                    np.round(orders(values), 2))
    positions = tuple(np.arange(0.05, 1.0, 0.1))
    say(f"step positions {np.round(positions, 2)}: max(over, under)/jump, worst (over, under)")
    for flow in STEP_FLOWS:
        for degree in DEGREES:
            for scheme in SCHEMES:
                for count in (8, 16):
                    values = step_extremes(flow, count, degree, scheme, positions)
                    say(f"{flow:6} Q{degree} {scheme:6} {count:2} cells",
                        np.round(values.max(axis=1), 3), np.round(values.max(axis=0), 3))
    say("cost on the cone flow, 64 cells across (the velocity of the strain's degree):"
        " dofs, seconds to assemble and solve (twice)")
    for degree in DEGREES:
        case = radial_case("axisymmetric", 64, degree, degree)
        for scheme in SCHEMES:
            seconds = []
            for _ in range(2):
                field = transport(case, degree, scheme)
                comm.barrier()
                start = time.perf_counter()
                field.solve(case.u)
                seconds.append(comm.allreduce(time.perf_counter() - start, op=MPI.MAX))
                dofs = field.space.dofmap.index_map.size_global
                field.destroy()
            say(f"Q{degree} {scheme:6} dofs {dofs:6} solve {seconds[0]:.3f} {seconds[1]:.3f}")


if __name__ == "__main__":
    report()


@pytest.mark.parametrize("tangent_from", [0.0, 0.01])
def test_a_start_near_the_answer_takes_the_strain_of_its_velocity(tangent_from):
    """start_at(u) (a restart, a free surface's update): eps is the transport of u at once, the
    first freeze at the same u changes nothing (to 1e-12), and Newton's step (tangent_from > 0)
    carries the strain's derivative from the start; the gain stays measured from the inflow
    strain. The secant methods' freezes stay relaxed."""
    case = extension_case("plane_strain", 4, 1)
    field = StrainField(case.u, case.coordinates, case.inflow, 1, 4, "supg",
                        tangent_from=tangent_from)
    inflow = field.eps.x.array.copy()
    field.start_at(case.u)
    settled = field.eps.x.array.copy()
    assert np.abs(settled - inflow).max() > 0.1
    assert field.in_tangent == (tangent_from > 0)
    assert np.allclose(field._start.x.array, inflow, rtol=0, atol=1e-14)
    field.freeze(case.u)
    assert np.abs(field.eps.x.array - settled).max() < 1e-12
    assert field.change(case.u) < 1e-12
    field.destroy()

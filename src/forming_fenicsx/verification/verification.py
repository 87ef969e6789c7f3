"""Problems with exact solutions (verification.md), solved with the production forms and solver.

Power-law channel (Poiseuille) flow: between walls at y = +-h, driven by a pressure gradient G (a
body force here), u(y) = n/(n+1) (G/K)^(1/n) [h^(1+1/n) - |y|^(1+1/n)] with K = (A/sqrt3) 3^(-n/2).
"""
from __future__ import annotations

from collections.abc import Callable

import dolfinx.fem
import dolfinx.mesh
import numpy as np
import ufl
from mpi4py import MPI
from petsc4py import PETSc

from forming_fenicsx.physics.closed_forms import radial_flow_stress_rise
from forming_fenicsx.core.compat import GHOST_MODE, function_space, mesh_from_gmsh
from forming_fenicsx.coupled.coupling import coupled_problem
from forming_fenicsx.fem.forms import FlowProblem
from forming_fenicsx.mesh.geometry import FormingMesh
from forming_fenicsx.config.loader import scene_from_dict
from forming_fenicsx.solvers.choice import solver_for
from forming_fenicsx.solvers.records import SolveResult
from forming_fenicsx.solvers.secant import SecantSolver

LENGTH, HALF_HEIGHT, GRADIENT, A = 2.0, 1.0, 1.0, 1.0


def channel_velocity(n: float, y):
    """The exact channel-flow velocity u_x(y) for the power law sigma_p = A rate^n (numpy or
    UFL)."""
    K = A / 3**0.5 * 3 ** (-n / 2)
    return (n / (n + 1) * (GRADIENT / K) ** (1 / n)
            * (HALF_HEIGHT ** (1 + 1 / n) - abs(y) ** (1 + 1 / n)))


def channel_errors(n: float, element: str, averaging: str, cells: int,
                   comm: MPI.Comm = MPI.COMM_WORLD) -> tuple[float, float]:
    """L2 and H1-seminorm velocity errors on the half channel [0, 2] x [0, 1] with 2 cells x cells
    elements: exact velocity on the wall and the ends, symmetry at y = 0, the pressure gradient as
    a body force."""
    mesh = dolfinx.mesh.create_rectangle(comm,
                                         [np.array([0.0, 0.0]), np.array([LENGTH, HALF_HEIGHT])],
                                         [2 * cells, cells], dolfinx.mesh.CellType.quadrilateral,
                                         ghost_mode=GHOST_MODE)
    mesh.topology.create_connectivity(1, 2)
    scene = scene_from_dict({
        "process": {"kind": "extrusion"}, "output": {"fields": False, "figures": False},
        "material": {"law": "rate_power", "A": A, "n": n, "rate_floor": 1e-10},
        "discretisation": {"element": element, "averaging": averaging}, "penalty": {"d": 1e-7},
        "solver": {"method": "direct", "tolerance": 1e-8, "max_iterations": 500,
                   "reference_strain_rate": 1.0}})
    none = np.array([], dtype=np.int32)
    problem = FlowProblem(scene, FormingMesh(mesh, dolfinx.mesh.meshtags(mesh, 1, none, none),
                                             {}, []))
    wall_velocity = dolfinx.fem.Function(problem.V)
    wall_velocity.interpolate(lambda x: np.vstack([channel_velocity(n, x[1]), 0 * x[0]]))
    walls = dolfinx.mesh.locate_entities_boundary(
        mesh, 1, lambda x: (np.isclose(x[1], HALF_HEIGHT) | np.isclose(x[0], 0)
                            | np.isclose(x[0], LENGTH)))
    axis = dolfinx.mesh.locate_entities_boundary(mesh, 1, lambda x: np.isclose(x[1], 0))
    problem.bcs = [
        dolfinx.fem.dirichletbc(wall_velocity,
                                dolfinx.fem.locate_dofs_topological(problem.V, 1, walls)),
        dolfinx.fem.dirichletbc(PETSc.ScalarType(0), dolfinx.fem.locate_dofs_topological(
            problem.V.sub(1), 1, axis), problem.V.sub(1))]
    problem.L = dolfinx.fem.form(GRADIENT * ufl.TestFunction(problem.V)[0] * ufl.dx)
    if not SecantSolver(problem).solve().converged:
        raise RuntimeError(f"channel flow n = {n}, {element}, {averaging}, {cells} cells "
                           "did not converge")
    y = ufl.SpatialCoordinate(mesh)[1]
    error = problem.u - ufl.as_vector([channel_velocity(n, y), 0])
    dx = ufl.dx(metadata={"quadrature_degree": 10})

    def norm(integrand):
        return float(np.sqrt(comm.allreduce(
            dolfinx.fem.assemble_scalar(dolfinx.fem.form(integrand * dx)))))
    return norm(ufl.inner(error, error)), norm(ufl.inner(ufl.grad(error), ufl.grad(error)))


def channel_orders(n: float, element: str, averaging: str, cells=(4, 8, 16)
                   ) -> tuple[np.ndarray, np.ndarray]:
    """Errors (rows: meshes; columns: L2, H1) and the observed orders between successive meshes."""
    errors = np.array([channel_errors(n, element, averaging, c) for c in cells])
    return errors, np.log2(errors[:-1] / errors[1:])


# -- radial flows through a smooth cone (axisymmetric) or wedge (plane strain) ---------------------
# Section 1 of the round-products reference: v = -(U/rho^2) e_rho (cone) or -(U/r) e_r (wedge)
# toward the apex, for any flow law; the workpiece between the caps rho1 < rho < rho0, frictionless
# wall at theta = alpha. Apex at the origin, flow along +x: x = -rho cos(theta), y = rho sin(theta).
RADIAL = {"alpha": 15.0, "rho1": 1.0, "rho0": 1.5, "U": 1.0, "K": 1.0}


def radial_power(symmetry: str) -> int:
    """The power of 1/rho in the radial velocity: 2 for the cone, 1 for the wedge."""
    return 2 if symmetry == "axisymmetric" else 1


def radial_velocity(symmetry: str, x):
    """The exact velocity -(U/rho^k) e_rho at the points x (UFL coordinates or a numpy (3, N)
    array)."""
    power, U = radial_power(symmetry), RADIAL["U"]
    rho = (x[0] ** 2 + x[1] ** 2) ** 0.5
    # e_rho = (x, y)/rho points away from the apex (upstream); the flow runs toward it
    return [-U / rho ** (power + 1) * x[0], -U / rho ** (power + 1) * x[1]]


def radial_stress_rise(symmetry: str, n: float) -> float:
    """sigma_rr(rho1) - sigma_rr(rho0) of the exact flow between the caps of RADIAL for the Norton
    law sigma = K rate^n (closed_forms.radial_flow_stress_rise with flux U)."""
    return radial_flow_stress_rise(RADIAL["rho0"], RADIAL["rho1"], RADIAL["K"], n, RADIAL["U"],
                                   symmetry)


def add_sector(cells: int, grading: float = 1.0, structured: bool = True) -> None:
    """The sector rho1 < rho < rho0, 0 < theta < alpha in the current gmsh session, unmeshed:
    exit cap gamma1 (its velocity prescribed by the caller), entry cap gamma2 (free), wall gamma3
    (die), axis gamma6. ``structured``: a transfinite block of ``cells`` elements across the angle
    and as many along rho, graded toward the exit cap by ``grading`` (largest/smallest element,
    where the strain rate 2U/rho^3 peaks); else the bare surface for a size field
    (mesh/adapted.py)."""
    import gmsh

    from forming_fenicsx.core.roles import ROLES, WORKPIECE
    from forming_fenicsx.mesh.grading import graded_edge

    alpha = np.radians(RADIAL["alpha"])
    rho0, rho1 = RADIAL["rho0"], RADIAL["rho1"]
    geo = gmsh.model.geo
    centre = geo.addPoint(0, 0, 0)
    corners = [geo.addPoint(-r * np.cos(t), r * np.sin(t), 0)
               for r, t in ((rho0, 0), (rho1, 0), (rho1, alpha), (rho0, alpha))]
    axis = geo.addLine(corners[0], corners[1])
    exit_cap = geo.addCircleArc(corners[1], centre, corners[2])
    wall = geo.addLine(corners[2], corners[3])
    entry_cap = geo.addCircleArc(corners[3], centre, corners[0])
    surface = geo.addPlaneSurface([geo.addCurveLoop([axis, exit_cap, wall, entry_cap])])
    if structured:
        along = max(1, round(cells * (rho0 - rho1) / (rho1 * alpha)))
        _, ratio = graded_edge(rho0 - rho1, (rho0 - rho1) / along, grading, toward_end=True)
        for curve, count, progression in ((axis, along, ratio), (wall, along, 1.0 / ratio),
                                          (exit_cap, cells, 1.0), (entry_cap, cells, 1.0)):
            geo.mesh.setTransfiniteCurve(curve, count + 1, "Progression", progression)
        geo.mesh.setTransfiniteSurface(surface)
    geo.mesh.setRecombine(2, surface)
    geo.synchronize()
    gmsh.model.addPhysicalGroup(2, [surface], WORKPIECE)
    for curve, role in ((exit_cap, "gamma1_velocity"), (entry_cap, "gamma2_free"),
                        (wall, "gamma3_contact"), (axis, "gamma6_symmetry")):
        gmsh.model.addPhysicalGroup(1, [curve], ROLES[role])


def sector_mesh(cells: int, degree: int, comm: MPI.Comm = MPI.COMM_WORLD, grading: float = 1.0,
                generate: Callable[[], None] | None = None) -> FormingMesh:
    """The sector of add_sector meshed in Gmsh (isoparametric Q_degree), or by ``generate`` on
    rank 0 (an adapted mesh of it, solvers/accuracy.adapted_mesh)."""
    import gmsh

    from forming_fenicsx.config.mesh_file import gmsh_session
    from forming_fenicsx.core.roles import ROLES
    from forming_fenicsx.mesh.geometry import mesh_model

    with gmsh_session():
        if comm.rank == 0:
            if generate is None:
                add_sector(cells, grading)
                mesh_model(2, degree)
            else:
                generate()
        mesh, _, facet_tags = mesh_from_gmsh(gmsh.model, comm, 0, gdim=2)
    roles = {role: ROLES[role]
             for role in ("gamma1_velocity", "gamma2_free", "gamma3_contact", "gamma6_symmetry")}
    return FormingMesh(mesh, facet_tags, roles, [])


def radial_hardening_stress_rise(symmetry: str, law, points: int = 200) -> float:
    """sigma_rr(rho1) - sigma_rr(rho0) of the exact flow between the caps of RADIAL for any flow law
    sigma(rate, eps) (a hardening law's initial_strain on the entry cap): int_rho1^rho0 c sigma/rho
    d rho by Gauss-Legendre, with the cone's c = 2, rate = 2U/rho^3, eps = eps0 + 2 ln(rho0/rho),
    or the wedge's c = 2/sqrt3, rate = (2/sqrt3) U/r^2, eps = eps0 + (2/sqrt3) ln(r0/r)."""
    U, rho0, rho1 = RADIAL["U"], RADIAL["rho0"], RADIAL["rho1"]
    nodes, weights = np.polynomial.legendre.leggauss(points)
    rho = rho1 + (rho0 - rho1) * (nodes + 1) / 2
    if symmetry == "axisymmetric":
        factor, rate = 2.0, 2 * U / rho**3
    else:
        factor, rate = 2 / np.sqrt(3), 2 / np.sqrt(3) * U / rho**2
    strain = law.initial_strain + factor * np.log(rho0 / rho)
    sigma = law.flow_stress(rate, strain)
    return float((rho0 - rho1) / 2 * np.sum(weights * factor * sigma / rho))


def radial_problem(symmetry: str, n: float, element: str, cells: int, method: str = "newton",
                   comm: MPI.Comm = MPI.COMM_WORLD, material: dict | None = None,
                   tolerance: float = 1e-8, forming_mesh: FormingMesh | None = None
                   ) -> FlowProblem:
    """Drawing through the smooth cone or wedge, to be solved by ``method``: the exit cap pulled at
    the exact velocity, the entry cap free (the exact sigma_rr is taken zero there), the wall a
    frictionless die, the Norton law sigma = K rate^n (or the scene ``material`` given, e.g. a
    hardening law, whose strain is then transported and coupled); on the uniform sector_mesh of
    ``cells``, or on ``forming_mesh`` (a sector_mesh graded or adapted)."""
    forming_mesh = forming_mesh or sector_mesh(cells, int(element[1]), comm)
    scene = scene_from_dict({
        "process": {"kind": "drawing", "velocity": RADIAL["U"]},
        "output": {"fields": False, "figures": False},
        "geometry": {"symmetry": symmetry,
                     **({"entry_diameter": 2 * RADIAL["rho0"], "exit_diameter": 2}
                        if symmetry == "axisymmetric" else {})},
        "material": material or {"law": "rate_power", "A": RADIAL["K"], "n": n},
        "discretisation": {"element": element, "averaging": "quadrature"},
        "penalty": {"d_relative": 1e-7, "d_N_relative": 1e-4},  # O(d) below Q2's error on 16 cells
        "solver": {"method": method, "tolerance": tolerance, "max_iterations": 300,
                   "reference_strain_rate": 2.0}})
    problem = coupled_problem(scene, forming_mesh)
    exit_velocity = dolfinx.fem.Function(problem.V)
    exit_velocity.interpolate(lambda x: np.vstack(radial_velocity(symmetry, x)))
    exit_facets = problem.role_facets("gamma1_velocity")
    axis_dofs = problem.boundary_dofs("gamma6_symmetry", 1)
    problem.bcs[:] = [dolfinx.fem.dirichletbc(exit_velocity, dolfinx.fem.locate_dofs_topological(
        problem.V, 1, exit_facets)),
        dolfinx.fem.dirichletbc(PETSc.ScalarType(0), axis_dofs, problem.V.sub(1))]
    return problem


def radial_flow(symmetry: str, n: float, element: str, cells: int, method: str = "newton",
                comm: MPI.Comm = MPI.COMM_WORLD, material: dict | None = None,
                tolerance: float = 1e-8) -> dict[str, float]:
    """The radial_problem on the uniform sector_mesh of ``cells``, solved by ``method``
    (radial_errors)."""
    problem = radial_problem(symmetry, n, element, cells, method, comm, material, tolerance)
    return radial_errors(problem, solve_radial(problem), n)


def solve_radial(problem: FlowProblem) -> SolveResult:
    """A radial_problem solved by its scene's method; one that does not converge raises."""
    solver = solver_for(problem)
    result = solver.solve()
    solver.destroy()
    if not result.converged:
        scene = problem.scene
        raise RuntimeError(f"radial flow {scene.geometry.symmetry} "
                           f"{scene.discretisation.element}: {result.reason}")
    return result


def radial_errors(problem: FlowProblem, result: SolveResult, n: float) -> dict[str, float]:
    """The L2 and H1-seminorm velocity errors of a solved radial_problem (relative to the exact
    field's norms) and the mean axial stress on the exit cap, F / (pi rho1^2 sin^2 alpha) (cone)
    or F / (rho1 sin alpha) (wedge), beside the exact sigma_rr(rho1) (radial_stress_rise, or
    radial_hardening_stress_rise; ``n`` the Norton law's exponent), and with a hardening law the
    mean exit strain beside the exact eps0 + ln(A0/A1)."""
    from forming_fenicsx.post.flux import mean_strain_through
    from forming_fenicsx.post.forces import reaction_on

    scene, comm = problem.scene, problem.comm
    symmetry = scene.geometry.symmetry
    x = ufl.SpatialCoordinate(problem.mesh)
    exact = ufl.as_vector(radial_velocity(symmetry, x))
    error = problem.u - exact
    dx = problem.coordinates.measure(ufl.dx(domain=problem.mesh, metadata={"quadrature_degree": 8}))

    def norm(integrand):
        return float(np.sqrt(comm.allreduce(
            dolfinx.fem.assemble_scalar(dolfinx.fem.form(integrand * dx)))))

    alpha, rho1 = np.radians(RADIAL["alpha"]), RADIAL["rho1"]
    area = problem.coordinates.section(rho1 * np.sin(alpha))
    law = scene.material
    found = {"l2": norm(ufl.inner(error, error)) / norm(ufl.inner(exact, exact)),
             "h1": (norm(ufl.inner(ufl.grad(error), ufl.grad(error)))
                    / norm(ufl.inner(ufl.grad(exact), ufl.grad(exact)))),
             "exit_stress": reaction_on(problem, "gamma1_velocity", 0) / area,
             "exact_exit_stress": (radial_hardening_stress_rise(symmetry, law) if law.hardens
                                   else radial_stress_rise(symmetry, n)),
             "linear_solves": result.linear_solves, "outer_iterations": result.outer_iterations}
    if law.hardens:
        factor = 2.0 if symmetry == "axisymmetric" else 2 / np.sqrt(3)
        found["exit_strain"] = mean_strain_through(problem)
        found["exact_exit_strain"] = law.initial_strain + factor * np.log(RADIAL["rho0"] / rho1)
    return found


def homogeneous_extension(element: str, method: str, formulation: str = "penalty",
                          comm: MPI.Comm = MPI.COMM_WORLD) -> dict[str, float]:
    """A bar [0, 2] x [0, 1] (radius 1) pulled along its axis: u_x = 0 on x = 0, u_x = 2 rate0 on
    x = 2, free lateral surface, Norton law sigma = K rate^n (n = 0.2). Exact: u = rate0 (x, -y/2),
    sigma_xx = sigma(rate0), the other stresses zero. Returns the largest nodal velocity error over
    rate0 and the end force over pi R^2 sigma(rate0). The penalty's solution differs by O(d)
    (sigma_H = sigma/3 needs div u = d sigma/3, Theorem 3.1): d is 1e-6 rate0/sigma0 here."""
    from forming_fenicsx.mesh.geometry import Constraint
    from forming_fenicsx.post.forces import reaction

    rate, n, length = 0.5, 0.2, 2.0
    mesh = dolfinx.mesh.create_rectangle(comm, [np.array([0.0, 0.0]), np.array([length, 1.0])],
                                         [6, 3], dolfinx.mesh.CellType.quadrilateral,
                                         ghost_mode=GHOST_MODE)
    facets = {role: dolfinx.mesh.locate_entities_boundary(mesh, 1, where) for role, where in (
        ("gamma1_velocity", lambda x: np.isclose(x[0], length)),
        ("gamma2_free", lambda x: np.isclose(x[0], 0)),
        ("gamma4_free", lambda x: np.isclose(x[1], 1.0)),
        ("gamma6_symmetry", lambda x: np.isclose(x[1], 0)))}
    from forming_fenicsx.core.roles import ROLES

    indices = np.concatenate(list(facets.values()))
    values = np.concatenate([np.full(len(f), ROLES[role], dtype=np.int32)
                             for role, f in facets.items()])
    order = np.argsort(indices)
    tags = dolfinx.mesh.meshtags(mesh, 1, indices[order].astype(np.int32), values[order])
    constraints = [Constraint("gamma1_velocity", 0, rate * length),
                   Constraint("gamma2_free", 0, 0.0), Constraint("gamma6_symmetry", 1, 0.0)]
    scene = scene_from_dict({
        "process": {"kind": "drawing", "velocity": rate * length},
        "output": {"fields": False, "figures": False},
        "geometry": {"symmetry": "axisymmetric"},
        "material": {"law": "rate_power", "A": RADIAL["K"], "n": n},
        "discretisation": {"element": element, "formulation": formulation,
                           "averaging": "quadrature" if method == "newton" else "nodes"},
        "penalty": {"d_relative": 1e-6},
        "solver": {"method": method, "tolerance": 1e-8, "reference_strain_rate": 0.1}})
    problem = coupled_problem(scene, FormingMesh(mesh, tags, {role: ROLES[role] for role in facets},
                                                 constraints))
    solver = solver_for(problem)
    result = solver.solve()
    solver.destroy()
    if not result.converged:
        raise RuntimeError(f"homogeneous extension {element} {method}: {result.reason}")
    points = problem.V.tabulate_dof_coordinates()
    exact = np.column_stack([rate * points[:, 0], -rate * points[:, 1] / 2])
    error = np.abs(problem.u.x.array.reshape(-1, 2) - exact).max() / rate
    return {"velocity_error": comm.allreduce(error, op=MPI.MAX),
            "force_ratio": reaction(problem) / (np.pi * RADIAL["K"] * rate**n),
            "solves": result.linear_solves}


WAVE_AMPLITUDE, WAVE_NUMBER = 0.1, 2.0


def wavy_streamlines(degree: int, cells: int, axisymmetric: bool, back: float = 0.0
                     ) -> tuple[dolfinx.fem.Function, Callable[[np.ndarray, float], np.ndarray]]:
    """A divergence-free field (plane, or axisymmetric with y the radius) whose streamlines are
    y = c s(x), s = 1 + 0.1 sin(2x), the axis y = 0 among them (stream function y/s, or
    y^2/(2 s^2)), interpolated on Q1 or Q2 over [0, 2] x [0, 1] (2 cells x cells); ``back``
    subtracted from u_x for x > 1 (a flow that runs back there). Returns it and the exact
    streamline y(x, c). The free surface's check (docs/free_surface.md)."""
    mesh = dolfinx.mesh.create_rectangle(
        MPI.COMM_WORLD, [np.array([0.0, 0.0]), np.array([2.0, 1.0])], [2 * cells, cells],
        dolfinx.mesh.CellType.quadrilateral)
    u = dolfinx.fem.Function(function_space(mesh, "P", degree, (2,)))
    power = 2 if axisymmetric else 1

    def shape(x: np.ndarray) -> np.ndarray:
        return 1 + WAVE_AMPLITUDE * np.sin(WAVE_NUMBER * x)

    def field(p: np.ndarray) -> np.ndarray:
        s = shape(p[0])
        ds = WAVE_AMPLITUDE * WAVE_NUMBER * np.cos(WAVE_NUMBER * p[0])
        return np.vstack([s ** -power - back * (p[0] > 1.0), p[1] * ds * s ** (-power - 1)])

    u.interpolate(field)
    return u, lambda x, c: c * shape(x)


def wavy_stream_surface(degree: int, cells: int, drift: float = 0.2
                        ) -> tuple[dolfinx.fem.Function, Callable[[np.ndarray, np.ndarray],
                                                                  np.ndarray]]:
    """The 3D field u = (1/s, y s'/s^2, drift), s = 1 + 0.1 sin(2x) (divergence-free), on Q1 or
    Q2 over [0, 2] x [0, 1] x [0, 1] (2 cells x cells x cells): its streamlines keep y/s(x) and
    drift in z by drift S(x), S = int_0^x s. Returns it and the exact stream surface y = h(x, z)
    through the curve y = 0.5 (1 + 0.2 z) at x = 0 (continued to z < 0), h = 0.5 (1 + 0.2 (z -
    drift S(x))) s(x): the least-squares surface's check over (x, z) (docs/verification.md)."""
    mesh = dolfinx.mesh.create_box(
        MPI.COMM_WORLD, [np.array([0.0, 0.0, 0.0]), np.array([2.0, 1.0, 1.0])],
        [2 * cells, cells, cells], dolfinx.mesh.CellType.hexahedron)
    u = dolfinx.fem.Function(function_space(mesh, "P", degree, (3,)))

    def shape(x: np.ndarray) -> np.ndarray:
        return 1 + WAVE_AMPLITUDE * np.sin(WAVE_NUMBER * x)

    def field(p: np.ndarray) -> np.ndarray:
        s = shape(p[0])
        ds = WAVE_AMPLITUDE * WAVE_NUMBER * np.cos(WAVE_NUMBER * p[0])
        return np.vstack([1 / s, p[1] * ds / s**2, np.full(p.shape[1], drift)])

    def exact(x: np.ndarray, z: np.ndarray) -> np.ndarray:
        travelled = x + WAVE_AMPLITUDE / WAVE_NUMBER * (1 - np.cos(WAVE_NUMBER * x))
        return 0.5 * (1 + 0.2 * (z - drift * travelled)) * shape(x)

    u.interpolate(field)
    return u, exact

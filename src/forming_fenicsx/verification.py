"""Problems with exact solutions (verification.md), solved with the production forms and solver.

Power-law channel (Poiseuille) flow: between walls at y = +-h, driven by a pressure gradient G (a body
force here), u(y) = n/(n+1) (G/K)^(1/n) [h^(1+1/n) - |y|^(1+1/n)] with K = (A/sqrt3) 3^(-n/2).
"""
from __future__ import annotations

import dolfinx.fem
import dolfinx.mesh
import numpy as np
import ufl
from mpi4py import MPI
from petsc4py import PETSc

from .forms import FlowProblem
from .geometry import FormingMesh
from .scene import scene_from_dict
from .solvers import SecantSolver

LENGTH, HALF_HEIGHT, GRADIENT, A = 2.0, 1.0, 1.0, 1.0


def channel_velocity(n: float, y):
    """The exact channel-flow velocity u_x(y) for the power law sigma_p = A rate^n (numpy or UFL)."""
    K = A / 3**0.5 * 3 ** (-n / 2)
    return n / (n + 1) * (GRADIENT / K) ** (1 / n) * (HALF_HEIGHT ** (1 + 1 / n) - abs(y) ** (1 + 1 / n))


def channel_errors(n: float, element: str, averaging: str, cells: int,
                   comm: MPI.Comm = MPI.COMM_WORLD) -> tuple[float, float]:
    """L2 and H1-seminorm velocity errors on the half channel [0, 2] x [0, 1] with 2 cells x cells elements:
    exact velocity on the wall and the ends, symmetry at y = 0, the pressure gradient as a body force."""
    mesh = dolfinx.mesh.create_rectangle(comm, [np.array([0.0, 0.0]), np.array([LENGTH, HALF_HEIGHT])],
                                         [2 * cells, cells], dolfinx.mesh.CellType.quadrilateral)
    mesh.topology.create_connectivity(1, 2)
    scene = scene_from_dict({
        "process": {"kind": "extrusion"}, "output": {"fields": False, "figures": False},
        "material": {"law": "power", "A": A, "n": n, "rate_floor": 1e-10},
        "discretisation": {"element": element, "averaging": averaging}, "penalty": {"d": 1e-7},
        "solver": {"method": "direct", "tolerance": 1e-8, "max_iterations": 500, "reference_strain_rate": 1.0}})
    none = np.array([], dtype=np.int32)
    problem = FlowProblem(scene, FormingMesh(mesh, dolfinx.mesh.meshtags(mesh, 1, none, none), {}, []))
    wall_velocity = dolfinx.fem.Function(problem.V)
    wall_velocity.interpolate(lambda x: np.vstack([channel_velocity(n, x[1]), 0 * x[0]]))
    walls = dolfinx.mesh.locate_entities_boundary(
        mesh, 1, lambda x: np.isclose(x[1], HALF_HEIGHT) | np.isclose(x[0], 0) | np.isclose(x[0], LENGTH))
    axis = dolfinx.mesh.locate_entities_boundary(mesh, 1, lambda x: np.isclose(x[1], 0))
    problem.bcs = [dolfinx.fem.dirichletbc(wall_velocity, dolfinx.fem.locate_dofs_topological(problem.V, 1, walls)),
                   dolfinx.fem.dirichletbc(PETSc.ScalarType(0), dolfinx.fem.locate_dofs_topological(
                       problem.V.sub(1), 1, axis), problem.V.sub(1))]
    problem.L = dolfinx.fem.form(GRADIENT * ufl.TestFunction(problem.V)[0] * ufl.dx)
    if not SecantSolver(problem).solve().converged:
        raise RuntimeError(f"channel flow n = {n}, {element}, {averaging}, {cells} cells did not converge")
    y = ufl.SpatialCoordinate(mesh)[1]
    error = problem.u - ufl.as_vector([channel_velocity(n, y), 0])
    dx = ufl.dx(metadata={"quadrature_degree": 10})

    def norm(integrand):
        return float(np.sqrt(comm.allreduce(dolfinx.fem.assemble_scalar(dolfinx.fem.form(integrand * dx)))))
    return norm(ufl.inner(error, error)), norm(ufl.inner(ufl.grad(error), ufl.grad(error)))


def channel_orders(n: float, element: str, averaging: str, cells=(4, 8, 16)) -> tuple[np.ndarray, np.ndarray]:
    """Errors (rows: meshes; columns: L2, H1) and the observed orders between successive meshes."""
    errors = np.array([channel_errors(n, element, averaging, c) for c in cells])
    return errors, np.log2(errors[:-1] / errors[1:])

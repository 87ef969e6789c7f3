"""Exact homogeneous solutions of the flow law (verification.md), solved by the secant iteration.

The whole boundary of a rectangle carries the exact velocity; the first, uniform-modulus solve
already reproduces it, the secant update then gives the law's stress: plane-strain compression
sigma_xx - sigma_yy = 2k, simple shear sigma_xy = sigma_p(gamma/sqrt3)/sqrt3.
"""
import dolfinx.fem
import dolfinx.mesh
import numpy as np
import pytest
from mpi4py import MPI

from forming_fenicsx.fem.forms import FlowProblem
from forming_fenicsx.mesh.geometry import FormingMesh
from forming_fenicsx.fem.projection import cell_means
from forming_fenicsx.solvers.secant import SecantSolver

from conftest import make_scene

LAWS = {"piecewise_power": {"law": "piecewise_power", "A": 3**0.5, "alpha": 0.2, "rate1": 1e-2,
                            "rate2": 1e2},
        "power": {"law": "rate_power", "A": 2.0, "n": 0.4, "rate_floor": 1e-6}}


def solve_box(material: dict, element: str, averaging: str, exact) -> FlowProblem:
    mesh = dolfinx.mesh.create_rectangle(MPI.COMM_WORLD,
                                         [np.array([0.0, 0.0]), np.array([2.0, 1.0])], [6, 3],
                                         dolfinx.mesh.CellType.quadrilateral)
    mesh.topology.create_connectivity(1, 2)
    facets = dolfinx.mesh.locate_entities_boundary(mesh, 1, lambda x: np.full(x.shape[1], True))
    tags = dolfinx.mesh.meshtags(mesh, 1, facets, np.full(len(facets), 7, dtype=np.int32))
    scene = make_scene(material=material,
                       discretisation={"element": element, "averaging": averaging},
                       solver={"method": "direct", "tolerance": 1e-10})
    problem = FlowProblem(scene, FormingMesh(mesh, tags, roles={}, constraints=[]))
    boundary_velocity = dolfinx.fem.Function(problem.V)
    boundary_velocity.interpolate(exact)
    problem.bcs = [dolfinx.fem.dirichletbc(
        boundary_velocity, dolfinx.fem.locate_dofs_topological(problem.V, 1, facets))]
    result = SecantSolver(problem).solve()
    assert result.converged and result.linear_solves <= 3
    problem.update_state(problem.u, frozen_too=True)
    return problem


def cell_values(problem: FlowProblem, expr) -> np.ndarray:
    owned = problem.mesh.topology.index_map(2).size_local
    return cell_means(problem.mesh, expr, "check", problem.full_degree).x.array[:owned]


@pytest.mark.parametrize("law", LAWS)
@pytest.mark.parametrize("element", ["Q1", "Q2"])
@pytest.mark.parametrize("averaging", ["nodes", "centres"])
@pytest.mark.parametrize("rate0", [1e-4, 0.7, 300.0])
def test_plane_strain_compression_gives_2k(law, element, averaging, rate0):
    problem = solve_box(LAWS[law], element, averaging,
                        lambda x: np.vstack([rate0 * x[0], -rate0 * x[1]]))
    sigma = problem.stress()
    difference = cell_values(problem, sigma[0, 0] - sigma[1, 1])
    two_k = 2 * problem.scene.material.flow_stress(np.array([2 / 3**0.5 * rate0]))[0] / 3**0.5
    assert np.max(np.abs(difference / two_k - 1)) < 1e-6


@pytest.mark.parametrize("law", LAWS)
@pytest.mark.parametrize("element", ["Q1", "Q2"])
def test_simple_shear(law, element):
    shear = 5.0
    problem = solve_box(LAWS[law], element, "nodes", lambda x: np.vstack([shear * x[1], 0 * x[0]]))
    tau = cell_values(problem, problem.stress()[0, 1])
    expected = problem.scene.material.flow_stress(np.array([shear / 3**0.5]))[0] / 3**0.5
    assert np.max(np.abs(tau / expected - 1)) < 1e-6

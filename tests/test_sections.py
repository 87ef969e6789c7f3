"""Section means of the axial stress (sections.py) and the element-wise L2 projection behind
them."""
from __future__ import annotations

import math

import dolfinx.fem
import dolfinx.mesh
import numpy as np
import pytest
import ufl
from mpi4py import MPI

from forming_fenicsx.core.compat import function_space
from forming_fenicsx.fem.projection import project_discontinuous
from forming_fenicsx.app.run import solve_scene
from forming_fenicsx.config.loader import scene_from_dict
from forming_fenicsx.post.sections import mean_axial_stress, values_at


def test_discontinuous_projection_is_exact_on_its_space_and_skips_the_axis():
    """x^2 y + y (in DQ2) is reproduced to rounding, and u_y/y with u_y = x y, 0/0 on the axis
    y = 0 for an interpolation, projects to x with no NaN."""
    mesh = dolfinx.mesh.create_unit_square(MPI.COMM_WORLD, 3, 4,
                                           dolfinx.mesh.CellType.quadrilateral)
    x = ufl.SpatialCoordinate(mesh)
    target = dolfinx.fem.Function(function_space(mesh, "DP", 2))
    project_discontinuous(x[0] ** 2 * x[1] + x[1], target, 4)
    exact = dolfinx.fem.Function(target.function_space)
    exact.interpolate(lambda p: p[0] ** 2 * p[1] + p[1])
    assert np.abs(target.x.array - exact.x.array).max() < 1e-12
    velocity = dolfinx.fem.Function(function_space(mesh, "P", 2, (2,)))
    velocity.interpolate(lambda p: np.vstack([0 * p[0], p[0] * p[1]]))
    project_discontinuous(velocity[1] / x[1], target, 4)
    exact.interpolate(lambda p: p[0])
    assert np.isfinite(target.x.array).all()
    assert np.abs(target.x.array - exact.x.array).max() < 1e-12


@pytest.fixture(scope="module", params=["axisymmetric", "plane_strain"])
def drawn(request):
    """A 2 -> 1.6 pass through a 10 degree die, friction factor 0.1, Newton on a coarse Q2 mesh."""
    ends = ("diameter" if request.param == "axisymmetric" else "thickness")
    scene = scene_from_dict({
        "process": {"kind": "drawing", "velocity": 1.0},
        "geometry": {"symmetry": request.param, f"entry_{ends}": 2.0, f"exit_{ends}": 1.6,
                     "die_angle": 10.0, "land_length": 0.0},
        "material": {"law": "piecewise_power", "A": 1.0},
        "friction": {"law": "factor", "m": 0.1},
        "discretisation": {"averaging": "quadrature", "mesh_size": 0.1},
        "solver": {"method": "newton"}, "output": {"fields": False, "figures": False}})
    problem, _, summary = solve_scene(scene)
    return scene, problem, summary


def test_section_means_carry_the_drawing_stress(drawn):
    """Downstream of the die every section carries the drawing force (no traction on the free
    surface): within 0.5 % of the reaction's drawing stress; upstream no force (the entry face is
    free): below 0.5 % of it; in the cone between the two."""
    scene, problem, summary = drawn
    g, stress = scene.geometry, summary["drawing_stress"]
    after = mean_axial_stress(problem, g.length - 0.5, 0.8 * (1 - 1e-9))
    before = mean_axial_stress(problem, 0.5 * g.die_entry, 1.0 * (1 - 1e-9))
    middle = mean_axial_stress(problem, g.die_entry + 0.5 * g.cone_length, 0.9)
    assert after == pytest.approx(stress, rel=5e-3)
    assert abs(before) < 5e-3 * stress
    assert 0.2 * stress < middle < 0.9 * stress


def test_a_point_outside_the_workpiece_is_refused(drawn):
    _, problem, _ = drawn
    with pytest.raises(ValueError, match="not in the workpiece"):
        values_at(problem, problem.u[0], np.array([[1.0, 5.0]]), 2)
    assert math.isfinite(values_at(problem, problem.u[0], np.array([[1.0, 0.5]]), 2)[0])

"""Three dimensions (issue 36) against plane strain, the axisymmetric model and an exact solution
(verification/three_d.py; docs/verification.md, "Three dimensions"): the one-element slab of a
strip, the 3D quarter of a round wire, the homogeneous extension of a box, and the contact where
two die faces meet."""
from __future__ import annotations

from pathlib import Path

import pytest
from mpi4py import MPI

from forming_fenicsx.config.loader import load_scene, scene_from_dict
from forming_fenicsx.coupled.coupling import coupled_problem
from forming_fenicsx.mesh.geometry import build_mesh
from forming_fenicsx.verification.three_d import (SLAB_FORCES, SLAB_RATIOS, edge_contact,
                                                  homogeneous_extension_3d, slab_comparison,
                                                  solved, wire_drawing)

DEMOS = Path(__file__).parents[1] / "demos"
SLAB = 0.4  # the strip's mesh size and the slab's thickness (mm)


@pytest.mark.parametrize("method, formulation, averaging", [
    ("newton", "penalty", "quadrature"), ("newton", "mixed", "quadrature"),
    ("direct", "penalty", "nodes")])
def test_slab_reproduces_plane_strain(method, formulation, averaging):
    """demos/strip_mm.toml (mu = 0.08) on a 0.4 mm mesh and as its 0.4 mm slab (Gamma7 on both
    sides: u_z = 0), solved to solver.tolerance 1e-8: the drawing stress, mean die pressure,
    contact length and end, and the forces per unit width agree to that tolerance, and both
    force balances hold to 1e-7 (the measured differences: docs/verification.md, "Three
    dimensions")."""
    scene = load_scene(DEMOS / "strip_mm.toml", [
        f"discretisation.mesh_size={SLAB}", f"discretisation.formulation={formulation}",
        f"discretisation.averaging={averaging}", f"solver.method={method}",
        "solver.tolerance=1e-8", "output.fields=false", "output.figures=false"])
    found = slab_comparison(scene, SLAB)
    plane, slab = found["plane_strain"], found["slab"]
    for key in (*SLAB_RATIOS, *SLAB_FORCES, "contact_length"):
        if key != "force_balance_residual":
            assert slab[key] == pytest.approx(plane[key], rel=scene.solver.tolerance), key
    assert max(plane["force_balance_residual"], slab["force_balance_residual"]) < 1e-7


@pytest.mark.parametrize("mu, within", [(0.0, 1e-3), (0.05, 1e-2)])
def test_round_wire_quarter(mu, within):
    """The copper-wire pass 2.0 -> 1.8 mm through a 6 degree die (WIRE) as the 3D quarter of the
    wire (hexahedra, an O-grid across the section) and axisymmetric (quadrilaterals), both at
    mesh size 0.45 mm: the drawing stresses agree within 1 % with friction (mu = 0.05) and 0.1 %
    without, and the quarter's force balance holds to 1e-8 (the meshes, the measured
    differences and finer pairs: docs/verification.md, "Three dimensions")."""
    quarter = wire_drawing("3d", 0.45, mu)
    axisymmetric = wire_drawing("axisymmetric", 0.45, mu)
    assert quarter["drawing_stress"] == pytest.approx(axisymmetric["drawing_stress"], rel=within)
    assert quarter["force_balance_residual"] < 1e-8


@pytest.mark.parametrize("element, method, formulation", [
    ("Q1", "direct", "penalty"), ("Q2", "modified", "penalty"), ("Q1", "newton", "penalty"),
    ("Q2", "newton", "penalty"), ("Q2", "newton", "mixed")])
def test_homogeneous_extension_3d(element, method, formulation):
    """u = rate0 (x, -y/2, -z/2) and the end force sigma(rate0) on the box's unit end: to 1e-6
    with the penalty (its O(d) volume change), to 1e-12 mixed, whose stress is exact too (1e-12
    of sigma(rate0) in L2)."""
    result = homogeneous_extension_3d(element, method, formulation)
    exact = 1e-12 if formulation == "mixed" else 1e-6
    assert result["velocity_error"] < exact
    assert result["force_ratio"] == pytest.approx(1.0, abs=exact)
    if formulation == "mixed":
        assert result["stress_error"] < 1e-12


def test_contact_at_die_edge():
    """A 4 x 6 -> 3.2 x 5 mm bar through an 8 degree die, mu = 0.05, on a 0.8 mm mesh: where the
    height and width faces meet, both contacts hold the edge as each holds its face. Within a
    mesh size of the edge the mean penetration velocity u_N^+ is at most 1.5 times the rest of
    the die's; the edge nodes' u.n against either face is at most twice the largest on the
    faces' own nodes and below 1e-3 of the drawing velocity; the force balance holds to 1e-9."""
    scene = scene_from_dict({
        "process": {"kind": "drawing", "velocity": 1.0},
        "geometry": {"symmetry": "3d", "entry_height": 4.0, "exit_height": 3.2,
                     "entry_width": 6.0, "exit_width": 5.0, "die_angle": 8.0},
        "material": {"law": "piecewise_power", "A": 300.0}, "friction": {"mu": 0.05},
        "discretisation": {"averaging": "quadrature", "mesh_size": 0.8},
        "solver": {"method": "newton"}, "output": {"fields": False, "figures": False}})
    problem = coupled_problem(scene, build_mesh(scene, MPI.COMM_WORLD))
    summary = solved(problem)
    found = edge_contact(problem)
    assert summary["force_balance_residual"] < 1e-9
    assert found["edge_nodes"] > 0
    assert found["edge_penetration"] < 1.5 * found["faces_penetration"]
    faces = max(found["top_node_normal_velocity"], found["side_node_normal_velocity"])
    assert found["edge_node_normal_velocity"] < 2 * faces
    assert found["edge_node_normal_velocity"] < 1e-3

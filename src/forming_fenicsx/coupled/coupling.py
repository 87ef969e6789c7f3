"""The coupled fields of a scene, built outside the flow problem and plugged into it
(FlowProblem.couple): the transported strain of a hardening law and the temperature of a scene
with [thermal], two way when the flow law reads it, else one way (settled from the converged flow).
"""
from __future__ import annotations

import numpy as np

from forming_fenicsx.config.scene import Scene
from forming_fenicsx.config.strain_profile import profile_values, read_strain_profile
from forming_fenicsx.coupled.strain_transport import TANGENT_FROM, StrainField, inflow_strain
from forming_fenicsx.coupled.thermal_scene import scene_temperature_field
from forming_fenicsx.fem.forms import FlowProblem
from forming_fenicsx.mesh.geometry import FormingMesh


def coupled_problem(scene: Scene, forming_mesh: FormingMesh) -> FlowProblem:
    """The scene's flow problem with its coupled fields plugged in."""
    problem = FlowProblem(scene, forming_mesh)
    couple_fields(problem)
    return problem


def couple_fields(problem: FlowProblem) -> None:
    """The strain field of a hardening law (transported into the law's strain coefficient,
    starting at the inflow strain everywhere; Newton carries its derivative after the relaxed
    steps, strain_tangent.py) and the temperature of a scene with [thermal]."""
    scene = problem.scene
    if problem.strain is not None:
        problem.couple(strain_field(problem))
    if scene.thermal is not None:
        field = scene_temperature_field(problem, temperature=problem.temperature)
        problem.couple(field, two_way=problem.temperature is not None)


def strain_field(problem: FlowProblem) -> StrainField:
    """The transported strain of the scene's hardening law: its inflow the law's initial strain or
    the profile of material.initial_strain_file (a previous pass's exit_strain.csv)."""
    scene, degree = problem.scene, problem.scene.discretisation.degree
    law = scene.material
    inflow = law.initial_strain
    profile = None
    if law.initial_strain_file is not None:  # a profile across the entry
        profile = read_strain_profile(law.initial_strain_file, "material.initial_strain_file")
        inflow = inflow_strain(problem.mesh, degree, profile, scene.geometry.entry_thickness / 2)
    field = StrainField(problem.u, problem.coordinates, inflow, degree, problem.full_degree,
                        tangent_from=TANGENT_FROM if scene.solver.method == "newton" else 0.0,
                        eps=problem.strain)
    if profile is None:
        field.eps.x.array[:] = inflow
    else:
        half = scene.geometry.entry_thickness / 2
        field.eps.interpolate(inflow)
        field.entry_strain = lambda points: profile_values(profile, np.abs(points[:, 1]), half)
    return field

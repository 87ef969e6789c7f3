"""Three-dimensional models checked against plane strain, the axisymmetric model and an exact
solution (issue 36; docs/verification.md, "Three dimensions"), solved with the production forms,
solvers and post-processing.

(a) A plane-strain scene and its one-element slab (mesh/slab.py) give the same numbers, the slab's
forces per unit width. (b) The 3D quarter of a round wire beside the axisymmetric model of the same
die and mesh size. (c) A box pulled at a uniform rate: the homogeneous extension u = rate0 (x, -y/2,
-z/2), sigma_xx = sigma_p(rate0), exact in Q1 and Q2. And the contact where two die faces meet.
"""
from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import dolfinx.fem
import dolfinx.mesh
import numpy as np
import ufl
from mpi4py import MPI

from forming_fenicsx.config.loader import scene_from_dict
from forming_fenicsx.config.scene import Scene
from forming_fenicsx.core.compat import GHOST_MODE
from forming_fenicsx.core.roles import ROLES
from forming_fenicsx.coupled.coupling import coupled_problem
from forming_fenicsx.fem.forms import FlowProblem
from forming_fenicsx.mesh.geometry import Constraint, FormingMesh, build_mesh
from forming_fenicsx.mesh.slab import slab_mesh
from forming_fenicsx.physics import contact
from forming_fenicsx.post.forces import force_balance, reaction
from forming_fenicsx.post.integrals import integrate
from forming_fenicsx.post.summary import scalars
from forming_fenicsx.solvers.choice import solver_for

# the summary's forces; a slab's are the strip's per unit width over twice its thickness
SLAB_FORCES = ("drawing_force", "die_force_x", "die_normal_force_x", "die_friction_force_x",
               "die_separation_force")
# the summary's ratios, the same in the slab and the strip
SLAB_RATIOS = ("drawing_stress", "mean_die_pressure", "contact_end_x", "die_contact_fraction",
               "force_balance_residual")


def solved(problem: FlowProblem) -> dict[str, Any]:
    """The problem solved by its scene's method (solver_for, with the force balance criterion a
    hardening run needs) and its summary numbers (post/summary.py), as app/run.py's solve_scene
    computes them, with its cells and unknowns; a run that does not converge raises."""
    solver = solver_for(problem, balance=lambda: force_balance(problem)[0])
    result = solver.solve()
    solver.destroy()
    if not result.converged:
        raise RuntimeError(f"{problem.scene.geometry.symmetry} run: {result.reason}")
    problem.update_state(problem.u, frozen_too=True)
    cells = problem.mesh.topology.index_map(problem.mesh.topology.dim).size_global
    return {**scalars(problem), "linear_solves": result.linear_solves,
            "unknowns": problem.unknowns, "cells": cells}


def slab_comparison(scene: Scene, thickness: float, comm: MPI.Comm = MPI.COMM_WORLD
                    ) -> dict[str, dict[str, float]]:
    """The plane-strain ``scene`` on its own mesh and as its slab of ``thickness``: SLAB_RATIOS
    and SLAB_FORCES (per unit width of the strip) and the contact length of each, with their
    linear solves and unknowns.

    The slab's FlowProblem counts Gamma6 and Gamma7 as two symmetry planes (whole = 4): its
    summary is that of the slab and its mirror image in z = 0, a strip 2 ``thickness`` wide whose
    die contact area is 2 contact lengths times that width."""
    plane = solved(coupled_problem(scene, build_mesh(scene, comm)))
    slab_scene, forming_mesh = slab_mesh(scene, thickness, comm)
    slab = solved(coupled_problem(slab_scene, forming_mesh))
    width = 2 * thickness
    slab.update({key: slab[key] / width for key in SLAB_FORCES})
    slab["contact_length"] = slab["contact_area"] / (2 * width)
    keys = (*SLAB_RATIOS, *SLAB_FORCES, "contact_length", "linear_solves", "unknowns", "cells")
    return {"plane_strain": {key: plane[key] for key in keys},
            "slab": {key: slab[key] for key in keys}}


# A copper-wire pass (demos/copper_wire.toml) with its die placed as the 3D model places it: the
# stock one entry diameter long, 1.5 exit diameters of product after the land
WIRE = {"entry_diameter": 2.0, "exit_diameter": 1.8, "die_angle": 6.0, "land_length": 0.5,
        "die_entry": 2.0}


def wire_scene(symmetry: str, mesh_size: float, mu: float, tolerance: float = 1e-8) -> Scene:
    """The WIRE pass, axisymmetric or as the 3D quarter of the round wire (symmetry = "3d"), at
    the given mesh size: the same die, lengths, material, friction and penalties in both."""
    cone = 0.5 * (WIRE["entry_diameter"] - WIRE["exit_diameter"]) / math.tan(
        math.radians(WIRE["die_angle"]))
    length = WIRE["die_entry"] + cone + WIRE["land_length"] + 1.5 * WIRE["exit_diameter"]
    geometry = {**WIRE, "symmetry": symmetry, "length": length,
                **({"section": "round"} if symmetry == "3d" else {})}
    return scene_from_dict({
        "process": {"kind": "drawing", "velocity": 1000.0}, "geometry": geometry,
        "material": {"law": "rate_power", "A": 236.0, "n": 0.01}, "friction": {"mu": mu},
        "solver": {"method": "newton", "tolerance": tolerance},
        # uniform blocks in both (the meshes docs/verification.md states)
        "discretisation": {"averaging": "quadrature", "mesh_size": mesh_size,
                           "corner_grading": 1.0, "wall_grading": 1.0},
        "output": {"fields": False, "figures": False},
        "units": {"length": "mm", "time": "s", "stress": "MPa", "force": "N"}})


def wire_drawing(symmetry: str, mesh_size: float, mu: float,
                 comm: MPI.Comm = MPI.COMM_WORLD) -> dict[str, Any]:
    """The summary of the WIRE pass (wire_scene) solved on its own mesh."""
    scene = wire_scene(symmetry, mesh_size, mu)
    return solved(coupled_problem(scene, build_mesh(scene, comm)))


def _box_mesh(element: str, length: float, velocity: float, comm: MPI.Comm) -> FormingMesh:
    """The box [0, length] x [0, 1] x [0, 1] in hexahedra, pulled at u_x = ``velocity`` on
    x = length (Gamma1), held at u_x = 0 on x = 0 (its Gamma2), on the symmetry planes y = 0
    (Gamma6) and z = 0 (Gamma7), its faces y = 1 and z = 1 free (Gamma4)."""
    cells = [6, 3, 3] if element == "Q1" else [4, 2, 2]
    mesh = dolfinx.mesh.create_box(comm, [np.zeros(3), np.array([length, 1.0, 1.0])], cells,
                                   dolfinx.mesh.CellType.hexahedron, ghost_mode=GHOST_MODE)
    places = (("gamma1_velocity", lambda x: np.isclose(x[0], length)),
              ("gamma2_free", lambda x: np.isclose(x[0], 0.0)),
              ("gamma4_free", lambda x: np.isclose(x[1], 1.0) | np.isclose(x[2], 1.0)),
              ("gamma6_symmetry", lambda x: np.isclose(x[1], 0.0)),
              ("gamma7_symmetry", lambda x: np.isclose(x[2], 0.0)))
    facets = {role: dolfinx.mesh.locate_entities_boundary(mesh, 2, where)
              for role, where in places}
    indices = np.concatenate(list(facets.values()))
    values = np.concatenate([np.full(len(f), ROLES[role], dtype=np.int32)
                             for role, f in facets.items()])
    order = np.argsort(indices)
    tags = dolfinx.mesh.meshtags(mesh, 2, indices[order].astype(np.int32), values[order])
    constraints = [Constraint("gamma1_velocity", 0, velocity), Constraint("gamma2_free", 0, 0.0),
                   Constraint("gamma6_symmetry", 1, 0.0), Constraint("gamma7_symmetry", 2, 0.0)]
    return FormingMesh(mesh, tags, {role: ROLES[role] for role in facets}, constraints)


def homogeneous_extension_3d(element: str, method: str, formulation: str = "penalty",
                             comm: MPI.Comm = MPI.COMM_WORLD) -> dict[str, float]:
    """A box [0, 2] x [0, 1] x [0, 1] (the quarter of a 2 x 2 bar) pulled along x: u_x = 0 on
    x = 0, u_x = 2 rate0 on x = 2, free lateral faces, Norton law sigma = K rate^n (n = 0.2). Exact
    (the 3D homogeneous extension of verification.homogeneous_extension): u = rate0 (x, -y/2,
    -z/2), sigma_xx = sigma(rate0), the other stresses zero, in Q1 and Q2. Returns the largest
    nodal velocity error over rate0, the force on the unit end over sigma(rate0), the stress's L2
    error over sigma(rate0) times the root of the volume, the linear solves and the unknowns. The
    penalty differs from it by O(d) (sigma_H = sigma/3 needs div u = d sigma/3, Theorem 3.1);
    penalty.d_relative is 1e-6."""
    rate, n, length, K = 0.5, 0.2, 2.0, 1.0
    forming_mesh = _box_mesh(element, length, rate * length, comm)
    scene = scene_from_dict({
        "process": {"kind": "drawing", "velocity": rate * length},
        "output": {"fields": False, "figures": False},
        "geometry": {"symmetry": "3d", "entry_height": 2.0, "exit_height": 1.0,
                     "entry_width": 2.0, "exit_width": 1.0},
        "material": {"law": "rate_power", "A": K, "n": n},
        "discretisation": {"element": element, "formulation": formulation,
                           "averaging": "quadrature" if method == "newton" else "nodes"},
        "penalty": {"d_relative": 1e-6},
        "solver": {"method": method, "tolerance": 1e-8, "reference_strain_rate": 0.1}})
    problem = coupled_problem(scene, forming_mesh)
    solver = solver_for(problem)
    result = solver.solve()
    solver.destroy()
    if not result.converged:
        raise RuntimeError(f"homogeneous 3D extension {element} {method}: {result.reason}")
    problem.update_state(problem.u, frozen_too=True)
    points = problem.V.tabulate_dof_coordinates()
    exact = rate * points * np.array([1.0, -0.5, -0.5])
    error = np.abs(problem.u.x.array.reshape(-1, 3) - exact).max() / rate
    sigma = K * rate**n
    stress_error = problem.stress() - ufl.as_matrix([[sigma, 0, 0], [0, 0, 0], [0, 0, 0]])
    square = integrate(problem, ufl.inner(stress_error, stress_error) * problem.dx)
    return {"velocity_error": comm.allreduce(error, op=MPI.MAX),
            "force_ratio": reaction(problem) / sigma,
            "stress_error": math.sqrt(square / length) / sigma,
            "solves": result.linear_solves, "unknowns": problem.unknowns}


def edge_contact(problem: FlowProblem) -> dict[str, float]:
    """The contact of a rectangular bar where the die's height face y = h(x) and width face
    z = w(x) meet (a converged problem of a 3D rectangle scene): over Gamma3's band within one
    mesh size of that edge and over the rest of Gamma3, the mean penetration velocity u_N^+
    (relative to the process velocity) and the mean contact pressure (lambda + u_N/d_N)^+ of
    (3.4); and the largest u.n (relative to the process velocity) at the nodes strictly inside
    the cone: on the edge against either face (the contact of both faces must keep it near zero),
    and on each face off the edge against that face."""
    g, scene = problem.scene.geometry, problem.scene
    x = ufl.SpatialCoordinate(problem.mesh)
    height, width = _die_faces(g)
    distance = (height(x[0], ufl.max_value, ufl.min_value) - x[1]
                + width(x[0], ufl.max_value, ufl.min_value) - x[2])
    band = ufl.conditional(ufl.lt(distance, scene.discretisation.mesh_size), 1.0, 0.0)
    ds, velocity = problem.ds_contact, scene.process.velocity
    inflow = ufl.max_value(contact.normal_velocity(problem.u, problem.n), 0.0)
    pressure = problem.contact_pressure(problem.u)
    found = {}
    for name, part in (("edge", band), ("faces", 1.0 - band)):
        area = integrate(problem, part * ds)
        found[f"{name}_penetration"] = integrate(problem, inflow * part * ds) / area / velocity
        found[f"{name}_pressure"] = integrate(problem, pressure * part * ds) / area
    owned = problem.V.dofmap.index_map.size_local
    points = problem.V.tabulate_dof_coordinates()[:owned]
    u = problem.u.x.array.reshape(-1, 3)[:owned]
    tolerance = 1e-9 * g.entry_thickness
    cone = ((points[:, 0] > g.die_entry + tolerance)
            & (points[:, 0] < g.die_entry + g.cone_length - tolerance))
    on_top = cone & np.isclose(points[:, 1], height(points[:, 0], np.maximum, np.minimum),
                               atol=tolerance)
    on_side = cone & np.isclose(points[:, 2], width(points[:, 0], np.maximum, np.minimum),
                                atol=tolerance)
    angles = np.radians([g.die_angle, g.width_angle])
    normals = np.array([[math.sin(angles[0]), math.cos(angles[0]), 0.0],
                        [math.sin(angles[1]), 0.0, math.cos(angles[1])]])
    normal_velocity = u @ normals.T
    for name, nodes, faces in (("edge", on_top & on_side, [0, 1]),
                               ("top", on_top & ~on_side, [0]), ("side", on_side & ~on_top, [1])):
        largest = normal_velocity[np.ix_(nodes, faces)].max(initial=-math.inf)
        found[f"{name}_node_normal_velocity"] = problem.comm.allreduce(
            float(largest), op=MPI.MAX) / velocity
        found[f"{name}_nodes"] = problem.comm.allreduce(int(nodes.sum()))
    return found


def _die_faces(g) -> tuple[Callable, Callable]:
    """The die's half-height h(x) and half-width w(x) over the axis: the entry size, the cone's
    faces (die_angle, width_angle), then the exit size; each called with x and the maximum and
    minimum functions of its kind (UFL's or NumPy's)."""
    def size(entry: float, exit: float, angle: float) -> Callable:
        slope = math.tan(math.radians(angle))
        return lambda x, maximum, minimum: maximum(exit, minimum(entry, entry - (x - g.die_entry)
                                                                 * slope))
    return (size(0.5 * g.entry_thickness, 0.5 * g.exit_thickness, g.die_angle),
            size(0.5 * g.entry_width, 0.5 * g.exit_width, g.width_angle))

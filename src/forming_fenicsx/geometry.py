"""Gmsh scripts for the half models of Fig. 1, built from structured quadrilateral blocks (Fig. 2).

Boundary roles are physical groups named as in section 2:
Gamma1 process velocity (2.5), Gamma2/Gamma4 free (2.6), Gamma3 die contact (2.9),
Gamma5 applied force (2.7), Gamma6 symmetry (2.8).
"""
from __future__ import annotations

import math
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path

import gmsh
from mpi4py import MPI

from .scene import Scene

ROLES = {"gamma1_velocity": 1, "gamma2_free": 2, "gamma3_contact": 3,
         "gamma4_free": 4, "gamma5_force": 5, "gamma6_symmetry": 6}
WORKPIECE = 1


@dataclass(frozen=True)
class Constraint:
    """A prescribed velocity component on a boundary role: (2.5) on Gamma1, (2.8) on Gamma6."""

    role: str
    component: int
    value: float


@dataclass
class FormingMesh:
    """A dolfinx mesh with its facet tags (values from ROLES), the roles present and the constraints."""

    mesh: object
    facet_tags: object
    roles: dict[str, int]
    constraints: list[Constraint]


def graded_edge(length: float, size: float, grading: float, toward_end: bool) -> tuple[int, float]:
    """Number of elements and gmsh progression for an edge refined geometrically toward one end.

    ``grading`` is the ratio of the largest to the smallest element on the edge (1 is uniform).
    """
    elements = max(1, math.ceil(length / size - 1e-9))
    if elements == 1 or grading == 1.0:
        return elements, 1.0
    ratio = grading ** (1.0 / (elements - 1))
    return elements, 1.0 / ratio if toward_end else ratio


@dataclass
class Edge:
    start: str
    end: str
    elements: int
    progression: float = 1.0


def _add_blocks(points: dict[str, tuple[float, float]], edges: dict[str, Edge],
                blocks: list[list[str]], groups: dict[str, list[str]]) -> None:
    """Add transfinite, recombined blocks to the current gmsh model.

    A block is four edge names around it counter-clockwise; a leading '-' reverses an edge.
    """
    geo = gmsh.model.geo
    point_tags = {name: geo.addPoint(x, y, 0.0) for name, (x, y) in points.items()}
    edge_tags = {}
    for name, edge in edges.items():
        tag = geo.addLine(point_tags[edge.start], point_tags[edge.end])
        geo.mesh.setTransfiniteCurve(tag, edge.elements + 1, "Progression", edge.progression)
        edge_tags[name] = tag
    surfaces = []
    for loop in blocks:
        signed = [-edge_tags[e[1:]] if e.startswith("-") else edge_tags[e] for e in loop]
        surface = geo.addPlaneSurface([geo.addCurveLoop(signed)])
        geo.mesh.setTransfiniteSurface(surface)
        geo.mesh.setRecombine(2, surface)
        surfaces.append(surface)
    geo.synchronize()
    gmsh.model.addPhysicalGroup(2, surfaces, WORKPIECE)
    gmsh.model.setPhysicalName(2, WORKPIECE, "workpiece")
    for role, names in groups.items():
        gmsh.model.addPhysicalGroup(1, [edge_tags[n] for n in names], ROLES[role])
        gmsh.model.setPhysicalName(1, ROLES[role], role)


def _extrusion(scene: Scene) -> None:
    """Example 1 half model: container [0, xd] x [0, h0], exit [xd, L] x [0, h1], die corner at (xd, h1)."""
    g, disc = scene.geometry, scene.discretisation
    h0, h1, xd, L = 0.5 * g.entry_thickness, 0.5 * g.exit_thickness, g.die_position, g.length
    size, grade = disc.mesh_size, disc.corner_grading
    n_xc, r_xc = graded_edge(xd, size, grade, toward_end=True)
    n_xe, r_xe = graded_edge(L - xd, size, grade, toward_end=False)
    n_y1, r_y1 = graded_edge(h1, size, grade, toward_end=True)
    n_y2, r_y2 = graded_edge(h0 - h1, size, grade, toward_end=False)
    points = {"p1": (0, 0), "p2": (xd, 0), "p3": (L, 0), "p4": (L, h1),
              "p5": (xd, h1), "p6": (xd, h0), "p7": (0, h0), "p8": (0, h1)}
    edges = {
        "bottom_container": Edge("p1", "p2", n_xc, r_xc), "bottom_exit": Edge("p2", "p3", n_xe, r_xe),
        "exit_face": Edge("p3", "p4", n_y1, r_y1), "exit_surface": Edge("p5", "p4", n_xe, r_xe),
        "inner_vertical": Edge("p2", "p5", n_y1, r_y1), "inner_horizontal": Edge("p8", "p5", n_xc, r_xc),
        "die_face": Edge("p5", "p6", n_y2, r_y2), "container_wall": Edge("p7", "p6", n_xc, r_xc),
        "ram_lower": Edge("p1", "p8", n_y1, r_y1), "ram_upper": Edge("p8", "p7", n_y2, r_y2),
    }
    blocks = [["bottom_container", "inner_vertical", "-inner_horizontal", "-ram_lower"],
              ["inner_horizontal", "die_face", "-container_wall", "-ram_upper"],
              ["bottom_exit", "exit_face", "-exit_surface", "-inner_vertical"]]
    end_role = "gamma5_force" if scene.process.applied_force is not None else "gamma4_free"
    groups = {"gamma1_velocity": ["ram_lower", "ram_upper"], "gamma2_free": ["exit_surface"],
              "gamma3_contact": ["die_face", "container_wall"], end_role: ["exit_face"],
              "gamma6_symmetry": ["bottom_container", "bottom_exit"]}
    _add_blocks(points, edges, blocks, groups)


BUILDERS = {"extrusion": _extrusion}


@contextmanager
def _gmsh_session():
    gmsh.initialize()
    gmsh.option.setNumber("General.Terminal", 0)
    try:
        yield
    finally:
        gmsh.finalize()


def _generate(scene: Scene) -> None:
    gmsh.model.add(scene.process.kind)
    BUILDERS[scene.process.kind](scene)
    gmsh.option.setNumber("Mesh.SecondOrderIncomplete", 0)
    gmsh.model.mesh.generate(2)
    gmsh.model.mesh.setOrder(scene.discretisation.degree)


def build_mesh(scene: Scene, comm: MPI.Comm = MPI.COMM_WORLD) -> FormingMesh:
    """Mesh the scene's workpiece on rank 0 and distribute it (isoparametric: geometry order = element)."""
    from dolfinx.io import gmshio

    with _gmsh_session():
        if comm.rank == 0:
            _generate(scene)
        mesh, _, facet_tags = gmshio.model_to_mesh(gmsh.model, comm, 0, gdim=2)
    present = set(int(v) for v in facet_tags.values)
    present = set().union(*comm.allgather(present))
    roles = {name: tag for name, tag in ROLES.items() if tag in present}
    # Gamma1 and Gamma6 are normal to x and y in both processes: u_x = u_N^0 and u_y = 0.
    constraints = [Constraint("gamma1_velocity", 0, scene.process.velocity), Constraint("gamma6_symmetry", 1, 0.0)]
    return FormingMesh(mesh, facet_tags, roles, constraints)


def write_msh(scene: Scene, path: str | Path) -> Path:
    """Write the scene's mesh as a Gmsh .msh file (format 4.1) for use in other tools."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    with _gmsh_session():
        _generate(scene)
        gmsh.write(str(path))
    return path

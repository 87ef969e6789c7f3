"""Gmsh scripts for the half models of Fig. 1, built from structured quadrilateral blocks (Fig. 2).

Boundary roles are physical groups named as in section 2 (roles.py); a user's .msh file is checked
by config/mesh_file.py.
"""
from __future__ import annotations

import ctypes
import os
from collections.abc import Callable
from contextlib import contextmanager
from dataclasses import dataclass
from functools import partial
from pathlib import Path

import gmsh
import numpy as np
from mpi4py import MPI

from forming_fenicsx.core.errors import SceneError
from forming_fenicsx.config.die_profile import Segment
from forming_fenicsx.config.mesh_file import gmsh_session, open_msh
from forming_fenicsx.core.roles import ROLES, WORKPIECE
from forming_fenicsx.config.scene import Scene
from forming_fenicsx.mesh.bar3d import rectangular_bar, round_bar
from forming_fenicsx.mesh.free_shape import FreeShape, fixed_shape, square_die
from forming_fenicsx.mesh.grading import graded_edge


@dataclass(frozen=True)
class Constraint:
    """A prescribed velocity component on a boundary role: (2.5) on Gamma1, (2.8) on Gamma6."""

    role: str
    component: int
    value: float


@dataclass
class FormingMesh:
    """A dolfinx mesh with its facet tags (values from ROLES), the roles present and the
    constraints."""

    mesh: object
    facet_tags: object
    roles: dict[str, int]
    constraints: list[Constraint]


@dataclass
class Edge:
    start: str
    end: str
    elements: int
    progression: float = 1.0


def _add_blocks(points: dict[str, tuple[float, float]], edges: dict[str, Edge],
                blocks: list[list[str]], groups: dict[str, list[str]],
                arcs: dict[str, tuple[float, float]] | None = None,
                structured: bool = True) -> None:
    """Add transfinite, recombined blocks to the current gmsh model (not transfinite unless
    ``structured``: the surfaces for a size field, mesh/adapted.py).

    A block is four edge names around it counter-clockwise; a leading '-' reverses an edge. An edge
    named in ``arcs`` is the circular arc about the centre given there, else a line.
    """
    geo = gmsh.model.geo
    point_tags = {name: geo.addPoint(x, y, 0.0) for name, (x, y) in points.items()}
    edge_tags = {}
    for name, edge in edges.items():
        if arcs and name in arcs:
            centre = geo.addPoint(*arcs[name], 0.0)
            tag = geo.addCircleArc(point_tags[edge.start], centre, point_tags[edge.end])
        else:
            tag = geo.addLine(point_tags[edge.start], point_tags[edge.end])
        if structured:
            geo.mesh.setTransfiniteCurve(tag, edge.elements + 1, "Progression", edge.progression)
        edge_tags[name] = tag
    surfaces = []
    for loop in blocks:
        signed = [-edge_tags[e[1:]] if e.startswith("-") else edge_tags[e] for e in loop]
        surface = geo.addPlaneSurface([geo.addCurveLoop(signed)])
        if structured:
            geo.mesh.setTransfiniteSurface(surface)
        geo.mesh.setRecombine(2, surface)
        surfaces.append(surface)
    geo.synchronize()
    gmsh.model.addPhysicalGroup(2, surfaces, WORKPIECE)
    gmsh.model.setPhysicalName(2, WORKPIECE, "workpiece")
    for role, names in groups.items():
        gmsh.model.addPhysicalGroup(1, [edge_tags[n] for n in names], ROLES[role])
        gmsh.model.setPhysicalName(1, ROLES[role], role)


def _extrusion(scene: Scene, structured: bool = True, shape: FreeShape | None = None) -> None:
    """Example 1 half model: container [0, xd] x [0, h0], exit [xd, L] x [0, h1], die corner at
    (xd, h1). A ``shape`` (free_shape.py) sets the product's height at the exit face (shaped_mesh
    moves its surface onto the shape's)."""
    g, disc = scene.geometry, scene.discretisation
    h0, h1, xd, L = 0.5 * g.entry_thickness, 0.5 * g.exit_thickness, g.die_position, g.length
    shape = fixed_shape(scene) if shape is None else shape
    size, grade = disc.mesh_size, disc.corner_grading
    n_xc, r_xc = graded_edge(xd, size, grade, toward_end=True)
    n_xe, r_xe = graded_edge(L - xd, size, grade, toward_end=False)
    n_y1, r_y1 = graded_edge(h1, size, grade, toward_end=True)
    n_y2, r_y2 = graded_edge(h0 - h1, size, grade, toward_end=False)
    points = {"p1": (0, 0), "p2": (xd, 0), "p3": (L, 0), "p4": (L, shape.exit_height),
              "p5": (xd, h1), "p6": (xd, h0), "p7": (0, h0), "p8": (0, h1)}
    edges = {
        "bottom_container": Edge("p1", "p2", n_xc, r_xc),
        "bottom_exit": Edge("p2", "p3", n_xe, r_xe),
        "exit_face": Edge("p3", "p4", n_y1, r_y1), "exit_surface": Edge("p5", "p4", n_xe, r_xe),
        "inner_vertical": Edge("p2", "p5", n_y1, r_y1),
        "inner_horizontal": Edge("p8", "p5", n_xc, r_xc),
        "die_face": Edge("p5", "p6", n_y2, r_y2), "container_wall": Edge("p7", "p6", n_xc, r_xc),
        "ram_lower": Edge("p1", "p8", n_y1, r_y1), "ram_upper": Edge("p8", "p7", n_y2, r_y2),
    }
    blocks = [["bottom_container", "inner_vertical", "-inner_horizontal", "-ram_lower"],
              ["inner_horizontal", "die_face", "-container_wall", "-ram_upper"],
              ["bottom_exit", "exit_face", "-exit_surface", "-inner_vertical"]]
    groups = _end_faces(scene, ["ram_lower", "ram_upper"], ["exit_face"])
    groups.setdefault("gamma4_free", []).append("exit_surface")
    groups["gamma3_contact"] = ["die_face", "container_wall"]
    groups["gamma6_symmetry"] = ["bottom_container", "bottom_exit"]
    _add_blocks(points, edges, blocks, groups, structured=structured)


def _end_faces(scene: Scene, entry: list[str], exit: list[str]) -> dict[str, list[str]]:
    """Gamma1 on the driven end face (entry for "push", exit for "pull"); the other end carries F_N
    (Gamma5) when the scene gives one, else it is free (Gamma2 upstream, Gamma4 downstream).
    Rolling: Gamma1 is the entry face, whose speed the flow decides (fem/entry_speed.py) and which
    carries the back tension; the exit face carries the front tension (Gamma5), or is free."""
    if scene.process.kind == "rolling":
        exit_role = "gamma5_force" if scene.process.front_tension else "gamma4_free"
        return {"gamma1_velocity": list(entry), exit_role: list(exit)}
    driven, other, free = ((entry, exit, "gamma4_free") if scene.process.drive == "push"
                           else (exit, entry, "gamma2_free"))
    loaded = "gamma5_force" if scene.process.applied_force is not None else free
    return {"gamma1_velocity": list(driven), loaded: list(other)}


def _profiled(scene: Scene, structured: bool = True, shape: FreeShape | None = None) -> None:
    """A workpiece through a profiled die (Example 2's strip, a drawn bar, a conical extrusion).

    Blocks along x: before the die [0, x0] (under a free surface for drawing, the container wall
    for extrusion), one block under each segment of the die wall (lines, and arcs that Q2 follows),
    then the product [x_n, L], with the same number of elements through the thickness. The ends of
    the first and last blocks are graded toward the die entry and exit (corner_grading); with
    wall_grading > 1 each die segment is two blocks graded toward its ends (the corners where the
    wall's slope changes) and the thickness is graded toward the die wall. A ``shape``
    (free_shape.py) replaces the die wall by its part in contact, the stock's block then reaching
    to where the contact starts, and sets the product's height at the exit face (shaped_mesh moves
    the stock's and the product's surfaces onto the shape's).
    """
    g, disc = scene.geometry, scene.discretisation
    h0, L = 0.5 * g.entry_thickness, g.length
    shape = fixed_shape(scene) if shape is None else shape
    size, grade = disc.mesh_size, disc.corner_grading
    pieces = _wall_pieces(shape.wall.segments, size, disc.wall_grading)
    n_y, r_y = graded_edge(h0, size, disc.wall_grading, toward_end=True)
    tops = [(0.0, h0), *(piece.start for piece, _ in pieces), pieces[-1][0].end,
            (L, shape.exit_height)]
    n_in, r_in = graded_edge(tops[1][0], size, grade, toward_end=True)
    n_out, r_out = graded_edge(L - tops[-2][0], size, grade, toward_end=False)
    counts = [(n_in, r_in)] + [count for _, count in pieces] + [(n_out, r_out)]
    points = {f"b{i}": (x, 0.0) for i, (x, _) in enumerate(tops)}
    points.update({f"t{i}": top for i, top in enumerate(tops)})
    edges = {f"bottom{i}": Edge(f"b{i}", f"b{i + 1}", *counts[i]) for i in range(len(tops) - 1)}
    edges.update({f"line{i}": Edge(f"b{i}", f"t{i}", n_y, r_y) for i in range(len(tops))})
    edges.update({f"top{i}": Edge(f"t{i}", f"t{i + 1}", *counts[i]) for i in range(len(tops) - 1)})
    arcs = {f"top{i + 1}": piece.centre for i, (piece, _) in enumerate(pieces)
            if piece.centre is not None}
    blocks = [[f"bottom{i}", f"line{i + 1}", f"-top{i}", f"-line{i}"] for i in range(len(tops) - 1)]
    last = len(tops) - 1
    groups = _end_faces(scene, ["line0"], [f"line{last}"])
    wall = [f"top{i}" for i in range(1, last - 1)]
    if scene.process.kind == "extrusion":
        wall.insert(0, "top0")  # the container
    else:
        groups.setdefault("gamma2_free", []).append("top0")
    groups.setdefault("gamma4_free", []).append(f"top{last - 1}")
    groups["gamma3_contact"] = wall
    groups["gamma6_symmetry"] = [f"bottom{i}" for i in range(last)]
    _add_blocks(points, edges, blocks, groups, arcs, structured)


def _wall_pieces(segments: list[Segment], size: float, grading: float
                 ) -> list[tuple[Segment, tuple[int, float]]]:
    """The die wall's blocks with their elements and progressions: each segment whole and uniform
    (``grading`` 1), else its two halves, each graded toward the segment's end it holds. Elements
    by the axial extent of a line (as Example 2's cone and land), by the length of an arc."""
    def extent(segment: Segment) -> float:
        return (segment.end[0] - segment.start[0] if segment.centre is None
                else segment.length)

    if grading == 1.0:
        return [(seg, graded_edge(extent(seg), size, 1.0, toward_end=True)) for seg in segments]
    pieces = []
    for seg in segments:
        middle = tuple(float(c) for c in seg.points(2)[1])
        for half, toward_end in ((Segment(seg.start, middle, seg.centre), False),
                                 (Segment(middle, seg.end, seg.centre), True)):
            pieces.append((half, graded_edge(extent(half), size, grading, toward_end)))
    return pieces


def _builder(scene: Scene):
    """Example 1's square die, a profiled die (drawing, conical extrusion), or a 3D quarter bar
    (rectangular or round section, mesh/bar3d.py)."""
    g = scene.geometry
    if g.three_dimensional:
        return round_bar if g.shape == "round" else rectangular_bar
    return _extrusion if square_die(scene) else _profiled


def add_model(scene: Scene, structured: bool = True) -> None:
    """The scene's gmsh model in the current session: its blocks and physical groups, unmeshed
    (mesh/slab.py extrudes a strip's); in 2D without the blocks' transfinite constraints unless
    ``structured`` (mesh/adapted.py meshes them by a size field)."""
    gmsh.model.add(scene.process.kind)
    if structured:
        _builder(scene)(scene)
    else:
        _builder(scene)(scene, structured=False)


def shaped_mesh(scene: Scene, shape: FreeShape) -> Callable[[], None]:
    """A generator for build_mesh: the scene's workpiece with the top boundary ``shape``
    (free_shape.py), meshed by the scene's blocks, the stock's and the product's blocks with a
    straight top between their surface's ends, then stretched onto the surface (_follow)."""
    def generate() -> None:
        gmsh.model.add(scene.process.kind)
        _builder(scene)(scene, shape=shape)
        mesh_model(2, scene.discretisation.degree)
        for surface in (shape.upstream, shape.downstream):
            if surface is not None:
                _follow(surface)

    return generate


def _follow(surface: np.ndarray) -> None:
    """Move the meshed nodes between the surface's ends x0 and x1 along y by y_s(x) / y_l(x),
    y_s the surface (N, 2) and y_l the straight edge between its ends: the block's top onto the
    surface, its columns of nodes kept vertical (the block's bottom is the axis, its corners
    stay). A spline edge instead is meshed by gmsh's own parameter, whose nodes did not lie above
    the straight bottom's where the surface's points bunch at a graded corner: skewed cells."""
    (x0, y0), (x1, y1) = surface[0], surface[-1]
    tags, coords, _ = gmsh.model.mesh.getNodes()
    coords = coords.reshape(-1, 3)
    slack = 1e-12 * max(abs(x0), abs(x1), 1.0)
    inside = (coords[:, 0] >= x0 - slack) & (coords[:, 0] <= x1 + slack)
    x = _columns(coords[inside])
    line = y0 + (x - x0) / (x1 - x0) * (y1 - y0)
    scale = np.interp(x, surface[:, 0], surface[:, 1]) / line
    moved = np.column_stack([x, coords[inside, 1] * scale, np.zeros(len(x))])
    _set_nodes(tags[inside], moved)


def _columns(coords: np.ndarray) -> np.ndarray:
    """The nodes' x (coords (N, 3) of a block whose bottom is the axis), each within 1e-6 of its
    column's spacing of a bottom node's x set to that x: gmsh's transfinite nodes under a sloping
    straight top stray from their column by up to 1e-9 on a graded block, which made its cells
    miss columns.py's vertical sides (1e-9 of their width)."""
    x = coords[:, 0].copy()
    bottom = np.unique(x[np.abs(coords[:, 1]) <= 1e-12 * max(np.ptp(coords[:, 1]), 1.0)])
    if len(bottom) < 2:
        return x
    j = np.clip(np.searchsorted(bottom, x), 1, len(bottom) - 1)
    nearest = np.where(x - bottom[j - 1] < bottom[j] - x, j - 1, j)
    spacing = np.diff(bottom)[np.clip(nearest, 0, len(bottom) - 2)]
    snap = np.abs(x - bottom[nearest]) <= 1e-6 * spacing
    x[snap] = bottom[nearest[snap]]
    return x


def _set_nodes(tags: np.ndarray, coords: np.ndarray) -> None:
    """gmsh.model.mesh.setNode for each node (tags, coords (N, 3)): gmsh's C function called with
    one buffer (the Python wrapper converts two lists a node: 20 ms for Example 2's 5k nodes, 4 ms
    this way)."""
    set_node = gmsh.lib.gmshModelMeshSetNode
    point, nothing, error = (ctypes.c_double * 3)(), (ctypes.c_double * 1)(), ctypes.c_int()
    for tag, (x, y, z) in zip(tags.tolist(), coords.tolist()):
        point[0], point[1], point[2] = x, y, z
        set_node(ctypes.c_size_t(tag), point, ctypes.c_size_t(3), nothing, ctypes.c_size_t(0),
                 ctypes.byref(error))
        if error.value:
            raise RuntimeError(f"gmsh could not move node {tag}: {gmsh.logger.getLastError()}")


def mesh_model(dim: int, degree: int) -> None:
    """Mesh the current gmsh model in ``dim`` dimensions with complete Lagrange cells of the
    element's degree (isoparametric: 9-node quadrilaterals, 27-node hexahedra for Q2)."""
    gmsh.option.setNumber("Mesh.SecondOrderIncomplete", 0)
    gmsh.model.mesh.generate(dim)
    gmsh.model.mesh.setOrder(degree)


def _generate(scene: Scene) -> None:
    add_model(scene)
    mesh_model(3 if scene.geometry.three_dimensional else 2, scene.discretisation.degree)


@contextmanager
def _one_scotch_thread():
    """SCOTCH, dolfinx's partitioner, on one thread per rank (Scotch 7 reads SCOTCH_PTHREAD_NUMBER
    at each call): with its threads the partition changes from run to run, and with it the dof
    numbering and MUMPS' ordering on several ranks. The variable is restored afterwards."""
    previous = os.environ.get("SCOTCH_PTHREAD_NUMBER")
    os.environ["SCOTCH_PTHREAD_NUMBER"] = "1"
    try:
        yield
    finally:
        if previous is None:
            del os.environ["SCOTCH_PTHREAD_NUMBER"]
        else:
            os.environ["SCOTCH_PTHREAD_NUMBER"] = previous


def build_mesh(scene: Scene, comm: MPI.Comm = MPI.COMM_WORLD,
               generate: Callable[[], None] | None = None) -> FormingMesh:
    """Mesh the scene's workpiece on rank 0 and distribute it (isoparametric: geometry order =
    element), or read the scene's own .msh file (geometry.mesh_file, checked when the scene was
    read). ``generate`` meshes another gmsh model of the scene's workpiece on rank 0 instead of
    its own (mesh/slab.py: a strip's model extruded). The partition repeats from run to run
    (_one_scotch_thread); its ghosts are compat.GHOST_MODE's."""
    from dolfinx.mesh import meshtags

    from forming_fenicsx.core.compat import mesh_from_gmsh

    mesh_file = scene.geometry.mesh_file
    with gmsh_session():
        outcome: dict[int, int] | SceneError | None = None
        if comm.rank == 0:
            try:
                outcome = open_msh(mesh_file) if mesh_file else None
                if not mesh_file:
                    (generate or partial(_generate, scene))()
            except SceneError as error:
                outcome = error
        outcome = comm.bcast(outcome, root=0)
        if isinstance(outcome, SceneError):
            raise outcome
        dim = 3 if scene.geometry.three_dimensional else 2
        with _one_scotch_thread():
            mesh, _, facet_tags = mesh_from_gmsh(gmsh.model, comm, 0, gdim=dim)
    if outcome is not None:  # the file's tags -> the roles' tags
        values = np.array([outcome[int(v)] for v in facet_tags.values], dtype=np.int32)
        facet_tags = meshtags(mesh, mesh.topology.dim - 1, facet_tags.indices, values)
    present = set(int(v) for v in facet_tags.values)
    present = set().union(*comm.allgather(present))
    roles = {name: tag for name, tag in ROLES.items() if tag in present}
    driven = scene.process.kind != "rolling"
    return FormingMesh(mesh, facet_tags, roles,
                       constraints(scene.process.velocity, roles, driven))


def constraints(velocity: float, roles: dict[str, int], driven: bool = True) -> list[Constraint]:
    """Gamma1, Gamma6 and Gamma7 are normal to x, y and z in every process: u_x = u_N^0 (2.5) on
    a ``driven`` Gamma1 (not rolling's, whose speed is the flow's), u_y = 0 and u_z = 0 (2.8)."""
    found = [Constraint("gamma6_symmetry", 1, 0.0)]
    if driven:
        found.insert(0, Constraint("gamma1_velocity", 0, velocity))
    if "gamma7_symmetry" in roles:
        found.append(Constraint("gamma7_symmetry", 2, 0.0))
    return found


def write_msh(scene: Scene, path: str | Path) -> Path:
    """Write the scene's mesh as a Gmsh .msh file (format 4.1) for use in other tools."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    with gmsh_session():
        _generate(scene)
        gmsh.write(str(path))
    return path


def _chain_coordinate(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Arc length along a polyline of nodes, walked from the upstream end (smallest x, then
    largest y) to the nearest node not yet visited."""
    points = np.column_stack([x, y])
    current = int(np.lexsort((-y, x))[0])
    s = np.zeros(len(points))
    visited = np.zeros(len(points), dtype=bool)
    visited[current] = True
    for _ in range(len(points) - 1):
        distance = np.linalg.norm(points - points[current], axis=1)
        distance[visited] = np.inf
        following = int(distance.argmin())
        s[following] = s[current] + distance[following]
        visited[following] = True
        current = following
    return s


def die_coordinate(scene: Scene, x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Arc length along Gamma3 from where the workpiece meets the die, for points on Gamma3.

    Square die: along the container wall (from the ram), then down the die face. A profiled die:
    along its wall (DieProfile.coordinate), after the container's length for an extrusion. A user's
    mesh: along the chain of its Gamma3 nodes.
    """
    g = scene.geometry
    if g.mesh_file:
        return _chain_coordinate(x, y)
    if g.die == "square":
        h0 = 0.5 * g.entry_thickness
        on_face = np.isclose(x, g.die_position) & (y < h0 - 1e-12 * h0)
        return np.where(on_face, g.die_position + (h0 - y), x)
    profile = g.profile()
    along = profile.coordinate(x, y)
    if scene.process.kind != "extrusion":
        return along
    return np.where(x < profile.start[0], x, profile.start[0] + along)

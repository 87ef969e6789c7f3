"""Gmsh scripts for 3D quarter models: a bar of rectangular section through a die of straight
converging faces with a land, and the quarter of a round bar through a conical die, built from
transfinite hexahedral blocks along the axis (x the flow direction, y the height, z the width; the
planes y = 0 and z = 0 are the symmetry planes Gamma6 and Gamma7).

The rectangular bar: one block per stretch of the axis (the stock ahead of the die, the converging
faces, the land, the product), each a hexahedron whose top face y = h(x) and side face z = w(x) are
planes. The round bar: an O-grid in every section (a square core and two blocks out to the quarter
circle), so that no element degenerates at the axis.
"""
from __future__ import annotations

import math
from collections.abc import Sequence

import gmsh

from forming_fenicsx.config.scene import Scene
from forming_fenicsx.core.roles import ROLES, WORKPIECE
from forming_fenicsx.mesh.grading import graded_edge

# the core square of a round section's O-grid, over the radius
CORE = 0.5


class HexBlocks:
    """Transfinite hexahedral blocks in the current gmsh model: points, lines (transfinite with a
    number of elements and a progression), faces of four corners, volumes of six faces; physical
    groups by role."""

    def __init__(self) -> None:
        self.geo = gmsh.model.geo
        self._lines: dict[tuple[int, int], int] = {}
        self._faces: dict[frozenset[int], int] = {}
        self.volumes: list[int] = []
        self.groups: dict[str, list[int]] = {}

    def point(self, x: float, y: float, z: float) -> int:
        return self.geo.addPoint(x, y, z)

    def line(self, a: int, b: int, elements: int, progression: float = 1.0,
             centre: int | None = None) -> None:
        """The line (or circular arc about ``centre``) from point a to b, meshed in ``elements``,
        refined geometrically by ``progression`` towards b (gmsh's progression from a)."""
        tag = (self.geo.addLine(a, b) if centre is None
               else self.geo.addCircleArc(a, centre, b))
        self.geo.mesh.setTransfiniteCurve(tag, elements + 1, "Progression", progression)
        self._lines[(a, b)] = tag

    def _signed(self, a: int, b: int) -> int:
        if (a, b) in self._lines:
            return self._lines[(a, b)]
        return -self._lines[(b, a)]

    def face(self, corners: Sequence[int], role: str | None = None) -> int:
        """The face through four corner points in order around it (the lines between them must
        exist), transfinite and recombined; the same corners give the same face."""
        key = frozenset(corners)
        if key not in self._faces:
            loop = self.geo.addCurveLoop([self._signed(a, b) for a, b in
                                          zip(corners, [*corners[1:], corners[0]], strict=True)])
            tag = self.geo.addSurfaceFilling([loop])
            self.geo.mesh.setTransfiniteSurface(tag, cornerTags=list(corners))
            self.geo.mesh.setRecombine(2, tag)
            self._faces[key] = tag
        if role is not None:
            self.groups.setdefault(role, []).append(self._faces[key])
        return self._faces[key]

    def volume(self, low: Sequence[int], high: Sequence[int]) -> None:
        """The hexahedron between the faces ``low`` and ``high`` (four corners each, in the same
        order around them); its other four faces must exist."""
        faces = [self.face(low), self.face(high)]
        for i in range(4):
            j = (i + 1) % 4
            faces.append(self.face([low[i], low[j], high[j], high[i]]))
        tag = self.geo.addVolume([self.geo.addSurfaceLoop(faces)])
        self.geo.mesh.setTransfiniteVolume(tag, cornerTags=[*low, *high])
        self.volumes.append(tag)

    def finish(self) -> None:
        """Synchronise and name the workpiece and the roles' physical groups."""
        self.geo.synchronize()
        gmsh.model.addPhysicalGroup(3, self.volumes, WORKPIECE)
        gmsh.model.setPhysicalName(3, WORKPIECE, "workpiece")
        for role, faces in self.groups.items():
            gmsh.model.addPhysicalGroup(2, faces, ROLES[role])
            gmsh.model.setPhysicalName(2, ROLES[role], role)


def stations(scene: Scene) -> list[tuple[float, float, float]]:
    """(x, half-height, half-width) at the ends of the axis' stretches: the entry face, the die
    entry, the land, the die exit, the exit face (a round bar: half-width = radius); with
    wall_grading > 1 also the middles of the converging stretch and of the land, where the
    stretches graded toward the die's corners meet (_axial)."""
    g = scene.geometry
    h0, h1 = 0.5 * g.entry_thickness, 0.5 * g.exit_thickness
    w0, w1 = ((h0, h1) if g.shape == "round" else (0.5 * g.entry_width, 0.5 * g.exit_width))
    land = g.die_entry + g.cone_length
    at = [(0.0, h0, w0), (g.die_entry, h0, w0), (land, h1, w1), (g.die_exit, h1, w1),
          (g.length, h1, w1)]
    if scene.discretisation.wall_grading == 1.0:
        return at
    middles = [tuple(0.5 * (a + b) for a, b in zip(at[k], at[k + 1], strict=True)) for k in (1, 2)]
    return [at[0], at[1], middles[0], at[2], middles[1], at[3], at[4]]


def _axial(scene: Scene, x: list[float]) -> list[tuple[int, float]]:
    """Elements and progression of each stretch of the axis: graded toward the die's ends in the
    stock and the product (discretisation.corner_grading); in the die uniform, or with
    wall_grading > 1 its halves graded toward the corner each holds (stations)."""
    disc, count = scene.discretisation, len(x) - 1
    counts = []
    for k in range(count):
        if k in (0, count - 1):
            grading, toward_end = disc.corner_grading, k == 0
        else:  # the die: halves alternate, from a corner to a middle and back
            grading, toward_end = disc.wall_grading, k % 2 == 0
        counts.append(graded_edge(x[k + 1] - x[k], disc.mesh_size, grading, toward_end))
    return counts


def _across(length: float, scene: Scene) -> tuple[int, float]:
    """Elements and progression of a line across the section toward the die wall
    (discretisation.wall_grading)."""
    disc = scene.discretisation
    return graded_edge(length, disc.mesh_size, disc.wall_grading, toward_end=True)


def _roles_along(scene: Scene, stretches: int) -> list[str]:
    """The role of the outer faces of each stretch: the stock ahead of the die free (drawing) or
    in the container (extrusion), the die and its land in contact, the product free."""
    ahead = "gamma3_contact" if scene.process.kind == "extrusion" else "gamma2_free"
    return [ahead] + ["gamma3_contact"] * (stretches - 2) + ["gamma4_free"]


def _end_roles(scene: Scene) -> tuple[str, str]:
    """(entry face's role, exit face's role): Gamma1 where the velocity is prescribed, the other
    end carrying F_N (Gamma5) or free."""
    loaded = "gamma5_force" if scene.process.applied_force is not None else None
    if scene.process.drive == "push":
        return "gamma1_velocity", loaded or "gamma4_free"
    return loaded or "gamma2_free", "gamma1_velocity"


def rectangular_bar(scene: Scene) -> None:
    """The quarter of a rectangular bar: a block per stretch of the axis, its corners at
    (x, 0, 0), (x, h, 0), (x, h, w), (x, 0, w)."""
    at = stations(scene)
    blocks = HexBlocks()
    (n_y, r_y), (n_z, r_z) = _across(at[0][1], scene), _across(at[0][2], scene)
    sections = [[blocks.point(x, 0.0, 0.0), blocks.point(x, h, 0.0), blocks.point(x, h, w),
                 blocks.point(x, 0.0, w)] for x, h, w in at]
    # around the section from the axis: up to the top, along it to the side, down, back: each
    # refined toward the wall (y = h, then z = w)
    lines = ((n_y, r_y), (n_z, r_z), (n_y, 1.0 / r_y), (n_z, 1.0 / r_z))
    for corners in sections:
        for (a, b), (n, ratio) in zip(zip(corners, [*corners[1:], corners[0]]), lines,
                                      strict=True):
            blocks.line(a, b, n, ratio)
    for (n_x, ratio), low, high in zip(_axial(scene, [s[0] for s in at]), sections[:-1],
                                       sections[1:],
                                       strict=True):
        for a, b in zip(low, high, strict=True):
            blocks.line(a, b, n_x, ratio)
    roles = _roles_along(scene, len(at) - 1)
    entry, exit = _end_roles(scene)
    blocks.face(sections[0], entry)
    blocks.face(sections[-1], exit)
    for role, low, high in zip(roles, sections[:-1], sections[1:], strict=True):
        blocks.face([low[0], low[1], high[1], high[0]], "gamma7_symmetry")  # z = 0
        blocks.face([low[1], low[2], high[2], high[1]], role)  # the top, y = h(x)
        blocks.face([low[2], low[3], high[3], high[2]], role)  # the side, z = w(x)
        blocks.face([low[3], low[0], high[0], high[3]], "gamma6_symmetry")  # y = 0
        blocks.volume(low, high)
    blocks.finish()


def round_bar(scene: Scene) -> None:
    """The quarter of a round bar: in every section a square core [0, c R]^2 (c = CORE) and two
    blocks from its outer sides to the quarter circle of radius R, joined at 45 degrees."""
    size = scene.discretisation.mesh_size
    at = stations(scene)
    blocks = HexBlocks()
    radius0 = at[0][1]
    n_core = max(1, math.ceil(CORE * radius0 / size - 1e-9))
    n_ring, r_ring = _across((1 - CORE) * radius0, scene)
    sections = []
    for x, radius, _ in at:
        core, diagonal = CORE * radius, radius / math.sqrt(2.0)
        names = {"o": (0.0, 0.0), "cy": (core, 0.0), "cc": (core, core), "cz": (0.0, core),
                 "ry": (radius, 0.0), "rd": (diagonal, diagonal), "rz": (0.0, radius)}
        section = {k: blocks.point(x, y, z) for k, (y, z) in names.items()}
        centre = blocks.point(x, 0.0, 0.0)
        for a, b, n, ratio in (("o", "cy", n_core, 1.0), ("cy", "cc", n_core, 1.0),
                               ("cc", "cz", n_core, 1.0), ("cz", "o", n_core, 1.0),
                               ("cy", "ry", n_ring, r_ring), ("cc", "rd", n_ring, r_ring),
                               ("cz", "rz", n_ring, r_ring)):
            blocks.line(section[a], section[b], n, ratio)
        blocks.line(section["ry"], section["rd"], n_core, centre=centre)
        blocks.line(section["rd"], section["rz"], n_core, centre=centre)
        sections.append(section)
    quads = {"core": ("o", "cy", "cc", "cz"), "lower": ("cy", "ry", "rd", "cc"),
             "upper": ("cz", "cc", "rd", "rz")}
    for (n_x, ratio), low, high in zip(_axial(scene, [s[0] for s in at]), sections[:-1],
                                       sections[1:],
                                       strict=True):
        for key in low:
            blocks.line(low[key], high[key], n_x, ratio)
    roles = _roles_along(scene, len(at) - 1)
    entry, exit = _end_roles(scene)
    for quad in quads.values():
        blocks.face([sections[0][k] for k in quad], entry)
        blocks.face([sections[-1][k] for k in quad], exit)
    for role, low, high in zip(roles, sections[:-1], sections[1:], strict=True):
        for a, b, face_role in (("o", "cy", "gamma7_symmetry"), ("cy", "ry", "gamma7_symmetry"),
                                ("cz", "o", "gamma6_symmetry"), ("rz", "cz", "gamma6_symmetry"),
                                ("ry", "rd", role), ("rd", "rz", role)):
            blocks.face([low[a], low[b], high[b], high[a]], face_role)
        for quad in quads.values():
            blocks.volume([low[k] for k in quad], [high[k] for k in quad])
    blocks.finish()

"""A user's Gmsh .msh file (geometry.mesh_file): its checks and the dimensions the scene takes
from it.

The workpiece flows along +x with its symmetry line on y = 0 (a 3D model: its symmetry planes
y = 0 and, for a quarter, z = 0); its entry and exit half-thicknesses are the largest y on its
upstream (smallest x) and downstream (largest x) end faces, a 3D model's half-widths the largest
z there.
"""
from __future__ import annotations

from contextlib import contextmanager
from dataclasses import dataclass
from itertools import product

import gmsh
import numpy as np

from forming_fenicsx.core.errors import SceneError
from forming_fenicsx.core.roles import REQUIRED_ROLES, ROLES

QUADRILATERALS = {3: "4-node quadrilateral", 10: "9-node quadrilateral"}  # gmsh element types
HEXAHEDRA = {5: "8-node hexahedron", 12: "27-node hexahedron"}
# the reference hexahedron's corners and centre, where a 3D cell's Jacobian is checked
HEXAHEDRON_POINTS = [*(float(c) for corner in product((-1, 1), repeat=3) for c in corner),
                     0.0, 0.0, 0.0]


@contextmanager
def gmsh_session():
    """An initialised gmsh that prints nothing, finalised afterwards."""
    gmsh.initialize()
    gmsh.option.setNumber("General.Terminal", 0)
    try:
        yield
    finally:
        gmsh.finalize()


@dataclass(frozen=True)
class MeshDimensions:
    """Extent of a user's workpiece mesh: full entry and exit thicknesses (twice the half model's
    largest y on the end faces; a 3D model's heights or diameters), the length along x and, for a
    3D model, the full entry and exit widths (twice its largest z there)."""

    entry_thickness: float
    exit_thickness: float
    length: float
    entry_width: float | None = None
    exit_width: float | None = None


def _quad_jacobians() -> np.ndarray:
    """Signed Jacobian determinants of the bilinear map of every quadrilateral of the current gmsh
    model at its four corners and its centre (gmsh's own are unsigned for 2-D cells)."""
    tags, points, _ = gmsh.model.mesh.getNodes()
    position = dict(zip(tags.tolist(), range(len(tags)), strict=True))
    values = []
    for element_type in QUADRILATERALS:
        if element_type not in gmsh.model.mesh.getElementTypes(2):
            continue
        nodes = gmsh.model.mesh.getElementsByType(element_type)[1].reshape(
            -1, 4 if element_type == 3 else 9)
        x = points.reshape(-1, 3)[[[position[n] for n in quad[:4]]
                                   for quad in nodes.tolist()]][:, :, :2]
        following, preceding = np.roll(x, -1, axis=1) - x, np.roll(x, 1, axis=1) - x
        corners = following[:, :, 0] * preceding[:, :, 1] - following[:, :, 1] * preceding[:, :, 0]
        d1, d2 = x[:, 2] - x[:, 0], x[:, 3] - x[:, 1]
        centre = 0.5 * (d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0])
        values.append(np.column_stack([corners, centre]).ravel())
    return np.concatenate(values)


def _open(path: str) -> None:
    try:
        gmsh.open(path)
    except Exception as error:
        raise SceneError("geometry.mesh_file", f"{path}: Gmsh cannot read it ({error})") from error


def _role_names() -> dict[int, str]:
    """The current model's boundary groups (of one dimension below the model's): file tag ->
    name."""
    boundary = gmsh.model.getDimension() - 1
    return {tag: gmsh.model.getPhysicalName(boundary, tag)
            for dim, tag in gmsh.model.getPhysicalGroups() if dim == boundary}


def _hex_jacobians() -> np.ndarray:
    """Jacobian determinants of every hexahedron of the current gmsh model at its eight corners
    and its centre (gmsh's, signed for 3-D cells)."""
    return np.concatenate([gmsh.model.mesh.getJacobians(element_type, HEXAHEDRON_POINTS)[1]
                           for element_type in HEXAHEDRA
                           if element_type in gmsh.model.mesh.getElementTypes(3)])


def open_msh(path: str) -> dict[int, int]:
    """Open a user's .msh (checked when the scene was read: mesh_dimensions) in the current gmsh
    session; returns file tag -> role tag."""
    _open(path)
    return {tag: ROLES[name] for tag, name in _role_names().items()}


def _check_msh(path: str, three_dimensional: bool = False) -> MeshDimensions:
    """Open a user's .msh in the current gmsh session and check it; returns the workpiece's
    dimensions.

    Raises SceneError (key geometry.mesh_file) for a mesh of the other dimension than the scene's
    (plane 2-D, or 3-D with symmetry = "3d"), cells other than quadrilaterals (hexahedra in 3D),
    a missing required role, unknown role names, a boundary edge (face) with two roles, inverted
    or degenerate elements, or nodes on the wrong side of a symmetry plane.
    """
    def fail(message: str) -> None:
        raise SceneError("geometry.mesh_file", f"{path}: {message}")

    _open(path)
    groups = gmsh.model.getPhysicalGroups()
    solid = any(dim == 3 for dim, _ in groups) or len(gmsh.model.mesh.getElementTypes(3)) > 0
    if solid and not three_dimensional:
        fail('a 3-D mesh; only plane (2-D) meshes are supported unless geometry.symmetry = "3d"')
    if three_dimensional and not solid:
        fail('a 2-D mesh; geometry.symmetry = "3d" needs a 3-D mesh of hexahedra')
    dim, cells = (3, HEXAHEDRA) if three_dimensional else (2, QUADRILATERALS)
    if not any(d == dim for d, _ in groups):
        fail(f"no physical group of dimension {dim} (the workpiece's cells)")
    coordinates = gmsh.model.mesh.getNodes()[1].reshape(-1, 3)
    extent = max(np.ptp(coordinates, axis=0).max(), 1e-300)
    if not three_dimensional and np.abs(coordinates[:, 2]).max() > 1e-12 * extent:
        fail("not plane: nodes with z != 0")
    other = [gmsh.model.mesh.getElementProperties(t)[0]
             for t in gmsh.model.mesh.getElementTypes(dim) if t not in cells]
    if other:
        fail(f"unsupported cells ({', '.join(other)}); use "
             f"{'8- or 27-node hexahedra' if three_dimensional else '4- or 9-node quadrilaterals'}")
    names = _role_names()
    unknown = sorted(name for name in names.values() if name not in ROLES)
    if unknown:
        fail(f"unknown boundary role names {unknown}; allowed: {', '.join(ROLES)}")
    missing = [role for role in REQUIRED_ROLES if role not in names.values()]
    if missing:
        fail(f"missing boundary roles {missing} (physical groups of dimension {dim - 1} with "
             "these names)")
    owner: dict[tuple[int, ...], str] = {}
    for tag, name in names.items():
        for entity in gmsh.model.getEntitiesForPhysicalGroup(dim - 1, tag):
            types, _, node_lists = gmsh.model.mesh.getElements(dim - 1, entity)
            for element_type, nodes in zip(types, node_lists, strict=True):
                properties = gmsh.model.mesh.getElementProperties(element_type)
                for side in np.asarray(nodes).reshape(-1, properties[3])[:, :properties[5]]:
                    key = tuple(sorted(int(n) for n in side))
                    if owner.setdefault(key, name) != name:
                        fail(f"overlapping roles: {'a face' if three_dimensional else 'an edge'} "
                             f"belongs to both {owner[key]} and {name}")
    determinants = _hex_jacobians() if three_dimensional else _quad_jacobians()
    largest = np.abs(determinants).max()
    if determinants.min() * determinants.max() < 0:
        flipped = int((np.sign(determinants) != np.sign(np.median(determinants))).sum())
        fail(f"inverted elements: the Jacobian changes sign ({flipped} of the corner and centre "
             "points of the cells)")
    if np.abs(determinants).min() < 1e-10 * largest:
        fail("degenerate elements: a Jacobian determinant is (nearly) zero")
    x = coordinates[:, 0]
    for axis in "yz"[:dim - 1]:
        low = coordinates[:, "xyz".index(axis)].min()
        if low < -1e-9 * extent:
            fail(f"nodes below {axis} = 0 (down to {axis} = {low:.6g}): the "
                 f"{'model' if three_dimensional else 'half model'} lies on {axis} >= 0 with its "
                 f"symmetry {'plane' if three_dimensional else 'line'} on {axis} = 0")
    upstream, downstream = x <= x.min() + 1e-9 * extent, x >= x.max() - 1e-9 * extent
    sizes = [2 * float(coordinates[end, axis].max()) for axis in range(1, dim)
             for end in (upstream, downstream)]
    return MeshDimensions(sizes[0], sizes[1], float(np.ptp(x)), *sizes[2:])


def mesh_dimensions(path: str, three_dimensional: bool = False) -> MeshDimensions:
    """Check a user's .msh file (_check_msh) in a gmsh session of its own and return its
    dimensions."""
    with gmsh_session():
        return _check_msh(path, three_dimensional)

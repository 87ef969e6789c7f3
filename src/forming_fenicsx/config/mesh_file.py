"""A user's Gmsh .msh file (geometry.mesh_file): its checks and the dimensions the scene takes
from it.

The workpiece flows along +x with its symmetry line on y = 0; its entry and exit half-thicknesses
are the largest y on its upstream (smallest x) and downstream (largest x) end faces.
"""
from __future__ import annotations

from contextlib import contextmanager
from dataclasses import dataclass

import gmsh
import numpy as np

from forming_fenicsx.core.errors import SceneError
from forming_fenicsx.core.roles import REQUIRED_ROLES, ROLES

QUADRILATERALS = {3: "4-node quadrilateral", 10: "9-node quadrilateral"}  # gmsh element types


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
    """Extent of a user's workpiece mesh: full entry and exit thicknesses (twice the half model's)
    and the length along x."""

    entry_thickness: float
    exit_thickness: float
    length: float


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
    """The current model's boundary groups: file tag -> name."""
    return {tag: gmsh.model.getPhysicalName(1, tag) for dim, tag in gmsh.model.getPhysicalGroups()
            if dim == 1}


def open_msh(path: str) -> dict[int, int]:
    """Open a user's .msh (checked when the scene was read: mesh_dimensions) in the current gmsh
    session; returns file tag -> role tag."""
    _open(path)
    return {tag: ROLES[name] for tag, name in _role_names().items()}


def _check_msh(path: str) -> MeshDimensions:
    """Open a user's .msh in the current gmsh session and check it; returns the workpiece's
    dimensions.

    Raises SceneError (key geometry.mesh_file) for a mesh that is not plane 2-D, has cells other
    than quadrilaterals, misses a required role, names unknown roles, gives one edge two roles, or
    has inverted or degenerate elements.
    """
    def fail(message: str) -> None:
        raise SceneError("geometry.mesh_file", f"{path}: {message}")

    _open(path)
    groups = gmsh.model.getPhysicalGroups()
    if any(dim == 3 for dim, _ in groups) or len(gmsh.model.mesh.getElementTypes(3)):
        fail("a 3-D mesh; only plane (2-D) meshes are supported")
    if not any(dim == 2 for dim, _ in groups):
        fail("no physical group of dimension 2 (the workpiece's cells)")
    coordinates = gmsh.model.mesh.getNodes()[1].reshape(-1, 3)
    extent = max(np.ptp(coordinates[:, :2], axis=0).max(), 1e-300)
    if np.abs(coordinates[:, 2]).max() > 1e-12 * extent:
        fail("not plane: nodes with z != 0")
    other = [gmsh.model.mesh.getElementProperties(t)[0] for t in gmsh.model.mesh.getElementTypes(2)
             if t not in QUADRILATERALS]
    if other:
        fail(f"unsupported cells ({', '.join(other)}); use 4- or 9-node quadrilaterals")
    names = _role_names()
    unknown = sorted(name for name in names.values() if name not in ROLES)
    if unknown:
        fail(f"unknown boundary role names {unknown}; allowed: {', '.join(ROLES)}")
    missing = [role for role in REQUIRED_ROLES if role not in names.values()]
    if missing:
        fail(f"missing boundary roles {missing} (physical groups of dimension 1 with these names)")
    owner: dict[tuple[int, int], str] = {}
    for tag, name in names.items():
        for entity in gmsh.model.getEntitiesForPhysicalGroup(1, tag):
            types, _, node_lists = gmsh.model.mesh.getElements(1, entity)
            for element_type, nodes in zip(types, node_lists, strict=True):
                per_edge = gmsh.model.mesh.getElementProperties(element_type)[3]
                for edge in np.asarray(nodes).reshape(-1, per_edge)[:, :2]:
                    key = tuple(sorted(int(n) for n in edge))
                    if owner.setdefault(key, name) != name:
                        fail(f"overlapping roles: an edge belongs to both {owner[key]} and {name}")
    determinants = _quad_jacobians()
    largest = np.abs(determinants).max()
    if determinants.min() * determinants.max() < 0:
        flipped = int((np.sign(determinants) != np.sign(np.median(determinants))).sum())
        fail(f"inverted elements: the Jacobian changes sign ({flipped} of the corner and centre "
             "points of the cells)")
    if np.abs(determinants).min() < 1e-10 * largest:
        fail("degenerate elements: a Jacobian determinant is (nearly) zero")
    x, y = coordinates[:, 0], coordinates[:, 1]
    if y.min() < -1e-9 * extent:
        fail(f"nodes below y = 0 (down to y = {y.min():.6g}): the half model lies on y >= 0 with "
             "its symmetry line on y = 0")
    upstream, downstream = x <= x.min() + 1e-9 * extent, x >= x.max() - 1e-9 * extent
    return MeshDimensions(2 * float(y[upstream].max()), 2 * float(y[downstream].max()),
                          float(np.ptp(x)))


def mesh_dimensions(path: str) -> MeshDimensions:
    """Check a user's .msh file (_check_msh) in a gmsh session of its own and return its
    dimensions."""
    with gmsh_session():
        return _check_msh(path)

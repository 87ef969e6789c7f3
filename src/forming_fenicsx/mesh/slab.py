"""A one-element-thick 3D slab of a plane-strain model: the scene's own 2D gmsh model extruded
along z by one recombined layer of hexahedra, to check the 3D code against plane strain (issue 36).

Each face extruded from a boundary curve takes the curve's role; both faces z = 0 and z = t are
Gamma7 (u_z = 0, (2.8)), so that the plane-strain velocity, extended constantly in z with u_z = 0,
solves the slab's discrete problem: its z derivatives vanish, the stress has no xz and yz parts,
and the hexahedra's Gauss rules are the quadrilaterals' times one in z.
"""
from __future__ import annotations

from functools import partial

import gmsh
from mpi4py import MPI

from forming_fenicsx.config.loader import scene_from_dict
from forming_fenicsx.config.scene import Scene
from forming_fenicsx.core.roles import ROLES, WORKPIECE
from forming_fenicsx.mesh.geometry import FormingMesh, add_model, build_mesh, mesh_model


def slab_scene(scene: Scene, thickness: float) -> Scene:
    """The 3D scene of the slab: the plane-strain ``scene`` as a bar of rectangular section,
    heights its thicknesses, width 2 ``thickness`` at entry and exit (the model is its half z > 0,
    CoordinateSystem.whole counting the plane z = 0), and every length, penalty and mesh size the
    2D scene resolved to (absolute, as the 3D defaults differ)."""
    if scene.geometry.symmetry != "plane_strain":
        raise ValueError("a slab extrudes a plane-strain model; got symmetry = "
                         f"{scene.geometry.symmetry!r}")
    data = {name: {key: value for key, value in section.items() if value is not None
                   and not (key.endswith("_relative")
                            and section.get(key.removesuffix("_relative")) is not None)}
            for name, section in scene.to_dict().items() if section is not None}
    geometry = data["geometry"]
    geometry.pop("width", None)
    geometry.update({"symmetry": "3d", "section": "rectangle",
                     "entry_height": geometry.pop("entry_thickness"),
                     "exit_height": geometry.pop("exit_thickness"),
                     "entry_width": 2 * thickness, "exit_width": 2 * thickness})
    return scene_from_dict(data)


def _extruded(scene: Scene, thickness: float) -> None:
    """The scene's 2D model extruded by ``thickness`` in one layer and meshed: the workpiece the
    volumes, each role on the faces swept by its curves, Gamma7 on both ends z = 0 and z = t."""
    add_model(scene)
    curves = {role: gmsh.model.getEntitiesForPhysicalGroup(1, tag)
              for role, tag in ROLES.items()
              if (1, tag) in gmsh.model.getPhysicalGroups(1)}
    surfaces = list(gmsh.model.getEntitiesForPhysicalGroup(2, WORKPIECE))
    gmsh.model.removePhysicalGroups()
    swept = gmsh.model.geo.extrude([(2, s) for s in surfaces], 0.0, 0.0, thickness,
                                   numElements=[1], recombine=True)
    gmsh.model.geo.synchronize()
    volumes = [tag for dim, tag in swept if dim == 3]
    # each input surface's output starts with its copy at z = t, then its volume
    ends = surfaces + [tag for (dim, tag), (next_dim, _) in zip(swept, swept[1:]) if next_dim == 3]
    gmsh.model.addPhysicalGroup(3, volumes, WORKPIECE)
    groups = {"gamma7_symmetry": ends}
    for role, tags in curves.items():  # a curve's faces: its surface's and the one it swept
        groups[role] = [face for curve in tags
                        for face in gmsh.model.getAdjacencies(1, curve)[0] if face not in surfaces]
    for role, faces in groups.items():
        gmsh.model.addPhysicalGroup(2, faces, ROLES[role])
        gmsh.model.setPhysicalName(2, ROLES[role], role)
    mesh_model(3, scene.discretisation.degree)


def slab_mesh(scene: Scene, thickness: float, comm: MPI.Comm = MPI.COMM_WORLD
              ) -> tuple[Scene, FormingMesh]:
    """The slab's scene (slab_scene) and mesh: the plane-strain ``scene``'s model extruded by
    ``thickness``, distributed as build_mesh distributes the scene's own."""
    slab = slab_scene(scene, thickness)
    return slab, build_mesh(slab, comm, partial(_extruded, scene, thickness))

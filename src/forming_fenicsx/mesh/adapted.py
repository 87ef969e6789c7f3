"""Meshes adapted to an error indicator (accuracy on demand, docs/accuracy.md): the scene's 2D
blocks, without their transfinite constraints, meshed by gmsh with a background size field given
cell by cell on the previous mesh, all quadrilaterals (recombined triangles, each split in four).

The sizes equidistribute the indicator: with eta_K the indicator of cell K of size h_K and p the
element degree (the energy-norm error of a smooth solution falls as h^p), the new size is
h_new = s h_K (eta_mean/eta_K)^(1/p), within [h_K/REFINE, COARSEN h_K], the scale s such that
the new mesh has a chosen number of cells, sum (h_K/h_new)^2.
"""
from __future__ import annotations

from collections.abc import Callable

import gmsh
import numpy as np

from forming_fenicsx.config.scene import Scene
from forming_fenicsx.mesh.geometry import add_model, mesh_model

REFINE, COARSEN = 4.0, 2.0  # a cell's new size within [h_K/REFINE, COARSEN h_K] per level
# gmsh's all-quadrilateral subdivision halves the elements it is asked for
SUBDIVISION = 2.0


def adapted_sizes(indicator: np.ndarray, sizes: np.ndarray, cells: float,
                  degree: int) -> np.ndarray:
    """New cell sizes h_new for cells of sizes h_K with indicators eta_K (module docstring), about
    ``cells`` cells in all."""
    eta = np.sqrt(np.maximum(indicator, 0.0))
    mean = eta.mean()
    if not mean > 0:
        return sizes / np.sqrt(cells / len(sizes))
    relative = np.maximum(eta / mean, 1e-12) ** (1.0 / degree)

    def new(scale: float) -> np.ndarray:
        return np.clip(scale * sizes / relative, sizes / REFINE, COARSEN * sizes)

    low, high = 1e-9, 1e9
    for _ in range(200):  # bisection on log(scale): the count falls as the scale grows
        scale = np.sqrt(low * high)
        low, high = (scale, high) if np.sum((sizes / new(scale)) ** 2) > cells else (low, scale)
    return new(np.sqrt(low * high))


def size_field_mesh(scene: Scene, corners: np.ndarray, sizes: np.ndarray,
                    add: Callable[[], None] | None = None) -> Callable[[], None]:
    """A generator for mesh/geometry.build_mesh: the scene's 2D workpiece (or the unmeshed model
    that ``add`` puts in the session, e.g. a verification's own domain) meshed with the size
    ``sizes[K]`` over the quadrilateral ``corners[K]`` (cells, 4, 2; in order around it), in the
    current gmsh session (rank 0), with the scene's element degree."""
    def generate() -> None:
        if add is None:
            add_model(scene, structured=False)
        else:
            add()
        view = gmsh.view.add("size")
        z = np.zeros(corners.shape[:2])
        values = np.repeat(SUBDIVISION * sizes[:, None], 4, axis=1)
        data = np.concatenate([corners[:, :, 0], corners[:, :, 1], z, values], axis=1)
        gmsh.view.addListData(view, "SQ", len(sizes), data.ravel().tolist())
        field = gmsh.model.mesh.field.add("PostView")
        gmsh.model.mesh.field.setNumber(field, "ViewTag", view)
        gmsh.model.mesh.field.setAsBackgroundMesh(field)
        for option in ("MeshSizeExtendFromBoundary", "MeshSizeFromPoints",
                       "MeshSizeFromCurvature"):
            gmsh.option.setNumber(f"Mesh.{option}", 0)
        gmsh.option.setNumber("Mesh.Algorithm", 6)  # frontal-Delaunay (8 crashes gmsh 4.8)
        gmsh.option.setNumber("Mesh.RecombinationAlgorithm", 1)  # blossom
        gmsh.option.setNumber("Mesh.RecombineAll", 1)
        gmsh.option.setNumber("Mesh.SubdivisionAlgorithm", 1)  # every cell a quadrilateral
        mesh_model(2, scene.discretisation.degree)
        gmsh.view.remove(view)

    return generate

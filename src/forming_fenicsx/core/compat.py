"""Every difference between the supported dolfinx releases (0.5 on Debian 12, 0.9 on Debian 13),
and between the NumPy they come with (1.24 and 2.2).

Nothing outside this module looks at ``dolfinx.__version__`` or NumPy's.
"""
from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
import dolfinx
import dolfinx.fem
import dolfinx.mesh
import ufl
from mpi4py import MPI
from petsc4py import PETSc

if TYPE_CHECKING:
    import gmsh

DOLFINX_VERSION = tuple(int(p) for p in dolfinx.__version__.split(".")[:2])
LEGACY = DOLFINX_VERSION < (0, 7)

# the trapezoidal rule: np.trapz in NumPy 1 (Debian 12), np.trapezoid from NumPy 2 (Debian 13,
# which deprecates trapz)
trapezoid = getattr(np, "trapezoid", None) or np.trapz

GHOST_MODE = dolfinx.mesh.GhostMode.shared_facet
"""Every mesh's ghosts on several ranks: the cells across the facets a rank shares, without which
an interior-facet integral (the upwind-DG strain transport) misses those facets (0.5 leaves them
out silently, 0.9 stops). The built-in meshes' default in both releases and 0.5's create_mesh's;
0.9's create_mesh, which gmshio calls, ghosts nothing unless given a partitioner."""


def mesh_from_gmsh(model: type[gmsh.model], comm: MPI.Comm, rank: int, gdim: int) -> tuple[
        dolfinx.mesh.Mesh, dolfinx.mesh.MeshTags, dolfinx.mesh.MeshTags]:
    """The gmsh ``model`` of rank ``rank`` distributed over ``comm`` with GHOST_MODE:
    (mesh, cell tags, facet tags)."""
    from dolfinx.io import gmshio

    if LEGACY:  # model_to_mesh takes no partitioner; its create_mesh ghosts shared facets
        return gmshio.model_to_mesh(model, comm, rank, gdim=gdim)
    partitioner = dolfinx.mesh.create_cell_partitioner(GHOST_MODE)
    return gmshio.model_to_mesh(model, comm, rank, gdim=gdim, partitioner=partitioner)


def function_space(mesh, family: str, degree: int, shape: tuple[int, ...] = ()):
    """A Lagrange ("P") or discontinuous Lagrange ("DP") space, scalar or vector valued."""
    if LEGACY:
        legacy_family = {"P": "CG", "DP": "DG"}[family]
        if family == "DP" and mesh.topology.cell_type in (dolfinx.mesh.CellType.quadrilateral,
                                                          dolfinx.mesh.CellType.hexahedron):
            legacy_family = "DQ"  # what UFL 2022 makes of "DG" on quads and hexes, with a warning
        if shape:
            return dolfinx.fem.VectorFunctionSpace(mesh, (legacy_family, degree), dim=shape[0])
        return dolfinx.fem.FunctionSpace(mesh, (legacy_family, degree))
    name = {"P": "Lagrange", "DP": "DG"}[family]
    return dolfinx.fem.functionspace(mesh, (name, degree, shape) if shape else (name, degree))


def petsc_vec(u: dolfinx.fem.Function) -> PETSc.Vec:
    """The PETSc vector that wraps a Function's degrees of freedom."""
    return u.vector if LEGACY else u.x.petsc_vec


def interpolation_matrix(space0, space1) -> PETSc.Mat:
    """The matrix of the interpolation from ``space0`` into ``space1`` (rows: space1's dofs,
    unrolled), assembled: the C++ binding in 0.5, dolfinx.fem.petsc.interpolation_matrix from
    0.8."""
    if LEGACY:
        from dolfinx.cpp.fem.petsc import interpolation_matrix as legacy

        matrix = legacy(space0._cpp_object, space1._cpp_object)
    else:
        import dolfinx.fem.petsc

        matrix = dolfinx.fem.petsc.interpolation_matrix(space0, space1)
    matrix.assemble()  # 0.5 leaves it unassembled
    return matrix


def cell_geometry_nodes(mesh) -> np.ndarray:
    """Geometry node indices of every local cell, shape (cells, nodes per cell)."""
    dofmap = mesh.geometry.dofmap
    if LEGACY:
        ncells = mesh.topology.index_map(mesh.topology.dim).size_local + \
            mesh.topology.index_map(mesh.topology.dim).num_ghosts
        return dofmap.array.reshape(ncells, -1)
    return np.asarray(dofmap)


def original_cell_index(mesh) -> np.ndarray:
    """The index each local cell had in the cell list the mesh was created from."""
    index = mesh.topology.original_cell_index
    return np.asarray(index if LEGACY else index[0] if isinstance(index, list) else index)


def geometry_degree(mesh) -> int:
    """Polynomial degree of the coordinate map."""
    return mesh.geometry.cmap.degree


def quadrature_space(mesh, degree: int, shape: tuple[int, ...]):
    """Values at the Gauss points of ``ufl.dx(metadata={"quadrature_degree": degree})``, per
    cell."""
    if LEGACY:
        import ufl

        if not shape:
            element = ufl.FiniteElement("Quadrature", mesh.ufl_cell(), degree,
                                        quad_scheme="default")
        elif len(shape) == 1:
            element = ufl.VectorElement("Quadrature", mesh.ufl_cell(), degree, dim=shape[0],
                                        quad_scheme="default")
        else:
            element = ufl.TensorElement("Quadrature", mesh.ufl_cell(), degree,
                                        quad_scheme="default", shape=shape)
        return dolfinx.fem.FunctionSpace(mesh, element)
    import basix.ufl

    element = basix.ufl.quadrature_element(mesh.basix_cell(), value_shape=shape, degree=degree)
    return dolfinx.fem.functionspace(mesh, element)


def quadrature_points(mesh, degree: int) -> np.ndarray:
    """Reference Gauss points of the default scheme of that degree on the mesh's cells."""
    import basix

    cell = getattr(basix.CellType, mesh.topology.cell_type.name)
    return basix.make_quadrature(cell, degree)[0]


def cell_dofs(dofmap) -> np.ndarray:
    """The (unblocked) degrees of freedom of every local cell, shape (cells, dofs per cell)."""
    if LEGACY:
        return dofmap.list.array.reshape(-1, dofmap.dof_layout.num_dofs)
    return np.asarray(dofmap.list)


def basix_element(of):
    """The basix element of a function space (``of``), or None where its cell dofs need
    transformations; or of a mesh's coordinate map (Lagrange, to degree 2, where the variants
    agree), or None above."""
    import basix

    if isinstance(of, dolfinx.mesh.Mesh):
        degree = of.geometry.cmap.degree
        if degree > 2:
            return None
        cell = getattr(basix.CellType, of.topology.cell_type.name)
        return basix.create_element(basix.ElementFamily.P, cell, degree,
                                    basix.LagrangeVariant.gll_warped)
    if of.element.needs_dof_transformations:
        return None
    return of.element.basix_element


def set_at_quadrature_points(function: dolfinx.fem.Function,
                             expression: dolfinx.fem.Expression) -> None:
    """function <- expression evaluated at the Gauss points of every local cell (then ghosts
    updated)."""
    mesh = function.function_space.mesh
    cells = np.arange(mesh.topology.index_map(mesh.topology.dim).size_local, dtype=np.int32)
    values = expression.eval(cells) if LEGACY else expression.eval(mesh, cells)
    dofmap = function.function_space.dofmap
    dofs = cell_dofs(dofmap)[cells]
    block = dofmap.index_map_bs
    function.x.array.reshape(-1, block)[dofs.ravel()] = values.reshape(dofs.size, block)
    function.x.scatter_forward()


def mixed_space(mesh, velocity_degree: int, pressure_family: str, pressure_degree: int):
    """The velocity-pressure space (vector Lagrange x ``pressure_family``, e.g. "DPC" for P1
    discontinuous on quadrilaterals)."""
    if LEGACY:
        import ufl

        velocity = ufl.VectorElement("Lagrange", mesh.ufl_cell(), velocity_degree)
        pressure = ufl.FiniteElement(pressure_family, mesh.ufl_cell(), pressure_degree)
        return dolfinx.fem.FunctionSpace(mesh, ufl.MixedElement([velocity, pressure]))
    import basix.ufl

    cell = mesh.basix_cell()
    velocity = basix.ufl.element("Lagrange", cell, velocity_degree, shape=(mesh.geometry.dim,))
    pressure = basix.ufl.element(pressure_family, cell, pressure_degree)
    return dolfinx.fem.functionspace(mesh, basix.ufl.mixed_element([velocity, pressure]))


def bounding_box_tree(mesh):
    """The bounding-box tree of the mesh's local cells (owned and ghost), for colliding_cells."""
    import dolfinx.geometry as geometry

    tdim = mesh.topology.dim
    if LEGACY:
        return geometry.BoundingBoxTree(mesh, tdim)
    return geometry.bb_tree(mesh, tdim)


def colliding_cells(mesh, points: np.ndarray, tree=None) -> np.ndarray:
    """For each point (shape (N, 3)), a local cell (owned or ghost) that contains it, or -1;
    ``tree`` a bounding_box_tree of the mesh to reuse (else one is built)."""
    import dolfinx.geometry as geometry

    tree = bounding_box_tree(mesh) if tree is None else tree
    if LEGACY:
        candidates = geometry.compute_collisions(tree, points)
    else:
        candidates = geometry.compute_collisions_points(tree, points)
    colliding = geometry.compute_colliding_cells(mesh, candidates, points)
    offsets = np.asarray(colliding.offsets)
    cells = np.full(len(points), -1, dtype=np.int32)
    hit = offsets[1:] > offsets[:-1]
    cells[hit] = np.asarray(colliding.array)[offsets[:-1][hit]]  # the first colliding cell of each
    return cells


def closest_cells(mesh, points: np.ndarray, tree, midpoints) -> tuple[np.ndarray, np.ndarray]:
    """For each point (N, 3), the local cell nearest to it and the squared distance to that cell's
    nodes' convex hull; ``midpoints`` the tree of the cells' midpoints
    (geometry.create_midpoint_tree, the same in both releases)."""
    import dolfinx.geometry as geometry

    cells = np.asarray(geometry.compute_closest_entity(tree, midpoints, mesh, points),
                       dtype=np.int32)
    return cells, np.asarray(geometry.squared_distance(mesh, mesh.topology.dim, cells, points))


def atan2(y, x):
    """UFL's two-argument arctangent: ufl.atan_2 in UFL 2022 (Debian 12), ufl.atan2 in 2024."""
    return (ufl.atan2 if hasattr(ufl, "atan2") else ufl.atan_2)(y, x)

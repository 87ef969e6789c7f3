"""A velocity carried from one mesh to another of the same workpiece (dolfinx 0.5 has no
interpolation between non-matching meshes): u_new(x_i) = u_old(x_i) at every node x_i of the new
Lagrange space, by point evaluation in the old mesh's cell that holds x_i.

Both meshes are distributed over the same communicator with unrelated partitions, so every rank
evaluates the old field at all new nodes that lie in its own cells and the values are summed over
the ranks. A new node outside the old mesh (at a curved die wall, whose element edges differ from
mesh to mesh) takes the old field extended from the old cell nearest to it (points.py).

A mesh that is the old one with its nodes moved (same_layout: a free surface's next shape meshed
by the same blocks with the same element counts) takes the old values node for node instead. The
point values of a Q2 field at the nodes of a slightly moved Q2 mesh carry an interpolation error
of O(h^3), whose rates in the almost rigid zones switched the law (4.5)'s branch at 800 Gauss
points and cost Newton 3 to 4 more solves a shape (docs/free_surface.md).
"""
from __future__ import annotations

from typing import Any

import dolfinx.fem
import numpy as np
from mpi4py import MPI

from forming_fenicsx.core.compat import cell_dofs, cell_geometry_nodes
from forming_fenicsx.mesh.points import PointValues


def transfer(source: dolfinx.fem.Function, target: dolfinx.fem.Function,
             nodal: bool = False) -> int:
    """target <- source at target's nodes (collective; both vector Lagrange functions on meshes of
    one communicator), or node for node (``nodal``: the meshes have one layout, same_layout).
    Returns how many nodes lay outside the source mesh (their values extended from the nearest
    cell)."""
    if nodal:
        target.x.array[:] = source.x.array
        return 0
    space = target.function_space
    comm = space.mesh.comm
    block = space.dofmap.index_map_bs
    owned = space.dofmap.index_map.size_local
    points = np.concatenate(comm.allgather(space.tabulate_dof_coordinates()[:owned, :2]))
    evaluate = PointValues([source])
    values = evaluate.evaluate(points, outside="extend")[0]
    start = sum(comm.allgather(owned)[:comm.rank])
    target.x.array[:owned * block] = values[start:start + owned].ravel()
    target.x.scatter_forward()
    return evaluate.missed


def same_layout(source: dolfinx.fem.Function, target: dolfinx.fem.Function,
                facet_tags: tuple[Any, Any]) -> bool:
    """Whether target's mesh is source's with its nodes moved (collective): on every rank the same
    cells on the same geometry nodes, the same degrees of freedom in them, and the same facets
    (``facet_tags``: source's and target's) in the same roles. A free surface's shapes meshed by
    the same blocks with the same element counts are (mesh/geometry.shaped_mesh); a shape whose
    contact ends before the land, its land's cells now the product's, is not."""
    (old_tags, new_tags), old, new = facet_tags, source.function_space, target.function_space
    pairs = [(cell_geometry_nodes(old.mesh), cell_geometry_nodes(new.mesh)),
             (cell_dofs(old.dofmap), cell_dofs(new.dofmap)),
             (old_tags.indices, new_tags.indices), (old_tags.values, new_tags.values)]
    same = source.x.array.shape == target.x.array.shape and all(
        a.shape == b.shape and np.array_equal(a, b) for a, b in pairs)
    return bool(target.function_space.mesh.comm.allreduce(same, op=MPI.LAND))

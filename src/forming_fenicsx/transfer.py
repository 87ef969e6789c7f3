"""A velocity carried from one mesh to another of the same workpiece (dolfinx 0.5 has no
interpolation between non-matching meshes): u_new(x_i) = u_old(x_i) at every node x_i of the new
Lagrange space, by point evaluation in the old mesh's cell that holds x_i.

Both meshes are distributed over the same communicator with unrelated partitions, so every rank
evaluates the old field at all new nodes that lie in its own cells and the values are summed over
the ranks. A new node outside the old mesh (at a curved die wall, whose element edges differ from
mesh to mesh) takes the old field extended from a cell of the old node nearest to it.
"""
from __future__ import annotations

import dolfinx.fem
import numpy as np

from .compat import cell_dofs, colliding_cells


def transfer(source: dolfinx.fem.Function, target: dolfinx.fem.Function) -> int:
    """target <- source at target's nodes (collective; both vector Lagrange functions on meshes of
    one communicator). Returns how many nodes lay outside the source mesh (their values extended
    from the nearest cell)."""
    space = target.function_space
    comm = space.mesh.comm
    block = space.dofmap.index_map_bs
    owned = space.dofmap.index_map.size_local
    points = np.concatenate(comm.allgather(space.tabulate_dof_coordinates()[:owned]))
    cells = colliding_cells(source.function_space.mesh, points)
    found = cells >= 0
    values = np.zeros((len(points), block))
    if found.any():
        values[found] = source.eval(points[found], cells[found])
    # a node on a partition boundary of the old mesh lies in cells of two ranks (the values agree)
    count = comm.allreduce(found.astype(float))
    values = comm.allreduce(values)
    outside = np.flatnonzero(count == 0)
    if len(outside):
        values[outside] = _nearest_cell_values(source, points[outside])
    values /= np.maximum(count, 1.0)[:, None]
    start = sum(comm.allgather(owned)[:comm.rank])
    target.x.array[:owned * block] = values[start:start + owned].ravel()
    target.x.scatter_forward()
    return len(outside)


def _nearest_cell_values(source: dolfinx.fem.Function, points: np.ndarray) -> np.ndarray:
    """The source field at points outside its mesh, extended from a cell that holds the source node
    nearest to each point (the cell's polynomial evaluated beyond it); over all ranks
    (collective)."""
    space = source.function_space
    comm = space.mesh.comm
    nodes = space.tabulate_dof_coordinates()
    dofs = cell_dofs(space.dofmap)
    best = np.full(len(points), np.inf)
    cells = np.full(len(points), -1, dtype=np.int32)
    for i, point in enumerate(points):
        if len(dofs):
            distances = np.einsum("ij,ij->i", nodes - point, nodes - point)
            nearest = int(np.argmin(distances))
            best[i], cells[i] = distances[nearest], np.flatnonzero((dofs == nearest).any(axis=1))[0]
    mine = np.argmin(np.array(comm.allgather(best)), axis=0) == comm.rank  # the nearest node's rank
    values = np.zeros((len(points), space.dofmap.index_map_bs))
    if mine.any():
        values[mine] = source.eval(points[mine], cells[mine])
    return comm.allreduce(values)

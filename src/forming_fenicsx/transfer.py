"""A velocity carried from one mesh to another of the same workpiece (dolfinx 0.5 has no
interpolation between non-matching meshes): u_new(x_i) = u_old(x_i) at every node x_i of the new
Lagrange space, by point evaluation in the old mesh's cell that holds x_i.

Both meshes are distributed over the same communicator with unrelated partitions, so every rank
evaluates the old field at all new nodes that lie in its own cells and the values are summed over
the ranks. A new node outside the old mesh (a curved die wall whose chords differ from mesh to mesh)
takes the value of the nearest old node: the result is a starting iterate, not an answer.
"""
from __future__ import annotations

import dolfinx.fem
import numpy as np

from .compat import colliding_cells


def transfer(source: dolfinx.fem.Function, target: dolfinx.fem.Function) -> int:
    """target <- source at target's nodes (collective; both vector Lagrange functions on meshes of
    one communicator). Returns how many nodes lay outside the source mesh and took the value of the
    nearest node."""
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
        values[outside] = _nearest_node_values(source, points[outside])
    values /= np.maximum(count, 1.0)[:, None]
    start = sum(comm.allgather(owned)[:comm.rank])
    target.x.array[:owned * block] = values[start:start + owned].ravel()
    target.x.scatter_forward()
    return len(outside)


def _nearest_node_values(source: dolfinx.fem.Function, points: np.ndarray) -> np.ndarray:
    """The value of the source's node nearest to each point, over all ranks (collective)."""
    space = source.function_space
    comm = space.mesh.comm
    block = space.dofmap.index_map_bs
    owned = space.dofmap.index_map.size_local
    nodes = space.tabulate_dof_coordinates()[:owned]
    node_values = source.x.array[:owned * block].reshape(-1, block)
    best = np.full(len(points), np.inf)
    chosen = np.zeros((len(points), block))
    for i, point in enumerate(points):
        if len(nodes):
            distances = np.einsum("ij,ij->i", nodes - point, nodes - point)
            nearest = int(np.argmin(distances))
            best[i], chosen[i] = distances[nearest], node_values[nearest]
    ranks = np.argmin(np.array(comm.allgather(best)), axis=0)  # the rank of the nearest node
    return comm.allreduce(np.where((ranks == comm.rank)[:, None], chosen, 0.0))

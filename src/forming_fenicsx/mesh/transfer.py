"""A velocity carried from one mesh to another of the same workpiece (dolfinx 0.5 has no
interpolation between non-matching meshes): u_new(x_i) = u_old(x_i) at every node x_i of the new
Lagrange space, by point evaluation in the old mesh's cell that holds x_i.

Both meshes are distributed over the same communicator with unrelated partitions, so every rank
evaluates the old field at all new nodes that lie in its own cells and the values are summed over
the ranks. A new node outside the old mesh (at a curved die wall, whose element edges differ from
mesh to mesh) takes the old field extended from the old cell nearest to it (points.py).
"""
from __future__ import annotations

import dolfinx.fem
import numpy as np

from forming_fenicsx.mesh.points import PointValues


def transfer(source: dolfinx.fem.Function, target: dolfinx.fem.Function) -> int:
    """target <- source at target's nodes (collective; both vector Lagrange functions on meshes of
    one communicator). Returns how many nodes lay outside the source mesh (their values extended
    from the nearest cell)."""
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

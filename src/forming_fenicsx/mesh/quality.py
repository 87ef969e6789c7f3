"""Folded cells: a 2D cell whose corners do not all turn the same way round it (a quadrilateral that
is not convex, or a cell of zero area). Its map from the reference cell is not invertible
everywhere, so the finite-element solution on it, and any point evaluation in it, is not to be
trusted. (Which way round a cell turns is the numbering's, and varies from cell to cell.)"""
from __future__ import annotations

import numpy as np
from mpi4py import MPI

from forming_fenicsx.core.compat import cell_geometry_nodes

# the corners in order round a cell among its geometry nodes (dolfinx's numbering)
CORNERS = {3: [0, 1, 2], 6: [0, 1, 2], 4: [0, 1, 3, 2], 9: [0, 1, 3, 2]}


def folded_cells(mesh) -> int:
    """How many of the 2D mesh's owned cells are folded, summed over the ranks (collective): the
    cross products of consecutive edges round a cell must all have one sign."""
    nodes = cell_geometry_nodes(mesh)
    owned = mesh.topology.index_map(mesh.topology.dim).size_local
    corners = mesh.geometry.x[nodes[:owned][:, CORNERS[nodes.shape[1]]], :2]
    edges = np.roll(corners, -1, axis=1) - corners
    following = np.roll(edges, -1, axis=1)
    turns = edges[:, :, 0] * following[:, :, 1] - edges[:, :, 1] * following[:, :, 0]
    one_way = np.all(turns > 0, axis=1) | np.all(turns < 0, axis=1)
    return int(mesh.comm.allreduce(int(np.count_nonzero(~one_way)), op=MPI.SUM))

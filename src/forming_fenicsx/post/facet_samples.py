"""Finite-element functions sampled on boundary facets of a 3D mesh, gathered on rank 0: the die
faces, the symmetry planes and the exit section that a 3D run's tables and figures show.

Each facet gets a grid of (n + 1)^2 points of its reference square pushed forward through its
cell's coordinate map, so the points lie on a curved facet too (the quarter circle of a round
bar), and with n the geometry degree they are the facet's nodes (Q2: its nine). The functions are
evaluated in the facet's own cell, which needs no search for the cell that holds a point.
"""
from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import basix
import dolfinx.fem
import numpy as np

from forming_fenicsx.core.compat import cell_geometry_nodes


def coincident(points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Points (N, d) that coincide (to 1e-9 of the extent) merged: the index of each distinct
    point's first occurrence and, for every point, the index of the distinct point it is."""
    scale = max(np.ptp(points, axis=0).max(), 1e-300)
    keys = np.round(points / scale * 1e9).astype(np.int64)
    _, first, index = np.unique(keys, axis=0, return_index=True, return_inverse=True)
    return first, index.reshape(-1)


@dataclass(frozen=True)
class FacetSamples:
    """Values of functions on a grid in each of F facets: ``points`` (F, m, 3), ``values``
    (F, m, width), m = (n + 1)^2 points in rows of n + 1 (``per_edge`` = n)."""

    points: np.ndarray
    values: np.ndarray
    per_edge: int

    @property
    def triangles(self) -> np.ndarray:
        """Two triangles per square of a facet's grid, (2 n^2, 3) indices into its points."""
        n = self.per_edge
        corner = np.array([i * (n + 1) + j for i in range(n) for j in range(n)])
        return np.vstack([np.column_stack([corner, corner + 1, corner + n + 2]),
                          np.column_stack([corner, corner + n + 2, corner + n + 1])])

    @property
    def ring(self) -> np.ndarray:
        """The grid's boundary points in order around a facet (4 n indices)."""
        n = self.per_edge
        return np.array([*range(n), *range(n, (n + 1) ** 2 - 1, n + 1),
                         *range((n + 1) ** 2 - 1, n * (n + 1), -1),
                         *range(n * (n + 1), 0, -(n + 1))])

    @property
    def corners(self) -> np.ndarray:
        """The four corners of every facet in order around it, (F, 4, 3)."""
        n = self.per_edge
        return self.points[:, [0, n, (n + 1) ** 2 - 1, n * (n + 1)]]

    @property
    def normals(self) -> np.ndarray:
        """A unit normal of every facet (the cross product of its diagonals; either side)."""
        c = self.corners
        normal = np.cross(c[:, 2] - c[:, 0], c[:, 3] - c[:, 1])
        return normal / np.linalg.norm(normal, axis=1, keepdims=True)

    def subset(self, chosen: np.ndarray) -> FacetSamples:
        """The samples of the facets ``chosen`` (a mask or indices)."""
        return FacetSamples(self.points[chosen], self.values[chosen], self.per_edge)

    def merged(self, project: Callable[[np.ndarray], np.ndarray]
               ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """One triangulation of all facets in a plane, ``project`` taking points (N, 3) to it
        (N, 2): (points (P, 2), triangles (T, 3), values (P, width)), a point shared by facets
        taken once."""
        flat = project(self.points.reshape(-1, 3))
        first, index = coincident(flat)
        m = self.points.shape[1]
        local = self.triangles[None, :, :] + m * np.arange(len(self.points))[:, None, None]
        return (flat[first], index[local.reshape(-1, 3)],
                self.values.reshape(len(flat), -1)[first])

    def outline(self, crease: float = 0.01) -> np.ndarray:
        """The edges (E, 2, 3) of the facets' grid squares along the boundary of the facets
        together (an edge of one facet only) or along a crease (two facets whose normals' x parts
        differ by more than ``crease``: the die's cone meeting its land)."""
        ring = self.ring
        ends = np.stack([self.points[:, ring], self.points[:, np.roll(ring, -1)]], axis=2)
        flat = ends.reshape(-1, 2, 3)
        _, index = coincident(flat.reshape(-1, 3))
        pairs = np.sort(index.reshape(-1, 2), axis=1)
        _, edge, counts = np.unique(pairs, axis=0, return_inverse=True, return_counts=True)
        edge = edge.reshape(-1)
        slope = np.repeat(np.abs(self.normals[:, 0]), len(ring))  # of each edge's facet
        low, high = np.full(len(counts), np.inf), np.zeros(len(counts))
        np.minimum.at(low, edge, slope)
        np.maximum.at(high, edge, slope)
        keep = (counts[edge] == 1) | (high[edge] - low[edge] > crease)
        _, once = np.unique(edge[keep], return_index=True)
        return flat[keep][once]


def reference_grid(facet: int, per_edge: int) -> np.ndarray:
    """The (n + 1)^2 points of a grid on the reference hexahedron's facet ``facet``, rows along
    its first edge (basix's numbering)."""
    vertices = basix.geometry(basix.CellType.hexahedron)[
        basix.topology(basix.CellType.hexahedron)[2][facet]]
    s = np.linspace(0.0, 1.0, per_edge + 1)
    t, s = np.meshgrid(s, s, indexing="ij")
    return (vertices[0] + s.reshape(-1, 1) * (vertices[1] - vertices[0])
            + t.reshape(-1, 1) * (vertices[2] - vertices[0]))


def sample_facets(functions: Sequence[dolfinx.fem.Function], facets: np.ndarray,
                  per_edge: int) -> FacetSamples | None:
    """The functions (side by side, each flattened to its value size) on a grid of ``per_edge``
    squares a side in each of the local ``facets`` (boundary facets of a hexahedral mesh) that
    this rank owns; gathered on rank 0 (None elsewhere; collective)."""
    mesh = functions[0].function_space.mesh
    tdim = mesh.topology.dim
    mesh.topology.create_connectivity(tdim - 1, tdim)
    mesh.topology.create_connectivity(tdim, tdim - 1)
    facet_cell, cell_facet = (mesh.topology.connectivity(tdim - 1, tdim),
                              mesh.topology.connectivity(tdim, tdim - 1))
    owned = np.asarray(facets)[np.asarray(facets) < mesh.topology.index_map(tdim - 1).size_local]
    nodes = cell_geometry_nodes(mesh)
    grids = [reference_grid(f, per_edge) for f in range(6)]
    width = sum(int(np.prod(f.ufl_shape)) for f in functions)
    m = (per_edge + 1) ** 2
    points, values = np.zeros((len(owned), m, 3)), np.zeros((len(owned), m, width))
    for i, facet in enumerate(owned):
        cell = facet_cell.links(facet)[0]
        local = int(np.flatnonzero(cell_facet.links(cell) == facet)[0])
        points[i] = mesh.geometry.cmap.push_forward(grids[local], mesh.geometry.x[nodes[cell]])
        cells = np.full(m, cell, dtype=np.int32)
        values[i] = np.hstack([f.eval(points[i], cells).reshape(m, -1) for f in functions])
    parts = mesh.comm.gather((points, values), root=0)
    if mesh.comm.rank != 0:
        return None
    return FacetSamples(np.concatenate([p for p, _ in parts]),
                        np.concatenate([v for _, v in parts]), per_edge)

"""Finite-element functions at arbitrary points of the workpiece, on any number of ranks.

Every rank evaluates the points that lie in its cells (owned or ghost); the ranks' values are
gathered and summed in rank order, so every rank holds the same array to the last bit (a point on a
partition boundary lies in cells of several ranks, whose values agree: they are averaged). A point
in no cell (past a curved wall whose element edges differ from mesh to mesh, or a streamline's step
beyond the wall it follows) takes the cell nearest to it, on the rank whose cell is the nearest:
its polynomial extended beyond the cell (``outside="extend"``), or the point moved onto that
cell's boundary (``outside="onto_cell"``: the nearest point of the polygon through its boundary
nodes, the cell's edges where they are straight). A quadrilateral's map to its reference cell is
not affine and may not be inverted far outside it (dolfinx 0.5's pull-back stops: "Newton method
failed to converge for non-affine geometry"); such a point is moved onto the cell as for
"onto_cell", and where even that fails (a distorted cell) it takes the cell's nearest node (a
swelling extrudate's streamline, traced above the last mesh's surface, met both).
"""
from __future__ import annotations

from typing import Sequence

import dolfinx.fem
import dolfinx.geometry
import numpy as np

from forming_fenicsx.core.compat import (bounding_box_tree, cell_geometry_nodes, closest_cells,
                                         colliding_cells)

OUTSIDE = ("nan", "extend", "onto_cell")
# a quadrilateral's boundary nodes in order around it (dolfinx's numbering: the vertices (0, 0),
# (1, 0), (0, 1), (1, 1), then Q2's midpoints of the edges 0-1, 0-2, 1-3, 2-3)
OUTLINE = {4: [0, 1, 3, 2], 9: [0, 4, 1, 6, 3, 7, 2, 5]}


class PointValues:
    """Functions of one mesh at points (collective): ``values, where = evaluate(points)``, the
    values side by side (N, total components) and where they were taken (the points, moved onto
    the nearest cell for ``outside="onto_cell"``); ``missed``: how many of the last points lay in
    no cell. The trees are built once."""

    def __init__(self, functions: Sequence[dolfinx.fem.Function]):
        self._functions = list(functions)
        self.mesh = mesh = self._functions[0].function_space.mesh
        self._tree = bounding_box_tree(mesh)
        index_map = mesh.topology.index_map(mesh.topology.dim)
        cells = np.arange(index_map.size_local + index_map.num_ghosts, dtype=np.int32)
        self._midpoints = dolfinx.geometry.create_midpoint_tree(mesh, mesh.topology.dim, cells)
        self.width = sum(int(np.prod(f.ufl_shape)) for f in self._functions)
        self.missed = 0

    def evaluate(self, points: np.ndarray, outside: str = "nan") -> tuple[np.ndarray, np.ndarray]:
        """The functions at the points (N, 2), or (N, 3) in 3D, and where they were taken; a point
        in no rank's cell gets nan, or by ``outside`` the values of the nearest cell (OUTSIDE,
        module docstring; "nan" only in 3D)."""
        if outside not in OUTSIDE:
            raise ValueError(f"outside must be one of {OUTSIDE}; got {outside!r}")
        padded = np.zeros((len(points), 3))
        padded[:, :np.shape(points)[1]] = points
        cells = colliding_cells(self.mesh, padded, self._tree)
        found = cells >= 0
        local = np.zeros((len(points), self.width))
        if found.any():
            local[found] = self._values_near(padded[found], cells[found])[1]
        count = self._summed(found.astype(float))
        values = self._summed(local) / np.maximum(count, 1.0)[:, None]
        where = np.array(points, dtype=float)
        missed = np.flatnonzero(count == 0)  # the same on every rank
        self.missed = len(missed)
        if len(missed) and outside == "nan":
            values[missed] = np.nan
        elif len(missed):
            where[missed], values[missed] = self._nearest(padded[missed], outside == "onto_cell")
        return values, where

    def _nearest(self, points: np.ndarray, onto: bool) -> tuple[np.ndarray, np.ndarray]:
        """Where and what the nearest cell gives at points (N, 3) outside the mesh (collective)."""
        cells, distances = self._closest(points)
        mine = np.argmin(np.array(self.mesh.comm.allgather(distances)), axis=0) \
            == self.mesh.comm.rank
        where = np.zeros((len(points), 2))
        values = np.zeros((len(points), self.width))
        if mine.any():
            where[mine] = self._onto(points[mine, :2], cells[mine]) if onto else points[mine, :2]
            padded = np.zeros((int(mine.sum()), 3))
            padded[:, :2] = where[mine]
            where[mine], values[mine] = self._values_near(padded, cells[mine])
        return self._summed(where), self._summed(values)

    def _closest(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The local cell nearest to each point (N, 3) and the squared distance to it
        (compat.closest_cells). Where dolfinx's distance (GJK) stops at its iteration limit (a
        point within 1e-4 of a Q2 cell's nearly straight edge of a re-meshed free surface met it),
        the cell of the nearest node and the squared distance to that node."""
        try:
            return closest_cells(self.mesh, points, self._tree, self._midpoints)
        except RuntimeError:
            pass
        x = self.mesh.geometry.x
        nodes = cell_geometry_nodes(self.mesh)
        cells, distances = np.empty(len(points), dtype=np.int32), np.empty(len(points))
        for i, point in enumerate(points):
            try:
                found = closest_cells(self.mesh, point[None, :], self._tree, self._midpoints)
                cells[i], distances[i] = found[0][0], found[1][0]
            except RuntimeError:
                squared = np.sum((x - point) ** 2, axis=1)
                node = int(np.argmin(squared))
                cells[i] = int(np.flatnonzero((nodes == node).any(axis=1))[0])
                distances[i] = squared[node]
        return cells, distances

    def _values_near(self, points: np.ndarray, cells: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Where and what each cell gives at its point (N, 3): at the point where the cell's map
        can be inverted there, else at the point moved onto the cell's outline (_onto; module
        docstring). One batch, or one point at a time once the batch has failed."""
        try:
            return points[:, :2].copy(), self._values(points, cells)
        except RuntimeError:  # a pull-back beyond a non-affine cell
            pass
        where, values = points[:, :2].copy(), np.zeros((len(points), self.width))
        for i in range(len(points)):
            try:
                values[i] = self._values(points[i:i + 1], cells[i:i + 1])[0]
            except RuntimeError:
                where[i] = self._onto(points[i:i + 1, :2], cells[i:i + 1])[0]
                moved = np.zeros((1, 3))
                moved[0, :2] = where[i]
                try:
                    values[i] = self._values(moved, cells[i:i + 1])[0]
                except RuntimeError:  # a cell too distorted to invert even there: its nearest node
                    where[i], values[i] = self._at_node(where[i], int(cells[i]))
        return where, values

    def _at_node(self, point: np.ndarray, cell: int) -> tuple[np.ndarray, np.ndarray]:
        """The cell's degree of freedom nearest to the point (x, y): where it is and the functions'
        values there (their Lagrange coefficients)."""
        found = []
        for f in self._functions:
            space, size = f.function_space, f.function_space.dofmap.index_map_bs
            dofs = space.dofmap.cell_dofs(cell)
            coordinates = space.tabulate_dof_coordinates()[dofs, :2]
            nearest = int(np.argmin(np.sum((coordinates - point) ** 2, axis=1)))
            found.append(f.x.array[dofs[nearest] * size:(dofs[nearest] + 1) * size])
        return coordinates[nearest], np.concatenate(found)

    def _onto(self, points: np.ndarray, cells: np.ndarray) -> np.ndarray:
        """Each point (N, 2) moved to the nearest point of its cell's outline: on the segment a-b
        at a + t (b - a), t = (p - a).(b - a) / |b - a|^2 clipped to [0, 1], the nearest of all."""
        nodes = cell_geometry_nodes(self.mesh)
        outline = nodes[cells][:, OUTLINE[nodes.shape[1]]]
        moved = np.empty_like(points)
        for i, (point, corners) in enumerate(zip(points, self.mesh.geometry.x[outline, :2])):
            a, edge = corners, np.roll(corners, -1, axis=0) - corners
            t = np.clip(np.einsum("ij,ij->i", point - a, edge) / np.einsum("ij,ij->i", edge, edge),
                        0.0, 1.0)
            nearest = a + t[:, None] * edge
            moved[i] = nearest[np.argmin(np.einsum("ij,ij->i", nearest - point, nearest - point))]
        return moved

    def _values(self, points: np.ndarray, cells: np.ndarray) -> np.ndarray:
        return np.hstack([f.eval(points, cells).reshape(len(points), -1) for f in self._functions])

    def _summed(self, array: np.ndarray) -> np.ndarray:
        """The ranks' arrays summed in rank order (the same bits on every rank)."""
        return np.sum(self.mesh.comm.allgather(array), axis=0)

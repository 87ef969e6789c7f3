"""Lagrange functions at points that lie on vertical lines, in a quadrilateral mesh of columns: the
free surface's flux sections (post/free_surface.py), 37k points an update of Example 2.

The workpiece's blocks are meshed in columns: every cell has two vertical sides, so that its x
depends on one reference coordinate s only (xi or eta, whichever the cell's numbering puts along
x). A point (x, y) then lies in the cell whose x-range holds x and whose bottom y(s, 0) and top
y(s, 1) at that x hold y; s solves x(s) = x and the other coordinate t solves y(s, t) = y, each
by Newton's method in one variable from the straight cell's value (exact on a straight cell, where
they are linear). The cells are found by sorting, not by a bounding-box tree, and the values
follow from the space's basis at (s, t) (basix), for all points together: the same polynomial at
the same point as Function.eval (to rounding), without its point-by-point search and pull-back
(43 of the 47 ms an Example 2 update took, docs/free_surface.md).

A point above the mesh's top at its x takes, for ``outside="column"``, the polynomial of the top
cell at its x extended: the section continued upward (the flux sections' top samples, one a
station where the surface dips below the level's start; their nearest-cell search took 60 % of an
update, and the nearest cell may be a neighbour's where the top slopes). Any other point that no
column holds (a cell without vertical sides, a triangle, a point beside or below the mesh, or
above it for the other rules) is evaluated by PointValues (points.py), whose ``outside`` rule
then applies ("extend" for "column").
"""
from __future__ import annotations

import dolfinx.fem
import numpy as np

from forming_fenicsx.core.compat import basix_element, cell_dofs, cell_geometry_nodes
from forming_fenicsx.mesh.points import PointValues

# the relative tolerance of "vertical" (a side's x spread over the cell's width) and of a point's
# height within its cell's bottom and top (over the cell's height)
VERTICAL = 1e-9
NEWTON_STEPS = 8


class ColumnValues:
    """A Lagrange function of a quadrilateral mesh at points (N, 2): ``evaluate(points,
    outside)`` as PointValues.evaluate, the points on vertical lines found through the mesh's
    columns (module docstring); ``missed``: how many of the last points lay in no cell.
    Collective."""

    def __init__(self, function: dolfinx.fem.Function):
        self._function = function
        mesh = function.function_space.mesh
        self._comm = mesh.comm
        self._points: PointValues | None = None  # for the points no column holds: built then
        self.width = int(np.prod(function.ufl_shape))
        self.missed = 0
        owned = mesh.topology.index_map(mesh.topology.dim).size_local
        self._geometry = basix_element(mesh)
        self._element = basix_element(function.function_space)
        dofs = cell_dofs(function.function_space.dofmap)
        usable = (mesh.topology.cell_type.name == "quadrilateral" and self._geometry is not None
                  and self._element is not None and self._element.dim == dofs.shape[1])
        self._cells = np.zeros(0, dtype=np.int32)
        self._along = np.zeros(0, dtype=int)
        self._usable = usable  # the same on every rank
        if not usable:
            return
        self._dofs = dofs
        self._values = function.x.array.reshape(-1, function.function_space.dofmap.index_map_bs)
        nodes = cell_geometry_nodes(mesh)[:owned]
        self._nodes = mesh.geometry.x[nodes][:, :, :2]  # (cells, nodes, 2)
        reference = np.asarray(self._geometry.points)
        along = np.zeros(owned, dtype=int) - 1  # the reference coordinate along x, or -1
        width = np.ptp(self._nodes[:, :, 0], axis=1)
        for axis in (0, 1):
            spread = np.zeros(owned)
            for level in np.unique(reference[:, axis]):
                row = self._nodes[:, np.isclose(reference[:, axis], level), 0]
                spread = np.maximum(spread, row.max(axis=1) - row.min(axis=1))
            along[(along < 0) & (spread <= VERTICAL * width)] = axis
        self._cells = np.flatnonzero(along >= 0).astype(np.int32)
        self._along = along[self._cells]
        # the nodes on the (s, t) grid of the tensor-product map: grid[cell, a, b] at s = a / k,
        # t = b / k (k the map's degree; its Lagrange points are equispaced to degree 2)
        self._levels = np.unique(reference[:, 0])
        index = np.rint(reference * (len(self._levels) - 1)).astype(int)
        grid = np.zeros((len(self._cells), len(self._levels), len(self._levels), 2))
        for node, (i, j) in enumerate(index):
            straight = self._along == 0
            grid[straight, i, j] = self._nodes[self._cells[straight], node]
            grid[~straight, j, i] = self._nodes[self._cells[~straight], node]
        self._x = grid[:, :, 0, 0]  # x at the s levels (the same at every t)
        self._y = grid[:, :, :, 1]
        self._low, self._high = self._x.min(axis=1), self._x.max(axis=1)

    def evaluate(self, points: np.ndarray, outside: str = "nan") -> tuple[np.ndarray, np.ndarray]:
        """The function at the points (N, 2) and where it was taken (PointValues.evaluate);
        ``outside`` one of PointValues' rules, or "column": a point above the mesh's top takes
        the polynomial of the top cell at its x extended, any other point outside as "extend"."""
        local = np.zeros((len(points), self.width))
        count = np.zeros(len(points))
        if self._usable:  # on every rank: "column" is collective
            hit, cells, reference = self._locate(np.asarray(points, dtype=float),
                                                 outside == "column")
            if len(hit):
                basis = self._element.tabulate(0, reference)[0, :, :, 0]
                local[hit] = np.einsum("pn,pnb->pb", basis, self._values[self._dofs[cells]])
                count[hit] = 1.0
        count = np.sum(self._comm.allgather(count), axis=0)
        values = np.sum(self._comm.allgather(local), axis=0) / np.maximum(count, 1.0)[:, None]
        where = np.array(points, dtype=float)
        missed = np.flatnonzero(count == 0)  # the same on every rank
        self.missed = 0
        if len(missed):
            if self._points is None:
                self._points = PointValues([self._function])
            rule = "extend" if outside == "column" else outside
            values[missed], where[missed] = self._points.evaluate(where[missed], rule)
            self.missed = self._points.missed
        return values, where

    def _locate(self, points: np.ndarray, extend: bool
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The points held by this rank's column cells: their indices, cells and reference
        coordinates (xi, eta); with ``extend``, also the points above the mesh's top at their x,
        in the top cell there (collective then)."""
        stations, station_of = np.unique(points[:, 0], return_inverse=True)
        first = np.searchsorted(stations, self._low, "left")
        last = np.searchsorted(stations, self._high, "right")
        spans = last - first
        pair_cell = np.repeat(np.arange(len(self._cells)), spans)  # index into self._cells
        pair_station = np.repeat(first, spans) + _ranges(spans)
        s = self._invert(pair_cell, stations[pair_station])
        # y at the t levels along the line x = const through each cell: its bottom and top first
        # and last (the Lagrange levels include t = 0 and 1)
        column = np.einsum("pab,pa->pb", self._y[pair_cell], _basis(s, self._levels)[0])
        bottom, top = column[:, 0], column[:, -1]
        low, high = np.minimum(bottom, top), np.maximum(bottom, top)
        # the pairs by station, then upward; a point's cell is the last pair of its station below
        # it (a key that orders stations first: heights span less than `span`)
        heights = self._nodes[:, :, 1]
        base = heights.min(initial=0.0)
        span = 2.0 * (heights.max(initial=0.0) - base + 1.0)
        order = np.lexsort((low, pair_station))
        keys = pair_station[order] * span + (low[order] - base)
        wanted = station_of * span + (points[:, 1] - base)
        index = np.searchsorted(keys, wanted, "right") - 1
        if not len(order):  # no cell of this rank spans a point's x
            order, index = np.zeros(1, dtype=int), np.full(len(points), -1)
            pair_station, low, high = np.full(1, -1), np.zeros(1), np.zeros(1)
        candidate = order[np.clip(index, 0, None)]
        tolerance = VERTICAL * (high - low)[candidate]
        held = ((index >= 0) & (pair_station[candidate] == station_of)
                & (points[:, 1] <= high[candidate] + tolerance)
                & (points[:, 1] >= low[candidate] - tolerance))
        if extend:
            held |= self._above(points, stations, station_of, pair_station, high, candidate,
                                index)
        hit = np.flatnonzero(held)
        pair = candidate[hit]
        t = _newton(column[pair], (points[hit, 1] - bottom[pair]) / (top[pair] - bottom[pair]),
                    points[hit, 1], self._levels)
        along = self._along[pair_cell[pair]]
        reference = np.where(along[:, None] == 0, np.column_stack([s[pair], t]),
                             np.column_stack([t, s[pair]]))
        return hit, self._cells[pair_cell[pair]], reference

    def _above(self, points: np.ndarray, stations: np.ndarray, station_of: np.ndarray,
               pair_station: np.ndarray, high: np.ndarray, candidate: np.ndarray,
               index: np.ndarray) -> np.ndarray:
        """Which points lie above the mesh's top at their x where this rank holds the top cell
        (the highest of the column cells there on any rank, no other cell spanning that x).
        Collective."""
        top = np.full(len(stations), -np.inf)
        spanning = pair_station >= 0  # none where no cell of this rank spans a point's x
        np.maximum.at(top, pair_station[spanning], high[spanning])
        top = np.max(self._comm.allgather(top), axis=0)
        others = np.setdiff1d(np.arange(len(self._nodes)), self._cells)
        blocked = np.zeros(len(stations), dtype=int)
        if len(others):
            x = self._nodes[others, :, 0]
            first = np.searchsorted(stations, x.min(axis=1), "left")
            last = np.searchsorted(stations, x.max(axis=1), "right")
            for a, b in zip(first, last):
                blocked[a:b] = 1
        blocked = np.max(self._comm.allgather(blocked), axis=0)
        station = pair_station[candidate]
        return ((index >= 0) & (station == station_of) & (high[candidate] == top[station_of])
                & (blocked[station_of] == 0) & (points[:, 1] > top[station_of]))

    def _invert(self, pair_cell: np.ndarray, x: np.ndarray) -> np.ndarray:
        """s with x(s) = x in each cell (x does not depend on t)."""
        nodes = self._x[pair_cell]
        low, high = self._low[pair_cell], self._high[pair_cell]
        s = (x - low) / (high - low)
        s = np.where(nodes[:, 0] <= nodes[:, -1], s, 1.0 - s)  # x may fall along s
        return _newton(nodes, s, x, self._levels)


def _basis(s: np.ndarray, levels: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The 1D Lagrange basis on the nodes ``levels`` at the points s (N,), and its derivative:
    two (N, nodes) arrays."""
    values = np.ones((len(s), len(levels)))
    slopes = np.zeros((len(s), len(levels)))
    for a, node in enumerate(levels):
        for b, other in enumerate(levels):
            if b == a:
                continue
            factor = (s - other) / (node - other)
            slopes[:, a] = slopes[:, a] * factor + values[:, a] / (node - other)
            values[:, a] *= factor
    return values, slopes


def _interpolate(nodes: np.ndarray, s: np.ndarray, levels: np.ndarray
                 ) -> tuple[np.ndarray, np.ndarray]:
    """sum_a l_a(s) nodes[:, a] and its derivative in s."""
    values, slopes = _basis(s, levels)
    return np.einsum("pa,pa->p", values, nodes), np.einsum("pa,pa->p", slopes, nodes)


def _newton(nodes: np.ndarray, guess: np.ndarray, target: np.ndarray, levels: np.ndarray
            ) -> np.ndarray:
    """Newton's method for sum_a l_a(v) nodes[:, a] = target, each point on its own until its step
    is below 1e-14 (a straight cell's guess is its root: most points stop at once); the guess
    itself on two ``levels`` (a linear map)."""
    if len(levels) == 2:
        return guess
    value = np.array(guess, dtype=float)
    going = np.arange(len(value))
    for _ in range(NEWTON_STEPS):
        result, slope = _interpolate(nodes[going], value[going], levels)
        step = (target[going] - result) / slope
        value[going] += step
        going = going[np.abs(step) >= 1e-14]
        if not len(going):
            break
    return value


def _ranges(counts: np.ndarray) -> np.ndarray:
    """0, 1, ..., count - 1 for each count, concatenated."""
    total = int(counts.sum())
    starts = np.repeat(np.cumsum(counts) - counts, counts)
    return np.arange(total) - starts

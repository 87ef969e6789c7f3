"""Functions at points on vertical lines through a mesh of columns (mesh/columns.py) against
PointValues (dolfinx's search and pull-back): the same values and the same points, inside the
cells, on their edges and beyond the mesh, for cells numbered along x and along y, a die's
rounded entry whose Q2 cells are not all columns, and a triangle mesh that has none."""
from __future__ import annotations

from pathlib import Path

import dolfinx.fem
import dolfinx.mesh
import numpy as np
import pytest
from mpi4py import MPI

from forming_fenicsx.config.loader import load_scene
from forming_fenicsx.core.compat import colliding_cells, function_space
from forming_fenicsx.mesh.columns import ColumnValues
from forming_fenicsx.mesh.geometry import build_mesh
from forming_fenicsx.mesh.points import PointValues

EXAMPLE2 = Path(__file__).resolve().parents[1] / "demos" / "example2_drawing.toml"


def _section_points(mesh: dolfinx.mesh.Mesh, stations: int = 23, heights: int = 31
                    ) -> np.ndarray:
    """Points on vertical lines across the mesh's x-range and beyond its y-range (as the free
    surface's sections are, and its nodes' columns: every third station is a node column)."""
    x = mesh.geometry.x[:, :2]
    low = np.min(mesh.comm.allgather(x.min(axis=0)), axis=0)
    high = np.max(mesh.comm.allgather(x.max(axis=0)), axis=0)
    nodes = np.unique(np.round(np.concatenate(mesh.comm.allgather(x[:, 0])), 12))
    xs = np.union1d(np.linspace(low[0] + 1e-3, high[0] - 1e-3, stations), nodes[::3])
    ys = np.linspace(low[1] - 0.1, high[1] + 0.2, heights)
    return np.array([[a, b] for a in xs for b in ys])


def _random_function(mesh: dolfinx.mesh.Mesh, degree: int, shape: tuple[int, ...]
                     ) -> dolfinx.fem.Function:
    f = dolfinx.fem.Function(function_space(mesh, "P", degree, shape))
    f.interpolate(lambda p: np.vstack([np.sin(3 * p[0] + k) * np.cos(2 * p[1] - k) + p[0] * p[1]
                                       for k in range(int(np.prod(shape)))]))
    return f


def _compare(f: dolfinx.fem.Function, points: np.ndarray) -> set[int]:
    """ColumnValues against PointValues at the points; returns the reference coordinates the
    cells' x follows (0: xi, 1: eta; none for a mesh without columns)."""
    columns = ColumnValues(f)
    for outside in ("nan", "extend"):
        found, where = columns.evaluate(points, outside)
        reference, reference_where = PointValues([f]).evaluate(points, outside)
        assert np.array_equal(np.isnan(found), np.isnan(reference))
        inside = ~np.isnan(reference[:, 0])
        assert inside.sum() > 0.5 * len(points)
        # dolfinx's pull-back stops at steps below 1e-8 in the reference cell: its values beyond
        # a curved cell, where Newton's method converges slower, differ by 1.3e-12 of the largest
        scale = np.max(np.abs(reference[inside]))
        assert np.max(np.abs(found[inside] - reference[inside])) < 1e-10 * scale
        assert np.array_equal(where, reference_where)
    if MPI.COMM_WORLD.allreduce(len(columns._cells)):
        _check_above(f, points, columns)
    return set(np.concatenate(MPI.COMM_WORLD.allgather(columns._along)).tolist())


def _check_above(f: dolfinx.fem.Function, points: np.ndarray, columns: ColumnValues) -> None:
    """outside="column": a point above the mesh whose top cell at its x is a column's takes that
    cell's polynomial extended (dolfinx's eval in that cell, which pulls the point back outside
    it); any other point the value "extend" gives."""
    found = columns.evaluate(points, "column")[0]
    extended = columns.evaluate(points, "extend")[0]
    mesh, comm = f.function_space.mesh, f.function_space.mesh.comm
    search = PointValues([f])
    top_of = {}
    for x in np.unique(points[:, 0]):  # the top at x: bisection on "in a cell", from inside
        low, high = 0.0, 3.0
        for _ in range(60):
            middle = 0.5 * (low + high)
            inside = not np.isnan(search.evaluate(np.array([[x, middle]]))[0][0, 0])
            low, high = (middle, high) if inside else (low, middle)
        top_of[x] = low
    tops = np.array([top_of[x] for x in points[:, 0]])
    under = np.column_stack([points[:, 0], tops - 1e-10, np.zeros(len(points))])
    cells = colliding_cells(mesh, under)
    column = np.max(comm.allgather(np.isin(cells, columns._cells)), axis=0)
    above = (points[:, 1] > tops + 1e-9) & column
    assert above.sum() > 10
    scale = 1 + np.max(np.abs(extended))
    assert np.max(np.abs(found[~above] - extended[~above])) < 1e-12 * scale
    reference = np.zeros((len(points), found.shape[1]))
    mine = above & (cells >= 0)
    for i in np.flatnonzero(mine):
        here = np.array([[points[i, 0], points[i, 1], 0.0]])
        reference[i] = f.eval(here, cells[i:i + 1]).ravel()
    count = comm.allreduce(mine.astype(float))
    reference = np.sum(comm.allgather(reference), axis=0)[above] / count[above, None]
    assert np.max(np.abs(found[above] - reference)) < 1e-10 * scale


def _columned_square(cell: dolfinx.mesh.CellType, swap: bool) -> dolfinx.mesh.Mesh:
    """The unit square's cells moved so that their sides along the square's y stay vertical: x a
    function of x alone, y of both; ``swap``: the square's y made the new x (and x the new y),
    so that the cells' x follows their second reference coordinate."""
    mesh = dolfinx.mesh.create_unit_square(MPI.COMM_WORLD, 5, 4, cell)
    x = mesh.geometry.x
    a, b = (x[:, 1].copy(), x[:, 0].copy()) if swap else (x[:, 0].copy(), x[:, 1].copy())
    x[:, 0] = a + 0.08 * np.sin(np.pi * a)
    x[:, 1] = b * (1 + 0.4 * a) + 0.05 * np.sin(2 * np.pi * a) * b * (1 - b)
    return mesh


@pytest.mark.parametrize("degree, shape", [(1, ()), (2, (2,))])
def test_columns_agree_with_point_search(degree: int, shape: tuple[int, ...]):
    """Both numberings: the square's cells' x follows one reference coordinate, and the other
    once x and y are exchanged."""
    kinds = []
    for swap in (False, True):
        mesh = _columned_square(dolfinx.mesh.CellType.quadrilateral, swap)
        kinds.append(_compare(_random_function(mesh, degree, shape), _section_points(mesh)))
    assert sorted(kinds, key=sorted) == [{0}, {1}]


def test_triangles_take_the_point_search():
    mesh = _columned_square(dolfinx.mesh.CellType.triangle, swap=False)
    assert _compare(_random_function(mesh, 2, (2,)), _section_points(mesh)) == set()


def test_a_die_with_a_rounded_entry():
    """Example 2's workpiece meshed by gmsh with 9-node cells, its die entry rounded (radius 1):
    the cells under the arc whose curved top puts its middle node off the column's middle are not
    columns, and their points take the point search."""
    scene = load_scene(EXAMPLE2, ["discretisation.element=Q2", "discretisation.mesh_size=0.1",
                                  "discretisation.formulation=mixed", "geometry.entry_radius=1.0"])
    mesh = build_mesh(scene, MPI.COMM_WORLD).mesh
    f = _random_function(mesh, 2, (2,))
    assert len(_compare(f, _section_points(mesh, stations=61))) == 1
    cells = mesh.topology.index_map(2).size_local
    held = len(ColumnValues(f)._cells)
    assert 0 < MPI.COMM_WORLD.allreduce(cells - held) < 0.1 * MPI.COMM_WORLD.allreduce(cells)

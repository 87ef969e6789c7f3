"""Gmsh half models: boundary roles, dimensions, grading toward the die corner, .msh output."""
import os

import dolfinx.fem
import gmsh
import numpy as np
import pytest
import ufl
from mpi4py import MPI

from forming_fenicsx.core.compat import cell_geometry_nodes, original_cell_index
from forming_fenicsx.mesh.geometry import build_mesh, write_msh
from forming_fenicsx.mesh.grading import graded_edge
from forming_fenicsx.core.roles import ROLES
from forming_fenicsx.verification.verification import sector_mesh

from conftest import make_scene


def integrate(mesh, integrand) -> float:
    return mesh.comm.allreduce(dolfinx.fem.assemble_scalar(dolfinx.fem.form(integrand)))


@pytest.mark.parametrize("element", ["Q1", "Q2"])
def test_extrusion_roles_and_measures(element):
    scene = make_scene(geometry={"length": 16.0, "entry_thickness": 8.0, "exit_thickness": 3.0,
                                 "die_position": 6.0},
                       discretisation={"element": element, "mesh_size": 0.5})
    fm = build_mesh(scene)
    mesh = fm.mesh
    assert mesh.geometry.cmap.degree == int(element[1])
    assert set(fm.roles) == {"gamma1_velocity", "gamma3_contact", "gamma4_free", "gamma6_symmetry"}
    one = dolfinx.fem.Constant(mesh, 1.0)
    ds = ufl.Measure("ds", domain=mesh, subdomain_data=fm.facet_tags)
    assert integrate(mesh, one * ufl.dx) == pytest.approx(6 * 4 + 10 * 1.5, rel=1e-12)
    lengths = {"gamma1_velocity": 4.0, "gamma3_contact": 6.0 + 2.5, "gamma4_free": 10.0 + 1.5,
               "gamma6_symmetry": 16.0}
    for role, length in lengths.items():
        assert integrate(mesh, one * ds(ROLES[role])) == pytest.approx(length, rel=1e-12)
    # every facet has a role
    assert integrate(mesh, one * ufl.ds) == pytest.approx(sum(lengths.values()), rel=1e-12)


@pytest.mark.parametrize("builder", ["build_mesh", "sector_mesh"])
def test_interior_facets_counted_once_on_every_rank(builder):
    """The interior facets' total length (an interior-facet integral, as in the upwind-DG strain
    transport) on the package's gmsh meshes distributed over all ranks is the serial mesh's: the
    facets between ranks are counted once (compat.GHOST_MODE; without those ghosts dolfinx 0.5
    leaves them out and 0.9 stops)."""
    def length(comm: MPI.Comm) -> float:
        if builder == "sector_mesh":
            mesh = sector_mesh(6, 2, comm).mesh
        else:
            mesh = build_mesh(make_scene(discretisation={"mesh_size": 0.5}), comm).mesh
        return integrate(mesh, dolfinx.fem.Constant(mesh, 1.0) * ufl.dS)

    assert length(MPI.COMM_WORLD) == pytest.approx(length(MPI.COMM_SELF), rel=1e-12)


def role_lengths(fm) -> dict[str, float]:
    ds = ufl.Measure("ds", domain=fm.mesh, subdomain_data=fm.facet_tags)
    one = dolfinx.fem.Constant(fm.mesh, 1.0)
    return {role: integrate(fm.mesh, one * ds(tag)) for role, tag in fm.roles.items()}


def test_applied_force_makes_the_exit_face_gamma5():
    lengths = role_lengths(build_mesh(make_scene(process={"applied_force": 0.5},
                                                 discretisation={"mesh_size": 1.0})))
    assert lengths["gamma5_force"] == pytest.approx(2.5, rel=1e-12)
    assert lengths["gamma4_free"] == pytest.approx(10.0, rel=1e-12)


@pytest.mark.parametrize("land", [0.0, 0.15])
@pytest.mark.parametrize("drive", ["pull", "push"])
def test_drawing_roles_and_measures(land, drive):
    scene = make_scene(process={"kind": "drawing", "drive": drive, "applied_force": 10.0},
                       geometry={"land_length": land}, discretisation={"mesh_size": 0.1})
    fm = build_mesh(scene)
    g = scene.geometry
    h0, h1 = g.entry_thickness / 2, g.exit_thickness / 2
    slant = (h0 - h1) / np.sin(np.radians(g.die_angle))
    lengths = role_lengths(fm)
    assert lengths["gamma3_contact"] == pytest.approx(slant + land, rel=1e-12)
    assert lengths["gamma1_velocity"] == pytest.approx(h1 if drive == "pull" else h0, rel=1e-12)
    assert lengths["gamma5_force"] == pytest.approx(h0 if drive == "pull" else h1, rel=1e-12)
    assert lengths["gamma2_free"] == pytest.approx(g.die_entry, rel=1e-12)
    assert lengths["gamma4_free"] == pytest.approx(g.length - g.die_exit, rel=1e-12)
    area = integrate(fm.mesh, dolfinx.fem.Constant(fm.mesh, 1.0) * ufl.dx)
    assert area == pytest.approx(g.die_entry * h0 + g.cone_length * (h0 + h1) / 2
                                 + (g.length - g.die_entry - g.cone_length) * h1, rel=1e-12)


def test_graded_edge_ratio():
    elements, progression = graded_edge(10.0, 1.0, 8.0, toward_end=True)
    sizes = progression ** np.arange(elements)
    assert elements == 10
    assert sizes[0] / sizes[-1] == pytest.approx(8.0, rel=1e-12)
    assert graded_edge(10.0, 1.0, 1.0, toward_end=True) == (10, 1.0)


def test_a_graded_edge_of_few_elements_is_capped():
    """Three elements graded by 64: neighbours differ by MAX_RATIO = 3 (not 8), the whole edge by 9;
    away from the end the same (progression 3); ten elements get the full 64."""
    assert graded_edge(3.0, 1.0, 64.0, toward_end=True) == pytest.approx((3, 1 / 3), rel=1e-15)
    assert graded_edge(3.0, 1.0, 64.0, toward_end=False) == pytest.approx((3, 3.0), rel=1e-15)
    elements, progression = graded_edge(10.0, 1.0, 64.0, toward_end=False)
    assert progression ** (elements - 1) == pytest.approx(64.0, rel=1e-12)


def nearest_cell_box(fm, point) -> np.ndarray:
    """The bounding box's extent along each axis of the owned cell (of any dimension) whose
    vertices' mean is nearest to ``point``, over all ranks."""
    mesh = fm.mesh
    dim = mesh.topology.dim
    owned = mesh.topology.index_map(dim).size_local
    corners = mesh.geometry.x[cell_geometry_nodes(mesh)[:owned, :2**dim]][:, :, :dim]
    found = (np.inf, None)
    if owned:
        distance = np.linalg.norm(corners.mean(axis=1) - point, axis=1)
        nearest = distance.argmin()
        found = (distance[nearest], np.ptp(corners[nearest], axis=0))
    return min(mesh.comm.allgather(found), key=lambda each: each[0])[1]


def smallest_cell_near(fm, point) -> float:
    """Bounding-box diagonal of the owned cell nearest to ``point`` (over all ranks)."""
    return float(np.linalg.norm(nearest_cell_box(fm, point)))


def test_corner_grading_refines_toward_die_corner():
    sizes = [smallest_cell_near(build_mesh(make_scene(discretisation={"mesh_size": 0.5,
                                                                      "corner_grading": g})),
                                np.array([10.0, 2.5])) for g in (1.0, 8.0)]
    assert sizes[0] == pytest.approx(0.5 * 2**0.5, rel=1e-9)
    assert sizes[1] < sizes[0] / 3


def _drawing(wall: float, symmetry: str = "plane_strain", size: float = 0.1):
    """Example 2's strip (or a wire, a quarter bar) meshed with corner_grading 1 and the given
    wall_grading."""
    geometry = {"symmetry": symmetry}
    if symmetry == "3d":
        geometry.update({"section": "rectangle", "entry_height": 2.0, "exit_height": 1.7,
                         "entry_width": 3.0, "exit_width": 2.6, "die_angle": 8.0,
                         "land_length": 0.3})
    return build_mesh(make_scene(process={"kind": "drawing"}, geometry=geometry,
                                 discretisation={"mesh_size": size, "corner_grading": 1.0,
                                                 "wall_grading": wall}))


def test_wall_grading_refines_toward_the_die_wall_and_its_corners():
    """Example 2's die (a 6 degree cone from x = 3, a land from x = 4.34 to 4.49 at y = 0.672),
    cells compared by their diagonals: with wall_grading 1 as large at the wall over the cone's
    middle as at the axis under it (0.112); with 16 the cell at the die entry corner is a fifth of
    the uniform one (0.029 against 0.135) and the thickness is graded: at the axis under the cone's
    middle the cell is three times the one at the wall above it (0.242 against 0.076)."""
    uniform, graded = _drawing(1.0), _drawing(16.0)
    entry, wall, axis = np.array([3.0, 0.8125]), np.array([3.67, 0.743]), np.array([3.67, 0.0])
    assert smallest_cell_near(uniform, wall) == pytest.approx(smallest_cell_near(uniform, axis),
                                                              rel=1e-6)
    assert smallest_cell_near(graded, entry) < smallest_cell_near(uniform, entry) / 4
    assert smallest_cell_near(graded, wall) < smallest_cell_near(uniform, wall)
    assert smallest_cell_near(graded, axis) > 3 * smallest_cell_near(graded, wall)


def test_wall_grading_in_3d_refines_toward_the_die_faces():
    """A quarter rectangular bar: with wall_grading 16 the hexahedra along the edge where the two
    die faces meet are smaller than at the axis (uniform: alike), the volume the same."""
    def extents(fm, point) -> float:
        return float(np.prod(nearest_cell_box(fm, point)))

    volumes = []
    for wall in (1.0, 16.0):
        fm = _drawing(wall, "3d", 0.25)
        edge, axis = np.array([2.0, 0.9, 1.4]), np.array([2.0, 0.0, 0.0])
        volumes.append(integrate(fm.mesh, dolfinx.fem.Constant(fm.mesh, 1.0) * ufl.dx))
        ratio = extents(fm, axis) / extents(fm, edge)
        assert (ratio == pytest.approx(1.0, rel=0.2)) if wall == 1.0 else ratio > 5
    assert volumes[1] == pytest.approx(volumes[0], rel=1e-10)


def test_msh_file_has_named_roles(tmp_path):
    if MPI.COMM_WORLD.rank != 0:
        return
    path = write_msh(make_scene(discretisation={"mesh_size": 1.0}), tmp_path / "ex1.msh")
    gmsh.initialize()
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.open(str(path))
        names = {gmsh.model.getPhysicalName(dim, tag)
                 for dim, tag in gmsh.model.getPhysicalGroups()}
        _, _, nodes = gmsh.model.mesh.getElements(2)
    finally:
        gmsh.finalize()
    assert {"workpiece", "gamma1_velocity", "gamma3_contact", "gamma6_symmetry"} <= names
    assert len(nodes[0]) % 9 == 0  # nine-node quadrilaterals by default (Q2)


def test_mesh_partition_repeats(monkeypatch):
    """Eight builds of the same mesh distribute its cells alike (with SCOTCH's threads, builds of
    this mesh differed), in balanced parts, and SCOTCH_PTHREAD_NUMBER is left as it was."""
    comm = MPI.COMM_WORLD
    monkeypatch.setenv("SCOTCH_PTHREAD_NUMBER", "2")
    scene = make_scene(discretisation={"mesh_size": 0.25})
    owned = []
    for _ in range(8):
        mesh = build_mesh(scene, comm).mesh
        local = mesh.topology.index_map(mesh.topology.dim).size_local
        owned.append(np.sort(original_cell_index(mesh)[:local]))
    assert all(np.array_equal(cells, owned[0]) for cells in owned)
    sizes = comm.allgather(len(owned[0]))
    assert max(sizes) <= 1.05 * min(sizes)
    assert os.environ["SCOTCH_PTHREAD_NUMBER"] == "2"

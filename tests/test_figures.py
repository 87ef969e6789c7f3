"""A run's figures and fields.xdmf: flow lines that follow the die and do not cross, die.png's
labels and die parts, one XDMF grid carrying every field, a non-negative strain rate in the file."""
import json
import xml.etree.ElementTree as ElementTree
from pathlib import Path

import h5py
import matplotlib.figure
import numpy as np
import pytest
from mpi4py import MPI

from forming_fenicsx import load_scene
from forming_fenicsx.plotting import die_parts, flow_lines
from forming_fenicsx.run import run_scene

DEMOS = Path(__file__).parents[1] / "demos"
FIELDS = {"velocity": 3, "equivalent_strain_rate": 1, "hydrostatic_pressure": 1,
          "secant_viscosity": 1}


@pytest.fixture(scope="module")
def wire(tmp_path_factory):
    """The copper wire demo (axisymmetric, mm and MPa) on a coarse mesh, every figure kept open."""
    out = Path(MPI.COMM_WORLD.bcast(str(tmp_path_factory.mktemp("wire") / "run"), root=0))
    scene = load_scene(DEMOS / "copper_wire.toml", ["discretisation.mesh_size_relative=0.2"])
    saved = {}
    original = matplotlib.figure.Figure.savefig

    def keep(fig, path, **kwargs):
        saved[Path(path).name] = fig
        return original(fig, path, **kwargs)

    matplotlib.figure.Figure.savefig = keep
    try:
        summary = run_scene(scene, out, title="wire")
    finally:
        matplotlib.figure.Figure.savefig = original
    MPI.COMM_WORLD.barrier()
    return out, summary, saved


def test_fields_xdmf_is_one_grid_with_every_field(wire):
    out, summary, _ = wire
    domain = ElementTree.parse(out / "fields.xdmf").getroot().find("Domain")
    grids = list(domain.iter("Grid"))
    assert len(grids) == 1 and grids[0].get("GridType") == "Uniform"
    grid = grids[0]
    geometry = grid.find("Geometry/DataItem")
    nodes = int(geometry.get("Dimensions").split()[0])
    attributes = {a.get("Name"): a for a in grid.findall("Attribute")}
    assert set(attributes) == set(FIELDS)
    with h5py.File(out / "fields.h5", "r") as h5:
        def dataset(item):
            name, path = item.text.strip().split(":")
            assert name == "fields.h5"
            return h5[path]

        assert dataset(geometry).shape == (nodes, 2)
        topology = grid.find("Topology")
        cells = int(topology.get("NumberOfElements"))
        assert dataset(topology.find("DataItem")).shape == (cells, 9)
        for name, width in FIELDS.items():
            item = attributes[name].find("DataItem")
            assert item.get("Dimensions") == f"{nodes} {width}"
            assert attributes[name].get("Center") == "Node"
            assert dataset(item).shape == (nodes, width)
        rate = dataset(attributes["equivalent_strain_rate"].find("DataItem"))[:]
        # clipped at 1e-12 of its largest value, above the rounding of dolfinx 0.5's writer (which
        # left -3e-12 against a largest 2e3 with a clip at zero; -4e-3 before any clip)
        assert rate.min() > 0.0
        assert rate.max() > 100.0  # 1/s; the process rate is 500 1/s
        speed = dataset(attributes["velocity"].find("DataItem"))[:, 0]
        assert np.abs(speed).max() == pytest.approx(1000.0, rel=1e-3)  # mm/s, the drawing speed


def test_die_plot_labels_settings_and_parts(wire):
    _, _, saved = wire
    if MPI.COMM_WORLD.rank != 0:
        return
    stresses, profile = saved["die.png"].axes
    assert stresses.get_xlabel() == \
        "s, distance along the die from where the workpiece meets it [mm]"
    assert stresses.get_ylabel() == \
        "contact pressure, averaged normal stress, friction stress [MPa]"
    settings = "wire: drawing, round 2 -> 1.8 mm, die 6 deg, mu = 0.05, Q2 h = 0.18 mm"
    assert settings in stresses.get_title()
    assert profile.get_ylabel() == "radius [mm]"
    assert profile.get_xlabel() == "x, along the axis [mm]"
    legend = [t.get_text() for t in profile.get_legend().get_texts()]
    assert legend == ["cone", "land", "nodes of Gamma3"]


def test_flow_lines_follow_the_die_and_do_not_cross(wire):
    out, summary, saved = wire
    if MPI.COMM_WORLD.rank != 0:
        return
    axes = saved["velocity.png"].axes[0]
    assert axes.get_xlabel() == "x [mm]" and axes.get_ylabel() == "y [mm]"
    blue = [line.get_xydata() for line in axes.get_lines() if line.get_color() == "tab:blue"]
    assert len(blue) == 10
    scene = json.loads((out / "summary.json").read_text())["scene"]["geometry"]
    entry, exit_radius = 0.5 * scene["entry_diameter"], 0.5 * scene["exit_diameter"]
    length = scene["length"]
    for line in blue:
        assert line[-1, 0] > length - 0.05 * length  # every line reaches the exit face
    # at the entry the lines sit at the centres of ten equal bands; in the product they lie in the
    # same order, below the exit radius: they followed the die and did not cross
    starts = np.array([line[0, 1] for line in blue])
    assert starts == pytest.approx(entry * (np.arange(10) + 0.5) / 10, rel=1e-9)
    for x in np.linspace(0.05, 0.95, 10) * length:
        heights = [np.interp(x, line[:, 0], line[:, 1]) for line in blue]
        assert np.all(np.diff(heights) > 0) and heights[-1] < entry
    ends = np.array([line[-1, 1] for line in blue])
    assert ends[-1] < exit_radius and ends[-1] > 0.85 * exit_radius


def test_flow_lines_of_a_uniform_flow_are_straight_with_square_marks():
    """Two triangles over [0, 4] x [0, 1], u = (2, 0): straight lines at the band centres, marks
    every two band widths of travel."""
    points = np.array([[0.0, 0.0], [4.0, 0.0], [0.0, 1.0], [4.0, 1.0]])
    triangles = np.array([[0, 1, 3], [0, 3, 2]])
    lines, every = flow_lines(points, triangles, np.tile([2.0, 0.0], (4, 1)), count=4)
    assert [line[0, 1] for line in lines] == pytest.approx([0.125, 0.375, 0.625, 0.875])
    for line in lines:
        assert np.ptp(line[:, 1]) < 1e-12 and 3.9 < line[-1, 0] <= 4.0
        assert line[every, 0] - line[0, 0] == pytest.approx(2 * 0.25, rel=1e-9)


def test_die_parts_by_slope():
    square = die_parts(np.array([0.0, 5.0, 10.0, 10.0, 10.0]), np.array([5.0, 5.0, 5.0, 4.0, 2.5]))
    assert square == ["container wall", "container wall", "die face", "die face"]
    cone = die_parts(np.array([0.0, 1.0, 2.0, 3.0]), np.array([5.0, 5.0, 4.0, 4.0]))
    assert cone == ["container wall", "cone", "land"]


def test_surface_cell_depth_is_the_exit_element():
    """The cold rod demo's mesh (h 1.2 mm): ceil(10 / 1.2) = 9 elements through the radius, so
    the element at the product's surface (exit radius 6 mm) is 6/9 mm deep; exit_strain.png
    shades it."""
    from forming_fenicsx.geometry import build_mesh
    from forming_fenicsx.postprocess import surface_cell_depth

    scene = load_scene(Path(__file__).parents[1] / "demos" / "aluminium_rod_cold.toml")
    g = scene.geometry
    depth = surface_cell_depth(build_mesh(scene, MPI.COMM_WORLD).mesh, g.length - 0.5 * g.thinnest,
                               g.thinnest * (1 - 1e-9))
    assert depth == pytest.approx(6.0 / 9.0, rel=1e-6)

"""A run's figures and fields.xdmf: flow lines that follow the die and do not cross, time lines
that stay straight across a flow that speeds up, the maps' window over the die with the die drawn
at 1:1, die.png's labels, parts and 1:1 profile, stresses without an offset, rounded titles and the
mark of a run that did not converge; one XDMF grid carrying every field, a non-negative strain rate
in the file."""
import csv
import json
import math
import re
import xml.etree.ElementTree as ElementTree
from pathlib import Path

import h5py
import numpy as np
import pytest
from conftest import kept_figures
from mpi4py import MPI

from forming_fenicsx import load_scene
from forming_fenicsx.io.die_plot import DIE_PARTS, die_parts, write_die_plot
from forming_fenicsx.io.figure import Heading, not_converged, run_settings
from forming_fenicsx.io.flow_lines import MAX_GAP, flow_lines
from forming_fenicsx.io.maps import die_body
from forming_fenicsx.app.run import run_scene

DEMOS = Path(__file__).parents[1] / "demos"
FIELDS = {"velocity": 3, "equivalent_strain_rate": 1, "hydrostatic_pressure": 1,
          "secant_viscosity": 1}


@pytest.fixture(scope="module")
def wire(tmp_path_factory):
    """The copper wire demo (axisymmetric, mm and MPa) on a coarse mesh, every figure kept open."""
    out = Path(MPI.COMM_WORLD.bcast(str(tmp_path_factory.mktemp("wire") / "run"), root=0))
    scene = load_scene(DEMOS / "copper_wire.toml", ["discretisation.mesh_size_relative=0.2"])
    with kept_figures() as saved:
        summary = run_scene(scene, out, title="wire")
    MPI.COMM_WORLD.barrier()
    return out, summary, saved


def _die_wall(out: Path) -> np.ndarray:
    """die.csv's x and y: the nodes of Gamma3 along the die, (N, 2)."""
    with (out / "die.csv").open() as stream:
        rows = list(csv.DictReader(stream))
    return np.array([[float(r["x [mm]"]), float(r["y [mm]"])] for r in rows])


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
        "s, distance along the die from its entry [mm]"
    assert stresses.get_ylabel() == "stress on the die [MPa]"
    curves = [t.get_text() for t in stresses.get_legend().get_texts()][2:]
    assert curves == ["contact pressure -sigma_N", "averaged normal stress",
                      "friction stress |sigma_T|"]
    settings = "wire: drawing, round 2 -> 1.8 mm, die 6 deg, mu = 0.05, Q2 h = 0.18 mm"
    assert settings in stresses.get_title() and "NOT CONVERGED" not in stresses.get_title()
    assert profile.get_ylabel() == "radius [mm]"
    assert profile.get_xlabel() == "x, along the axis [mm]"
    legend = [t.get_text() for t in profile.get_legend().get_texts()]
    assert legend == ["cone", "land", "nodes of Gamma3"]


def test_die_profile_is_drawn_one_to_one(wire):
    """The lower panel of die.png at equal aspect: the 6 degree cone is drawn at 6 degrees on the
    page (it was 11 to 45 degrees, whatever the panel's proportions made it)."""
    _, _, saved = wire
    if MPI.COMM_WORLD.rank != 0:
        return
    figure = saved["die.png"]
    profile = figure.axes[1]
    figure.canvas.draw()
    assert profile.get_aspect() == 1.0
    cone = next(line for line in profile.get_lines() if line.get_color() == DIE_PARTS["cone"])
    ends = profile.transData.transform(cone.get_xydata()[[0, -1]])
    drawn = math.degrees(math.atan2(ends[0, 1] - ends[1, 1], ends[1, 0] - ends[0, 0]))
    assert drawn == pytest.approx(6.0, abs=0.05)
    low, high = profile.get_ylim()
    assert low <= 0.0 < 1.0 <= high  # from the axis to the entry radius


def test_maps_show_the_die_zone_at_one_to_one_with_the_die(wire):
    """velocity.png and strain_rate.png: the window covers the die (die.csv's x range) but not the
    whole 10 mm wire, at 1:1 from the axis to above the entry radius; the die drawn as a patch
    along its wall; the strain rate in viridis with a colour bar as tall as the map."""
    out, _, saved = wire
    if MPI.COMM_WORLD.rank != 0:
        return
    wall = _die_wall(out)
    length = json.loads((out / "summary.json").read_text())["scene"]["geometry"]["length"]
    for name in ("velocity.png", "strain_rate.png"):
        figure = saved[name]
        figure.canvas.draw()
        ax = figure.axes[0]
        left, right = ax.get_xlim()
        assert left < wall[0, 0] and right > wall[-1, 0]
        assert right - left < 0.5 * length
        assert ax.get_ylim()[0] == 0.0 and ax.get_ylim()[1] > wall[:, 1].max()
        assert ax.get_aspect() == 1.0
        die = [patch for patch in ax.patches if patch.get_label() == "die"]
        assert len(die) == 1
        outline = die[0].get_xy()
        for point in (wall[0], wall[-1]):
            assert np.min(np.linalg.norm(outline - point, axis=1)) < 1e-6
        assert "NOT CONVERGED" not in ax.get_title()
    rates = saved["strain_rate.png"]
    cells = rates.axes[0].collections[0]
    assert cells.get_cmap().name == "viridis"
    bar, mapped = rates.axes[1].get_window_extent(), rates.axes[0].get_window_extent()
    assert bar.height == pytest.approx(mapped.height, rel=0.02)


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


SQUARE = (np.array([[0.0, 0.0], [4.0, 0.0], [0.0, 1.0], [4.0, 1.0]]),
          np.array([[0, 1, 3], [0, 3, 2]]))  # two triangles over [0, 4] x [0, 1]


def test_flow_lines_of_a_uniform_flow_are_straight_with_square_marks():
    """u = (2, 0): straight lines at the band centres, time lines straight across from the axis
    to the outermost band centre, every two band widths of travel."""
    points, triangles = SQUARE
    lines, times = flow_lines(points, triangles, np.tile([2.0, 0.0], (4, 1)), count=4)
    assert [line[0, 1] for line in lines] == pytest.approx([0.125, 0.375, 0.625, 0.875])
    for line in lines:
        assert np.ptp(line[:, 1]) < 1e-12 and 3.9 < line[-1, 0] <= 4.0
    assert len(times) == 7  # at x = 0.5, 1, ..., 3.5
    for index, line in enumerate(times, start=1):
        assert np.ptp(line[:, 0]) < 1e-12
        assert line[0, 0] == pytest.approx(0.5 * index, abs=1e-5)  # the seeds 4e-6 inside
        assert line[0, 1] < 1e-3 and line[-1, 1] == pytest.approx(0.875)


def test_time_lines_stay_straight_across_a_flow_that_speeds_up():
    """u = (1 + x, -y), incompressible, linear (exact on the triangles): as in an extruded product
    the material speeds up, and a line of markers that entered together stays a straight line
    across the flow, at x = e^t - 1 (t = 0.5, 1, 1.5: every two band widths of entry travel), not
    the long oblique lines of marks joined across the section."""
    points, triangles = SQUARE
    lines, times = flow_lines(points, triangles,
                              np.column_stack([1 + points[:, 0], -points[:, 1]]), count=4)
    assert len(lines) == 4 and len(times) == 3
    for index, line in enumerate(times, start=1):
        assert np.ptp(line[:, 0]) < 1e-6
        assert line[0, 0] == pytest.approx(math.exp(0.5 * index) - 1, rel=1e-4)


def test_time_lines_stay_connected_across_a_shear_layer():
    """u = (1 + 20 y, 0) (linear on the two triangles): the outer layer outruns the core 21 to
    1, as an extruded product's core outruns its surface held by friction. Seeds are added where
    neighbouring marks drift apart, so that every time line stays within MAX_GAP band widths from
    point to point (with the starting seeds alone the last time line's marks were 2.73 band
    widths apart: chords that cut across the die of an extrusion)."""
    points, triangles = SQUARE
    band = 1.0 / 4
    _, times = flow_lines(points, triangles,
                          np.column_stack([1 + 20 * points[:, 1], 0 * points[:, 1]]), count=4)
    assert len(times) == 24
    for line in times:
        assert np.linalg.norm(np.diff(line, axis=0), axis=1).max() <= MAX_GAP * band
    assert len(times[-1]) == 35  # 5 with the starting seeds alone


@pytest.mark.no_parallel_content  # pure Python: a figure from numbers
def test_stresses_in_pa_read_in_mpa_without_offset_and_a_failed_run_says_so(tmp_path):
    """die.png of a scene in m and Pa: a stress axis of 3e8 +- 2e4 Pa reads 299.98 to 300.02 MPa,
    without the "1e8" or "+3e2" offset above it, the lengths without offset; a heading with a
    failure puts it in red first in the title and across the plot."""
    scene = load_scene(DEMOS / "strip_mm.toml", ["units.length='m'", "units.stress='Pa'",
                                                 "units.force='N'"])
    s = np.linspace(0.0, 1.2e-3, 25)
    profile = {"s": s, "x": 3.7e-3 + s * math.cos(math.radians(10)),
               "y": 1e-3 - s * math.sin(math.radians(10)),
               "contact_pressure": 3e8 + 2e4 * np.sin(5e3 * s)}
    heading = Heading("si", run_settings(scene), "NOT CONVERGED: stalled or oscillating")
    with kept_figures() as saved:
        write_die_plot(profile, tmp_path / "die.png", heading, scene)
    figure = saved["die.png"]
    figure.canvas.draw()
    stresses, shape = figure.axes
    assert stresses.get_ylabel() == "stress on the die [MPa]"
    assert stresses.get_ylim() == pytest.approx((300.0, 300.0), abs=0.03)
    ticks = [float(label.get_text().replace("\u2212", "-")) for label in stresses.get_yticklabels()]
    assert all(299.9 < tick < 300.1 for tick in ticks)  # with an offset: -0.02 ... 0.02
    for axis in (stresses.xaxis, stresses.yaxis, shape.xaxis, shape.yaxis):
        assert axis.get_offset_text().get_text() == ""
    title = stresses.get_title()
    assert title.startswith("NOT CONVERGED: stalled or oscillating\nsi: drawing")
    assert stresses.title.get_color() == "tab:red"
    assert "NOT CONVERGED" in [text.get_text() for text in stresses.texts]


@pytest.mark.no_parallel_content  # pure Python
def test_not_converged_names_the_first_clause_of_the_reason_or_the_failed_check():
    """The iteration's reason when it did not converge, else the first failed check, each cut at
    its first clause; None for a converged run."""
    stopped = {"converged": False, "iteration_converged": False, "failed_checks": ["x forces ..."],
               "reason": "no convergence in 2 Newton steps (last increment 2.470e-02, delta "
                         "0.0001)"}
    assert not_converged(stopped) == "NOT CONVERGED: no convergence in 2 Newton steps"
    checked = {"converged": False, "iteration_converged": True, "reason": "the iteration ...",
               "failed_checks": ["8.32 % of the throughput flows into the die (u_N > 0 on "
                                 "Gamma3): the contact penalty d_N = 0.01 is too soft"]}
    assert not_converged(checked) == "NOT CONVERGED: 8.32 % of the throughput flows into the die"
    long = {**stopped, "reason": "word " * 40}
    assert len(not_converged(long)) <= len("NOT CONVERGED: ") + 90
    assert not_converged({**stopped, "converged": True}) is None


@pytest.mark.no_parallel_content  # pure Python: scene to text
def test_titles_round_the_die_angle_of_a_chord():
    """A two-angle die's semi-angle is its chord's (9.70039... deg here): the title gives 4
    significant digits and says it is the chord's."""
    scene = load_scene(DEMOS / "strip_mm.toml", ["geometry.second_angle=20",
                                                 "geometry.second_angle_length=0.2"])
    angle = scene.geometry.semi_angle
    assert angle != round(angle, 2)
    settings = run_settings(scene)
    assert f"die {angle:.4g} deg (chord)," in settings
    numbers = [n for n in re.findall(r"\d+\.?\d*", settings)]
    assert all(len(n.replace(".", "").lstrip("0")) <= 4 for n in numbers), settings


def test_die_parts_by_slope():
    square = die_parts(np.array([0.0, 5.0, 10.0, 10.0, 10.0]), np.array([5.0, 5.0, 5.0, 4.0, 2.5]))
    assert square == ["container wall", "container wall", "die face", "die face"]
    cone = die_parts(np.array([0.0, 1.0, 2.0, 3.0]), np.array([5.0, 5.0, 4.0, 4.0]))
    assert cone == ["container wall", "cone", "land"]
    # a curved die's tail within 1 deg of the axis before its land (a new user's bell die: the
    # land's band started two elements early)
    tail = (np.array([0.0, 1.0, 2.0, 3.0, 4.0]), np.array([5.0, 4.0, 3.99, 3.99, 3.99]))
    assert die_parts(*tail) == ["cone", "land", "land", "land"]
    assert die_parts(*tail, land_start=2.0) == ["cone", "cone", "land", "land"]


def test_die_body_closes_the_wall_above():
    """The die drawn on a map: a square die's face goes on as a plate to the window's right edge;
    a drawing die ends with a back face at the end of its land; both closed at the top."""
    square = die_body(np.array([[0.0, 5.0], [10.0, 5.0], [10.0, 2.5]]), 15.0, 5.75)
    assert square[3:].tolist() == [[15.0, 2.5], [15.0, 5.75], [0.0, 5.75]]
    drawing = die_body(np.array([[3.7, 1.0], [4.8, 0.8], [5.0, 0.8]]), 6.0, 1.15)
    assert drawing[3:].tolist() == [[5.0, 0.8], [5.0, 1.15], [3.7, 1.15]]


def test_surface_cell_depth_is_the_exit_element():
    """The cold rod demo's mesh (h 1.2 mm): ceil(10 / 1.2) = 9 elements through the radius, so
    the element at the product's surface (exit radius 6 mm) is 6/9 mm deep; exit_strain.png
    shades it."""
    from forming_fenicsx.mesh.geometry import build_mesh
    from forming_fenicsx.post.exit_profiles import surface_cell_depth

    scene = load_scene(Path(__file__).parents[1] / "demos" / "aluminium_rod_cold.toml")
    g = scene.geometry
    depth = surface_cell_depth(build_mesh(scene, MPI.COMM_WORLD).mesh, g.length - 0.5 * g.thinnest,
                               g.thinnest * (1 - 1e-9))
    assert depth == pytest.approx(6.0 / 9.0, rel=1e-6)

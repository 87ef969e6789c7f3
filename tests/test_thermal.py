"""The steady heat equation (thermal.py) against exact solutions (thermal_verification.py,
docs/thermal.md): the 1-D advection-diffusion layer at Peclet 1e1 to 1e5, manufactured solutions in
both symmetries with their orders, the adiabatic limit of the radial flows (with and without a
temperature-dependent source coupled by freezing), the heat balances, the frozen protocol, the
[thermal] scene section and the field it builds on a flow."""
from __future__ import annotations

from pathlib import Path

import dolfinx.fem
import pytest
import ufl
from mpi4py import MPI

from conftest import make_scene
from forming_fenicsx.physics.coordinates import CoordinateSystem
from forming_fenicsx.core.errors import SceneError
from forming_fenicsx.app.run import solve_scene, solve_updated
from forming_fenicsx.config.loader import load_scene, read_scene_data, scene_from_dict
from forming_fenicsx.coupled.thermal import TemperatureField, ThermalMaterial, effusivity_share
from forming_fenicsx.coupled.thermal_scene import scene_temperature_field
from forming_fenicsx.verification.thermal_verification import (LEFT, RIGHT, adiabatic, layer,
                                                               manufactured, orders, rectangle)

PECLET = (1e1, 1e2, 1e3, 1e4, 1e5)


@pytest.mark.parametrize("degree", [1, 2])
def test_layer_without_oscillation(degree):
    """u T' = k T'' on 20 cells (cell Peclet 0.25 to 2500), sampled at 20 points per cell. Bounds
    (measured): Q1 neither over- nor undershoots (1e-15); Q2 undershoots by at most 6 % of the jump
    in the last cell (3.8 to 5.7 % from Pe = 1e2 on), never overshoots; nothing reaches upstream:
    the error where x <= 1/2 is below 2e-4 (Q1 at Pe = 10, where the layer spans the domain; 1e-17
    and less from Pe = 1e2 on), and outside the last cell below 0.02 (Q1) and 0.07 (Q2)."""
    runs = [layer(peclet, 20, degree) for peclet in PECLET]
    assert max(r["overshoot"] for r in runs) < 1e-12
    assert max(r["undershoot"] for r in runs) < (1e-12 if degree == 1 else 0.06)
    assert max(r["error_first_half"] for r in runs) < 2e-4
    assert max(r["error_first_half"] for r in runs[1:]) < 1e-10
    assert max(r["error_outside_layer"] for r in runs) < (0.02 if degree == 1 else 0.07)


@pytest.mark.parametrize("degree", [1, 2])
@pytest.mark.parametrize("symmetry", ["plane_strain", "axisymmetric"])
def test_manufactured_orders(symmetry, degree):
    """Observed orders between 4, 8 and 16 cells a side at Peclet u L/k = 50 (cell Peclet 6 to 1.6
    for Q1): L2 p + 1 and H1 p (measured Q1 1.77 to 2.0 and 1.0; Q2 2.9 to 3.0 and 2.0), in the
    weighted measure when axisymmetric; the heat balance (tool exchange, friction share, inflow,
    source) closes to 1e-5 on 16 cells (measured 8e-7 and 2e-7 for Q1, below 1e-9 for Q2)."""
    runs = [manufactured(symmetry, degree, cells) for cells in (4, 8, 16)]
    l2, h1 = orders([r["l2"] for r in runs]), orders([r["h1"] for r in runs])
    assert l2.min() > (1.7 if degree == 1 else 2.85), l2
    assert h1.min() > degree - 0.05, h1
    assert abs(runs[-1]["residual"]) < 1e-5
    balance = runs[-1]
    assert balance["friction_to_die"] == pytest.approx(balance["friction_to_workpiece"] * 0.4 / 0.6)


@pytest.mark.parametrize("degree", [1, 2])
@pytest.mark.parametrize("symmetry", ["axisymmetric", "plane_strain"])
def test_adiabatic_limit(symmetry, degree):
    """kappa = 0, no tool contact, the exact cone (wedge) flow on 4 cells across the angle: the
    mixing-cup exit temperature rise is beta W/(rho c) to 1e-3 (the issue asks 1 %; measured 2.2e-4
    and 2.7e-4 for Q1, below 1e-6 for Q2); the heat balance closes to 2e-3 and the drawing power
    equals the heat carried out plus the work stored to 1e-3 (measured, Q1: 1.4e-3 and 3.5e-4)."""
    result = adiabatic(symmetry, degree, 4)
    assert result["exit_rise"] == pytest.approx(result["exact_rise"], rel=1e-3)
    assert abs(result["residual"]) < 2e-3
    assert abs(result["global_residual"]) < 1e-3


@pytest.mark.parametrize("symmetry", ["axisymmetric", "plane_strain"])
def test_temperature_dependent_source_by_freezing(symmetry):
    """A flow stress softening as exp(-(T - T_in)/theta), theta = 0.1 (the exit rise falls from 0.30
    to 0.14 in the cone): freezing with relaxation 1/2 until the change is below 1e-10 reaches
    exp(dT/theta) - 1 = beta W/(rho c theta) to 1e-3 (measured 3.1e-4 and 2.4e-4, Q1, 4 cells) in
    17 freezes, one solve per freeze and one for the first change."""
    result = adiabatic(symmetry, 1, 4, softening=0.1)
    assert result["exit_rise"] == pytest.approx(result["exact_rise"], rel=1e-3)
    assert result["freezes"] <= 25
    assert result["solves"] == result["freezes"] + 1


def test_frozen_protocol():
    """change(u) is the relative L2 distance to the solution at u; a freeze (relaxation 1/2) halves
    it; a zero velocity (before the first flow solve) leaves T as it is: change 0, no solve."""
    mesh, tags, V = rectangle((8, 1), (1.0, 0.125), 1)
    u = dolfinx.fem.Function(V)
    field = TemperatureField(u, CoordinateSystem(mesh), tags, ThermalMaterial(1.0, 0.01), 300.0, 1,
                             fixed={LEFT: 300.0, RIGHT: 400.0})
    assert field.change(u) == 0 and field.solves == 0
    u.x.array[0::2] = 1.0
    first = field.change(u)
    field.freeze(u)
    second = field.change(u)
    assert first > 1e-2
    assert second == pytest.approx(first / 2, rel=1e-10)
    assert field.solves == 2  # the freeze reused the change's solve; T moved: change solved again
    hottest = mesh.comm.allreduce(field.T.x.array.max(), op=MPI.MAX)
    assert hottest == pytest.approx(350.0)  # half way from 300 to the fixed 400
    field.destroy()


def test_effusivity_share():
    """Blok's share e_w/(e_w + e_d): 1/2 for like materials; aluminium (201 W/(m K), 2.98 MPa/K)
    on H13 tool steel (24.3 W/(m K), 7800 kg/m^3 x 460 J/(kg K) = 3.59 MPa/K): 0.724."""
    aluminium, steel = ThermalMaterial(2.98, 201.0), ThermalMaterial(3.588, 24.3)
    assert effusivity_share(aluminium, aluminium) == 0.5
    assert effusivity_share(aluminium, steel) == pytest.approx(0.7238, abs=1e-4)


THERMAL = {"heat_capacity": 2.98, "conductivity": 201.0, "inflow_temperature": 723.15,
           "die_h": 20.0, "container_h": 5.0, "container_temperature": 693.15, "air_h": 0.01}


def rod_scene(**thermal):
    """demos/aluminium_rod.toml (mm, MPa, s) on a coarse mesh, with a [thermal] section."""
    data = read_scene_data(Path(__file__).parents[1] / "demos" / "aluminium_rod.toml")
    data["discretisation"]["mesh_size"] = 2.5
    data["output"] = {"fields": False, "figures": False}
    if thermal:
        data["thermal"] = thermal
    return scene_from_dict(data)


def test_thermal_scene_section():
    """[thermal] is optional (None, and absent from the resolved scene, without it); the die's
    temperature defaults to the inflow's, the container's values to the die's; missing, unknown and
    non-physical keys are named; drawing has no container; a mesh file has one Gamma3."""
    assert rod_scene().thermal is None and "thermal" not in rod_scene().to_dict()
    die_only = {k: v for k, v in THERMAL.items() if not k.startswith("container")}
    thermal = rod_scene(**die_only).thermal
    assert (thermal.die_temperature, thermal.container_h) == (723.15, 20.0)
    assert thermal.container_temperature == 723.15 and thermal.heat_fraction == 0.9
    assert rod_scene(**THERMAL).to_dict()["thermal"]["container_temperature"] == 693.15
    for bad, key in (({"conductivity": None}, "thermal.conductivity"),
                     ({"conductivity": -1.0}, "thermal.conductivity"),
                     ({"inflow_temperature": -10.0}, "thermal.inflow_temperature"),
                     ({"friction_share": 1.5}, "thermal.friction_share"),
                     ({"die_temperatur": 700.0}, "thermal.die_temperatur")):
        table = {k: v for k, v in {**THERMAL, **bad}.items() if v is not None}
        with pytest.raises(SceneError, match=key):
            rod_scene(**table)
    with pytest.raises(SceneError, match="thermal.container_h"):
        make_scene(process={"kind": "drawing"}, thermal=THERMAL)


def test_scene_temperature_field():
    """The coarse aluminium rod with [thermal] (one way: the flow law does not read T): the
    container wall split from the die, the heat balance closes to 1e-3 (measured 1.5e-4) and the
    ram's power against the heat leaving and stored to 2e-3 (measured 5.4e-4); the container
    (420 C) takes more than half the heat generated, and the mixing-cup exit temperature lies
    between the billet's 450 C and the adiabatic 450 + beta p_ram/(rho c) (measured 457.6 C
    against 485 C)."""
    scene = rod_scene(**THERMAL)
    problem, _, summary = solve_scene(scene)
    field = scene_temperature_field(problem)
    field.settle(problem.u)
    balance = field.energy_balance(summary["ram_force"] * scene.process.velocity)
    assert abs(balance["residual"]) < 1e-3 and abs(balance["global_residual"]) < 2e-3
    assert balance["exchange_container"] > 0.5 * balance["generated"]
    leaving = ufl.dot(field.velocity, field.n)
    outflow = ufl.conditional(ufl.gt(leaving, 0), leaving, 0)
    exit_temperature = (field.integral(field.T * outflow, field.ds)
                        / field.integral(outflow, field.ds))
    adiabatic = 723.15 + 0.9 * summary["ram_pressure"] / 2.98
    assert 723.15 + 2 < exit_temperature < adiabatic - 2
    field.destroy()


def test_hot_rod_run_writes_its_temperature(shared_tmp):
    """demos/aluminium_rod_hot.toml through `forming run`'s pipeline: the temperature of the
    converged flow (one way), its exit profile and balance. The product leaves between the billet's
    450 C and the adiabatic 450 C + beta p / (rho c) (the container at 420 C takes heat); the energy
    balance closes to 2e-3 (measured 4.7e-4 on the default mesh, 7.4e-4 on this test's coarse one,
    h = 4 mm).
    The scene's units.temperature = "C": the summary in kelvin, the CSV in kelvin and Celsius,
    temperature.png (magma) and exit_temperature.png in Celsius."""
    import json

    from conftest import kept_figures
    from forming_fenicsx.app.run import run_scene
    from forming_fenicsx.config.loader import load_scene

    demos = Path(__file__).resolve().parents[1] / "demos"
    scene = load_scene(demos / "aluminium_rod_hot.toml", ["discretisation.mesh_size=4"])
    with kept_figures() as figures:
        summary = run_scene(scene, shared_tmp / "hot_rod")
    inflow = scene.thermal.inflow_temperature
    adiabatic = inflow + 0.9 * summary["ram_pressure"] / 2.98
    assert summary["converged"]
    for key in ("min_exit_temperature", "mean_exit_temperature", "max_exit_temperature"):
        assert inflow < summary[key] < adiabatic, key
    assert abs(summary["energy_balance_residual"]) < 2e-3
    assert summary["units"]["quantities"]["mean_exit_temperature"] == "K"
    assert summary["units"]["temperature"] == "K" and summary["units"]["temperature_shown"] == "C"
    written = json.loads((shared_tmp / "hot_rod" / "summary.json").read_text())
    assert written["energy_balance"]["process_power"] == pytest.approx(
        summary["ram_force"] * scene.process.velocity)
    rows = (shared_tmp / "hot_rod" / "exit_temperature.csv").read_text().splitlines()
    assert rows[0] == "y [mm],temperature [K],temperature [C]" and len(rows) == 42
    kelvin, celsius = (float(value) for value in rows[1].split(",")[1:])
    assert celsius == pytest.approx(kelvin - 273.15, abs=1e-6)
    if MPI.COMM_WORLD.rank == 0:
        mapped = figures["temperature.png"].axes[0].collections[0]
        assert mapped.get_cmap().name == "magma"
        low, high = mapped.get_clim()  # Celsius: the container's 420 C to the product's
        assert 400 < low < 450 < high < summary["max_exit_temperature"] - 273.15 + 5
        assert figures["temperature.png"].axes[1].get_ylabel() == "temperature [C]"
        profile = figures["exit_temperature.png"].axes[0]
        assert profile.get_ylabel() == "temperature [C]"
        legend = [text.get_text() for text in profile.get_legend().get_texts()]
        assert "inflow temperature = 450" in legend
    assert 'Name="temperature"' in (shared_tmp / "hot_rod" / "fields.xdmf").read_text()


def test_hot_extrusion_softens_as_it_heats():
    """demos/aluminium_rod_hot.toml with insulated tools (the heat of deformation stays in the
    billet): the Sellars-Tegart flow stress read at the coupled temperature, against the isothermal
    run at the billet's 450 C (the same scene without [thermal]), on a coarse mesh (h = 4 mm).
    Measured: 112.44 against 123.27 MPa (on the demo's 2 mm mesh 106.00 against 115.77), the product
    30.7 K hotter (below beta p / (rho c) = 34.0 K: a share of the friction heat goes to the die),
    14 Newton solves against 12 (the issue allows 3 times)."""
    demos = Path(__file__).resolve().parents[1] / "demos"
    insulated = ["thermal.die_h=0", "thermal.container_h=0", "thermal.air_h=0",
                 "output.fields=false", "output.figures=false", "discretisation.mesh_size=4"]
    data = read_scene_data(demos / "aluminium_rod_hot.toml", insulated)
    hot = solve_scene(scene_from_dict(data))[2]
    data.pop("thermal")
    data["material"]["temperature"] = 723.15
    cold = solve_scene(scene_from_dict(data))[2]
    assert hot["converged"] and cold["converged"]
    assert hot["ram_pressure"] < 0.95 * cold["ram_pressure"]
    rise = hot["mean_exit_temperature"] - 723.15
    assert 0.5 < rise / (0.9 * hot["ram_pressure"] / 2.98) < 1.0
    assert abs(hot["energy_balance_residual"]) < 5e-3
    assert hot["linear_solves"] <= 3 * cold["linear_solves"]


def test_softening_hardening_law_reads_the_temperature():
    """Annealed copper wire (demos/copper_wire_pass.toml, coarse) with a Hensel-Spittel softening
    factor exp(-0.002 (T - 293.15 K)): insulated, the wire heats by its own work (measured 9.2 K at
    the exit) and draws 1.2 % easier (40.33 against 40.80 MPa) than without [thermal], where the
    factor stays 1; strain and temperature coupled at every Newton step. On this test's mesh, h =
    0.15 mm as the schedule's (1 rank): 9.34 K, 1.2 % (40.68 against 41.16 MPa), 16 and 11 Newton
    solves."""
    data = read_scene_data(
        Path(__file__).resolve().parents[1] / "demos" / "copper_wire_pass.toml",
        ["output.fields=false", "output.figures=false", "material.softening=0.002",
         "material.softening_temperature=293.15", "discretisation.mesh_size=0.15"])
    cold = solve_scene(scene_from_dict(data))[2]
    data["thermal"] = {"heat_capacity": 3.45, "conductivity": 400.0, "inflow_temperature": 293.15}
    hot = solve_scene(scene_from_dict(data))[2]
    assert cold["converged"] and hot["converged"]
    assert 3.0 < hot["mean_exit_temperature"] - 293.15 < 15.0
    assert 0.003 < 1 - hot["drawing_stress"] / cold["drawing_stress"] < 0.03


def test_a_hot_run_that_melts_fails_naming_the_solidus():
    """Issue 34: hot AA6063 at a ram speed of 1e6 mm/s converged unflagged at an exit temperature
    of 1675 K (1402 C). Now the run fails: the workpiece passes AA6063's solidus, 888 K (measured
    on this coarse mesh: 1983 K at the die wall, 2.23 times the solidus)."""
    demos = Path(__file__).resolve().parents[1] / "demos"
    scene = load_scene(demos / "aluminium_rod_hot.toml", ["output.figures=false",
                                                          "discretisation.mesh_size=4",
                                                          "process.velocity=1e6"])
    summary = solve_scene(scene)[2]
    assert summary["iteration_converged"] and not summary["converged"]
    assert summary["max_temperature"] > scene.thermal.solidus == 888.0
    assert "above the solidus" not in summary["reason"]
    assert ("of its solidus 888.0 K (614.9 C)" in summary["reason"]
            and "it melts" in summary["reason"])


def hot_strip_extrusion(**sections) -> dict:
    """A new user's scene (mm, MPa, s): an AA6060 strip 40 -> 10 mm through a square die at 10 mm/s,
    friction factor 0.9, the billet at 480 C, the die at 450 C, 150 mm wide; h = 2.5 mm."""
    data = {"process": {"kind": "extrusion", "velocity": 10.0},
            "geometry": {"die": "square", "symmetry": "plane_strain", "entry_thickness": 40.0,
                         "exit_thickness": 10.0, "width": 150.0},
            "material": {"name": "AA6060"}, "friction": {"law": "factor", "m": 0.9},
            "discretisation": {"mesh_size": 2.5},
            "units": {"length": "mm", "time": "s", "stress": "MPa", "force": "N"},
            "thermal": {"heat_capacity": 2.7, "conductivity": 200.0, "inflow_temperature": 753.15,
                        "die_h": 15.0, "die_temperature": 723.15, "air_h": 0.01},
            "output": {"fields": False, "figures": False}}
    for name, values in sections.items():
        data.setdefault(name, {}).update(values)
    return data


def test_friction_heat_is_the_flows_own_from_any_start():
    """The friction heat is the regularised law's power at the velocity the temperature is solved
    for. It read the secant iterates' slip coefficient, which Newton's steps do not update: Newton
    started without its secant iterates (as every free-surface update starts from the last flow)
    saw tau_f / d_T at zero slip, heated the die face to 9000 K, and the new user's hot strip (h = 1
    mm) converged at a ram pressure of 1.83 MPa instead of 99.8, flagged only by the heat balance.
    Now the default start, Newton from the uniform-modulus solution and the free surface agree
    (measured 103.60, 103.62 and 102.60 MPa, the last on its own shape, 1.0 % lower), and every
    heat balance closes (measured 3.7e-4, 3.8e-4, 4.6e-4)."""
    runs = [solve_scene(scene_from_dict(hot_strip_extrusion()))[2],
            solve_scene(scene_from_dict(hot_strip_extrusion(solver={"secant_start": 0})))[2],
            solve_updated(scene_from_dict(hot_strip_extrusion(free_surface={"update": True})))[2]]
    for summary in runs:
        assert summary["converged"], summary["reason"]
        assert abs(summary["energy_balance_residual"]) < 2e-3
        assert summary["max_temperature"] < 800.0  # the die face heats by its friction only
    default, cold_newton, free = (summary["ram_pressure"] for summary in runs)
    assert cold_newton == pytest.approx(default, rel=1e-3)
    assert free == pytest.approx(default, rel=0.03)
    assert runs[2]["free_surface"]["updates"] >= 1

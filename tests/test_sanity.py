"""The physical sanity checks (sanity.py) on summaries of a normal run with one number changed: each
check is silent below its thresholds, warns between them and fails above, naming cause and fix."""
import dataclasses
import math

import pytest

from forming_fenicsx.post.sanity import bite, check_run
from forming_fenicsx.config.loader import scene_from_dict

# measured on Example 2 (mu = 0.2, Q2 reduced, h = 0.05) with the default penalties
NORMAL = {"die_penetration": 2e-5, "relative_divergence": 3e-3, "exit_zone_rate_ratio": 1.5e-5,
          "drawing_stress": 70.0, "free_surface_crossing": 0.019, "die_contact_fraction": 0.8,
          "dissipation_above_rate2": 0.037, "dissipation_below_rate1": 0.01,
          "solve_error_estimate": 1e-9, "volume_change": -1.8e-4,
          # the drawing stress over the strip's 2k, about 201
          "product_yield_ratio": 70.0 / 201.0, "force_balance_residual": 2e-5}
SCENE = scene_from_dict({"process": {"kind": "drawing"}})


def findings(**changed):
    return {f.check: f for f in check_run({**NORMAL, **changed}, SCENE)}


def test_a_normal_run_passes_every_check():
    assert findings() == {}


@pytest.mark.parametrize("key, warn, fail, check, phrase", [
    ("die_penetration", 0.02, 0.083, "die_penetration", "smaller solver.tolerance"),
    ("relative_divergence", 0.2, 0.6, "compressibility", "the material compresses"),
    # the paper's Example 1 (d = 1e-3, h = 0.125) loses 2.2 % of its volume
    ("volume_change", -0.022, -0.06, "compressibility", "formulation = \"mixed\""),
    ("product_yield_ratio", 0.95, 1.05, "drawability", "not drawable"),
    ("free_surface_crossing", 0.08, 0.98, "free_surface_crossing",
     "refine discretisation.mesh_size"),
    ("force_balance_residual", 0.02, 0.62, "force_balance", "solver.force_tolerance"),
])
def test_graded_checks_warn_then_fail(key, warn, fail, check, phrase):
    warned, failed = findings(**{key: warn})[check], findings(**{key: fail})[check]
    assert not warned.failure and failed.failure
    assert phrase in failed.message


def test_penetration_is_named_as_the_cause_of_compression():
    found = findings(die_penetration=0.083, relative_divergence=1.32)
    assert found["compressibility"].failure
    assert "the die lets the workpiece through" in found["compressibility"].message


def test_a_yielding_product_and_no_contact_fail():
    assert findings(exit_zone_rate_ratio=3.9)["exit_zone"].failure  # measured at 60 % reduction
    assert findings(die_contact_fraction=0.0)["die_contact"].failure


def test_work_outside_the_rate_window_warns():
    found = check_run({**NORMAL, "dissipation_above_rate2": 0.2, "dissipation_below_rate1": 0.6},
                      SCENE)
    messages = [f.message for f in found if f.check == "rate_window"]
    assert len(messages) == 2 and not any(f.failure for f in found)
    assert "Raise material.rate2" in messages[0] and "Lower material.rate1" in messages[1]


def test_ill_conditioned_solves_warn():
    assert not findings(solve_error_estimate=1e-5)["solve_accuracy"].failure


def test_the_force_balance_advice_fits_a_stopped_iteration():
    """An annealed steel wire drawn at 0.94 of its stock's yield stress stopped ill-conditioned
    with its x forces 4.7 % apart, and was told to set solver.force_tolerance "so the iteration
    goes on until they balance": it had not converged at all (docs/sanity.md)."""
    converged = findings(force_balance_residual=0.047)["force_balance"].message
    assert "solver.force_tolerance" in converged and "stopped" not in converged
    stopped = {f.check: f for f in check_run({**NORMAL, "force_balance_residual": 0.047}, SCENE,
                                             converged=False)}["force_balance"].message
    assert "4.7 %" in stopped and "iteration stopped before they balance" in stopped
    assert "force_tolerance" not in stopped and "direct" not in stopped


def test_the_penetration_advice_fits_the_contact_settings():
    """Issue 34: an unconverged Newton run with the default augmented contact was told to "leave
    penalty.d_N out and penalty.augmented at its default", which it did."""
    pure = scene_from_dict({"process": {"kind": "drawing"}, "penalty": {"augmented": False}})
    message = check_run({**NORMAL, "die_penetration": 0.03}, pure)[0].message
    assert "penalty.augmented = true" in message
    unconverged = check_run({**NORMAL, "die_penetration": 0.03}, SCENE, converged=False)[0].message
    assert "had not settled when the iteration stopped" in unconverged
    assert "leave penalty.d_N out" not in unconverged


def test_a_viscous_law_is_named_as_why_the_product_deforms_after_the_die():
    """Issue 34: far outside (4.5)'s rate window the product stretches like a fluid, and the
    reason told the user to reduce the reduction, the die angle or the friction."""
    found = check_run({**NORMAL, "dissipation_above_rate2": 1.0, "exit_zone_rate_ratio": 1.14},
                      SCENE)
    failure = next(f for f in found if f.failure)
    assert failure.cause and "viscous at this velocity" in failure.message
    assert "material.rate2" in failure.message and "reduce the reduction" not in failure.message


def test_an_overdrawn_wire_is_not_drawable_and_called_a_wire():
    wire = scene_from_dict({"process": {"kind": "drawing"},
                            "geometry": {"symmetry": "axisymmetric"}})
    found = check_run({**NORMAL, "product_yield_ratio": 0.991, "exit_zone_rate_ratio": 4.75,
                       "reduction": 0.64}, wire)
    assert found[0].failure and found[0].cause
    assert found[0].message.startswith("not drawable") and "drawn wire" in found[0].message
    assert "strip" not in found[0].message


HOT = {"max_temperature": 760.0, "min_temperature": 690.0,
       "energy_balance": {"residual": 2e-4, "global_residual": 6e-4}}
HOT_DICT = {
    "process": {"kind": "extrusion", "velocity": 5.0},
    "geometry": {"die": "conical", "symmetry": "axisymmetric", "entry_diameter": 50.0,
                 "exit_diameter": 20.0},
    "material": {"name": "AA6063"}, "discretisation": {"averaging": "quadrature"},
    "units": {"length": "mm", "time": "s", "stress": "MPa", "force": "N"},
    "thermal": {"heat_capacity": 2.98, "conductivity": 201.0, "inflow_temperature": 723.15,
                "container_h": 5.0, "container_temperature": 693.15, "air_h": 0.01}}
HOT_SCENE = scene_from_dict(HOT_DICT)


@pytest.mark.parametrize("changed, check, failure", [
    ({}, None, None),
    ({"max_temperature": 860.0}, "melting", False),   # 0.968 of AA6063's solidus 888 K
    ({"max_temperature": 1675.0}, "melting", True),   # issue 34: 1402 C, converged unflagged
    ({"min_temperature": 290.0}, "temperature_undershoot", False),  # 3 K below the air
    ({"min_temperature": 250.0}, "temperature_undershoot", True),
    ({"energy_balance": {"residual": 2e-4, "global_residual": -0.016}}, "energy_balance", False),
    ({"energy_balance": {"residual": 0.08, "global_residual": 6e-4}}, "energy_balance", True),
])
def test_heat_checks(changed, check, failure):
    found = {f.check: f for f in check_run({**NORMAL, **HOT, **changed}, HOT_SCENE)
             if f.check in ("melting", "temperature_undershoot", "energy_balance")}
    assert HOT_SCENE.thermal.solidus == 888.0 and HOT_SCENE.thermal.coldest == 293.15
    if check is None:
        assert found == {}
    else:
        assert list(found) == [check] and found[check].failure == failure


def test_a_temperature_meant_in_celsius_is_named():
    """A new user's hot strip with units.temperature = "C" and its [thermal] temperatures written
    in Celsius (480, 450 and 20: the run went on at 207 C with the air at -253 C, 364 MPa against
    107 unflagged): the air's 20 K is named, with the 273.15 to add; the hot rod's kelvin are
    not, nor an air temperature the workpiece exchanges no heat with."""
    def celsius_slips(thermal: dict) -> list[str]:
        scene = scene_from_dict({**HOT_DICT, "thermal": {**HOT_DICT["thermal"], **thermal}})
        return [f.message for f in check_run({**NORMAL, **HOT}, scene)
                if f.check == "kelvin_temperature"]

    assert celsius_slips({}) == []
    slips = celsius_slips({"inflow_temperature": 480.0, "container_temperature": 450.0,
                           "air_temperature": 20.0})
    assert len(slips) == 1 and slips[0].startswith("thermal.air_temperature = 20 K is -253.15 C")
    assert "+ 273.15" in slips[0]
    assert celsius_slips({"air_temperature": 20.0, "air_h": 0.0}) == []
    assert len(celsius_slips({"die_temperature": 77.0, "die_h": 10.0})) == 1


def test_a_molten_workpiece_is_refused_before_any_work():
    from forming_fenicsx.core.errors import SceneError
    with pytest.raises(SceneError) as error:
        scene_from_dict({"process": {"kind": "extrusion"},
                         "material": {"name": "AA6063", "temperature": 900.0},
                         "discretisation": {"averaging": "quadrature"},
                         "units": {"stress": "MPa", "time": "s"}})
    assert error.value.key == "material.temperature" and "solidus" in error.value.message
    with pytest.raises(SceneError) as error:
        scene_from_dict({"process": {"kind": "drawing"},
                         "thermal": {"heat_capacity": 3.4, "conductivity": 390.0,
                                     "inflow_temperature": 1400.0, "solidus": 1356.0}})
    assert error.value.key == "thermal.inflow_temperature"


def test_the_friction_factor_on_an_unpressed_die_warns():
    """The factor law's m k on a land the product does not press on: its x-force over the
    product's section against the answer, a warning above 1 % (drawing: over the drawing force;
    extrusion: over the ram force times A1/A0), silent at 0 (Coulomb friction, a die pressed
    everywhere). Example 2's strip (A1/A0 = 1.5/1.625) with its drawing force 70 x 0.75."""
    drawn = {**NORMAL, "drawing_force": 52.5, "contact_end_x": 3.6}
    scene = scene_from_dict({"process": {"kind": "drawing"}, "friction": {"law": "factor",
                                                                          "m": 0.5}})
    checks = {f.check: f for f in check_run({**drawn, "unpressed_friction_force_x": 1.05}, scene)}
    warned = checks["unpressed_friction"]
    assert not warned.failure and "about 2 % of the drawing stress" in warned.message
    assert "x = 3.6" in warned.message and "free_surface.update = true" in warned.message
    quiet = {f.check for f in check_run({**drawn, "unpressed_friction_force_x": 0.5}, scene)}
    assert "unpressed_friction" not in quiet | {f.check for f in check_run(drawn, scene)}
    pushed = scene_from_dict({"process": {"kind": "extrusion"},
                              "friction": {"law": "factor", "m": 0.5}})
    extruded = {**NORMAL, "ram_force": 30.0, "unpressed_friction_force_x": 0.6}
    message = {f.check: f for f in check_run(extruded, pushed)}["unpressed_friction"].message
    assert "about 4 % of the ram pressure" in message  # 0.6 / (30 x 5/10)


def test_the_friction_factor_on_an_unpressed_roll_warns():
    """Rolling's share: the friction factor's torque where the strip does not press on the roll
    over the roll torque (measured 8.0 % on a hot AA6060 strip at m = 0.7, docs/sanity.md)."""
    scene = scene_from_dict({"process": {"kind": "rolling"},
                             "geometry": {"entry_thickness": 2.0, "exit_thickness": 1.6,
                                          "roll_radius": 100.0},
                             "friction": {"law": "factor", "m": 0.7}})
    rolled = {**NORMAL, "roll_torque": 8.13e7, "neutral_angle": 3.3, "bite_angle": 8.6,
              "forward_slip": 0.076}
    found = {f.check: f for f in check_run({**rolled, "unpressed_friction_torque": -6.49e6},
                                           scene)}
    assert "about 8 % of the roll torque" in found["unpressed_friction"].message
    assert "the factor law, unlike" in found["unpressed_friction"].message
    assert "unpressed_friction" not in {
        f.check for f in check_run({**rolled, "unpressed_friction_torque": -5e5}, scene)}
    # sticking's penalised slip does not vanish with the pressure either (15 % on stop 70's steel
    # pass 8 -> 5 mm), and the message names it
    scene.friction = dataclasses.replace(scene.friction, law="sticking", m=0.0, sticks=True)
    message = {f.check: f for f in check_run({**rolled, "unpressed_friction_torque": -6.49e6},
                                             scene)}["unpressed_friction"].message
    assert message.startswith("sticking friction acts") and "and sticking, unlike" in message


def test_friction_at_a_rate_sensitive_metals_shear_strength_warns():
    """Rolling: the share of the friction's torque at the metal's shear strength (measured 83 % on
    a steel pass at m = 1, 52 % capped Coulomb at mu = 0.3; docs/sanity.md) warns above 10 %, with
    the fix of the friction law: d_T halved for the factor law, the cap off for Coulomb's."""
    rolled = {**NORMAL, "roll_torque": 1.7e5, "neutral_angle": 2.9, "bite_angle": 7.0,
              "forward_slip": 0.11}
    for law, fix in (({"law": "factor", "m": 1.0, "sticks": False},
                      "friction.d_T_relative = 0.0005"),
                     ({"mu": 0.3, "shear_limit": True}, "friction.shear_limit = false")):
        scene = scene_from_dict({"process": {"kind": "rolling", "velocity": 1500.0},
                                 "geometry": {"entry_thickness": 8.0, "exit_thickness": 5.0,
                                              "roll_radius": 200.0},
                                 "material": {"law": "rate_power", "A": 150.0, "n": 0.15},
                                 "friction": law})
        found = {f.check: f for f in check_run({**rolled, "friction_at_strength_share": 0.83},
                                               scene)}
        message = found["friction_at_strength"].message
        assert "over 83 % of the friction's torque" in message and fix in message
        assert "d ln sigma_p / d ln rate = 0.15 at the process strain rate" in message
        # the factor law's limit d_T -> 0 at m = 1 is sticking's, m = 1's default on this metal
        # (docs/rolling.md)
        assert ("m = 1 is solved as it by default" in message) is (law.get("law") == "factor")
        assert "friction_at_strength" not in {f.check for f in check_run(
            {**rolled, "friction_at_strength_share": 0.09}, scene)}


def test_a_back_tension_near_the_stocks_yield_stress_is_named():
    """A drawing's back tension over the stock's yield stress in tension: silent at 0.75, a
    warning (and the cause a stopped run leads its reason with) above 0.8; above 1 a failure for a
    stock that does not harden (it stretches without end), a warning for one that hardens (it
    stretches until it carries the tension: the annealed steel wire converged at 1.04)."""
    scene = scene_from_dict({"process": {"kind": "drawing", "applied_force": 100.0}})

    def checked(summary: dict, converged: bool = True) -> dict:
        return {f.check: f for f in check_run({**NORMAL, **summary}, scene, converged)}

    assert "stock_yield" not in checked({"stock_yield_ratio": 0.75})
    warned = checked({"stock_yield_ratio": 0.943})["stock_yield"]
    assert not warned.failure and warned.cause and "0.943 times" in warned.message
    assert "2k)" in warned.message  # Example 2's strip: plane strain, no hardening
    found = checked({"stock_yield_ratio": 1.05})
    assert found["stock_yield"].failure and "no steady drawing" in found["stock_yield"].message
    hardening = {"stock_yield_ratio": 1.05, "mean_entry_strain": 0.0}
    found = checked(hardening)
    assert not found["stock_yield"].failure
    assert "until it hardens" in found["stock_yield"].message
    assert "2k at its entry strain" in found["stock_yield"].message
    assert "free_surface.update" in found["stock_yield"].message
    stopped = checked(hardening, converged=False)
    assert "free_surface.update" not in stopped["stock_yield"].message


def test_a_rolling_back_tension_above_the_stocks_yield_stress_is_named():
    """Rolling's process.back_tension over the stock's 2k: the annealed copper strip demo's 20 MPa
    is 1.57 times it at the strain floor, and its stock crosses its surface before the bite (2.55 %
    of the throughput, entry_speed 2.4 % below exit_speed h1/h0: stop 71). A stock that does not
    harden fails above 1 (it stretches without end)."""
    scene = scene_from_dict({"process": {"kind": "rolling", "back_tension": 20.0},
                             "geometry": {"entry_thickness": 3.0, "exit_thickness": 2.4,
                                          "roll_radius": 75.0}, "friction": {"mu": 0.12}})
    rolled = {**NORMAL, "entry_speed": 0.8, "exit_speed": 1.03, "neutral_x": 1.0,
              "roll_torque": 1.0e4, "free_surface_crossing_stock": 0.0255}
    found = {f.check: f for f in check_run(
        {**rolled, "stock_yield_ratio": 1.57, "mean_entry_strain": 0.0}, scene)}
    warned = found["stock_yield"]
    assert not warned.failure and warned.cause
    assert "process.back_tension = 20 is 1.57 times" in warned.message
    assert "stretches before the rolls" in warned.message and "roll a stronger" in warned.message
    assert "2.55 % of the throughput enters" in warned.message and "entry_speed" in warned.message
    found = {f.check: f for f in check_run({**rolled, "stock_yield_ratio": 1.05}, scene)}
    assert found["stock_yield"].failure and "no steady rolling" in found["stock_yield"].message
    assert "stock_yield" not in {f.check for f in check_run(
        {**rolled, "stock_yield_ratio": 0.43}, scene)}
    # the crossing's causes in rolling: the stock before the bite, not a die's gap
    crossed = {f.check: f for f in check_run({**rolled, "free_surface_crossing": 0.06}, scene)}
    message = crossed["free_surface_crossing"].message
    assert "the stock yields before the bite" in message and "die leaves a gap" not in message


def test_rolling_warns_of_flow_into_the_rolls_from_a_fifth_of_a_percent():
    """The pure penalty lets 0.55 % of a copper slab's throughput (8 -> 5 mm, R = 300 mm) into the
    rolls: its forward slip 9.41 % against the augmented contact's 9.68 %, the roll force 0.7 % low
    (stop 71). Rolling warns above 0.2 %; drawing and extrusion above 1 %."""
    scene = scene_from_dict({"process": {"kind": "rolling"},
                             "geometry": {"entry_thickness": 8.0, "exit_thickness": 5.0,
                                          "roll_radius": 300.0}, "friction": {"mu": 0.3}})
    rolled = {**NORMAL, "entry_speed": 0.8, "exit_speed": 1.09, "neutral_x": 1.0,
              "roll_torque": 1.0e4}

    def checked(penetration: float, on: object = scene) -> dict:
        return {f.check: f for f in check_run({**rolled, "die_penetration": penetration}, on)}

    assert "die_penetration" not in checked(0.0015)
    warned = checked(0.0055)["die_penetration"]
    assert not warned.failure and "0.55 % of the throughput flows into the rolls" in warned.message
    assert "forward slip" in warned.message and "penalty.augmented = true" in warned.message
    drawing = scene_from_dict({"process": {"kind": "drawing"}})
    assert "die_penetration" not in checked(0.0055, drawing)


def test_a_hardening_strain_that_runs_away_is_named():
    """A hardening law's largest strain gained against the ideal strain ln(A0/A1): at most 4.4
    times it on the demos and their variants (a cold rod at m = 0.8), silent there; a warning above
    5, a failure (and a cause) above 10: annealed copper through a square die converged with 29
    times it at the die's corner and twice the ram pressure (test_hardening.py). A strain below the
    entry's by more than half the ideal strain (-29.5 there) warns of the transport's
    undershoot. A stopped run's strain beyond any flow's (4e27, the iterate of a wire stopped on
    Debian 13) is the iterate's: named, but not as the cause, which the iteration's reason gives."""
    scene = scene_from_dict({"process": {"kind": "extrusion"},
                             "material": {"name": "copper_annealed", "initial_strain": 0.3},
                             "units": {"length": "mm", "time": "s", "stress": "MPa"}})
    hardening = {"ideal_strain": 1.27, "max_strain": 0.3 + 4.4 * 1.27, "max_strain_at": [3, 4],
                 "min_strain": 0.3 - 0.4 * 1.27}

    def checked(converged: bool = True, **changed) -> dict:
        return {f.check: f
                for f in check_run({**NORMAL, **hardening, **changed}, scene, converged)}

    assert not {"strain_runaway", "strain_undershoot"} & set(checked())
    warned = checked(max_strain=0.3 + 6 * 1.27)["strain_runaway"]
    assert not warned.failure and warned.cause and "6 times" in warned.message
    failed = checked(max_strain=37.59, max_strain_at=[59.94, 10.12])["strain_runaway"]
    assert failed.failure and "reaches 37.6 at (59.94, 10.12), 29.4 times" in failed.message
    assert f"A = {scene.reference_flow_stress:.4g}, n = 0.001" in failed.message
    stopped = checked(False, max_strain=37.59)["strain_runaway"]
    assert stopped.cause and "material that barely moves" in stopped.message
    for garbage in (3.96e27, math.nan):  # a stopped iterate's transport (Debian 13), or none
        found = checked(False, max_strain=garbage)["strain_runaway"]
        assert found.failure and not found.cause
        assert "the stopped iterate's transported strain reaches" in found.message
        assert "dead zone" in found.message and "A = " not in found.message
    assert checked(max_strain=3.96e27)["strain_runaway"].cause  # converged: a flow's runaway
    under = checked(min_strain=-29.5)["strain_undershoot"]
    assert not under.failure and "falls to -29.5" in under.message
    plastic = {f.check for f in check_run({**NORMAL, "max_strain": 99.0}, SCENE)}
    assert "strain_runaway" not in plastic  # no ideal strain: no hardening law


def test_a_tension_no_friction_can_roll_against_is_named():
    """A new user's annealed aluminium strip (demos/aluminium_strip_pass.toml) at front tensions
    of 140 to 170 MPa was told that "the slab solution needs mu above inf" and to raise the
    friction: the tension is above the strip's yield stress in plane-strain tension at the pass's
    mean flow stress (2k = 132.8 MPa), which no friction rolls against. A tension below it keeps
    the slab solution's least mu and the advice to raise the friction."""
    def skidded(front: float, speed: float = 3.0) -> str:
        scene = scene_from_dict({"process": {"kind": "rolling", "front_tension": front},
                                 "geometry": {"entry_thickness": 2.0, "exit_thickness": 1.6,
                                              "roll_radius": 20.0}, "friction": {"mu": 0.05}})
        found = bite({**NORMAL, "entry_speed": speed, "neutral_x": math.nan}, scene)
        assert found.failure and found.cause
        return found.message

    pulled = skidded(2.1)  # the law's k = 1: 2k = 2
    assert "rolls it at no friction coefficient" in pulled and "1.05 and 0 of it" in pulled
    assert "Lower the tensions" in pulled and "Raise the friction" not in pulled
    mild = skidded(0.2)
    assert "the slab solution needs mu above" in mild and "Raise the friction" in mild
    assert "the strip enters at 3 times the rolls' speed" in mild  # the scene's velocity is 1


@pytest.mark.parametrize("speed", [-7.43e5, 66.8])
def test_a_strip_speed_no_strip_has_is_the_iteration_s(speed):
    """The demo strip at a back tension of 150 MPa stopped with "the strip enters at -7.43e+05
    times the rolls' speed", the aluminium pass at a front tension of 155 MPa at 66.8 times: the
    iteration ran away with the strip's speed, and the message says so (stop 68)."""
    scene = scene_from_dict({"process": {"kind": "rolling", "back_tension": 0.3},
                             "geometry": {"entry_thickness": 2.0, "exit_thickness": 1.6,
                                          "roll_radius": 20.0}, "friction": {"mu": 0.2}})
    message = bite({**NORMAL, "entry_speed": speed, "neutral_x": math.nan}, scene).message
    assert f"the iteration ran away with the strip's speed, which it left at {speed:.3g}" in message
    assert "the strip enters at" not in message and "Raise the friction" in message

"""The physical sanity checks (sanity.py) on summaries of a normal run with one number changed: each
check is silent below its thresholds, warns between them and fails above, naming cause and fix."""
import pytest

from forming_fenicsx.sanity import check_run
from forming_fenicsx.scene import scene_from_dict

# measured on Example 2 (mu = 0.2, Q2 reduced, h = 0.05) with the default penalties
NORMAL = {"die_penetration": 2e-5, "relative_divergence": 3e-3, "exit_zone_rate_ratio": 1.5e-5,
          "drawing_stress": 70.0, "free_surface_crossing": 0.019, "die_contact_fraction": 0.8,
          "dissipation_above_rate2": 0.037, "dissipation_below_rate1": 0.01, "solve_error_estimate": 1e-9,
          "product_yield_ratio": 70.0 / 201.0, "force_balance_residual": 2e-5}  # the drawing stress over the strip's 2k, about 201
SCENE = scene_from_dict({"process": {"kind": "drawing"}})


def findings(**changed):
    return {f.check: f for f in check_run({**NORMAL, **changed}, SCENE)}


def test_a_normal_run_passes_every_check():
    assert findings() == {}


@pytest.mark.parametrize("key, warn, fail, check, phrase", [
    ("die_penetration", 0.02, 0.083, "die_penetration", "penalty.d_N"),
    ("relative_divergence", 0.2, 0.6, "compressibility", "the material compresses"),
    ("product_yield_ratio", 0.95, 1.05, "drawability", "not drawable"),
    ("free_surface_crossing", 0.08, 0.98, "free_surface_crossing", "refine discretisation.mesh_size"),
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
    found = check_run({**NORMAL, "dissipation_above_rate2": 0.2, "dissipation_below_rate1": 0.6}, SCENE)
    messages = [f.message for f in found if f.check == "rate_window"]
    assert len(messages) == 2 and not any(f.failure for f in found)
    assert "raise material.rate2" in messages[0] and "Lower material.rate1" in messages[1]


def test_ill_conditioned_solves_warn():
    assert not findings(solve_error_estimate=1e-5)["solve_accuracy"].failure

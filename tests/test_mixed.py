"""The mixed velocity-pressure formulation (Q2 velocity, discontinuous P1 pressure): the d -> 0
limit of the penalty problem (Theorem 3.1) computed directly."""
import pytest

from forming_fenicsx.core.errors import SceneError
from forming_fenicsx.app.run import solve_scene

from conftest import make_scene

DIRECT = {"method": "direct", "force_tolerance": 1e-3, "max_iterations": 1000}


def limit_and_mixed(kind: str, discretisation: dict, d_values: tuple,
                    **sections) -> tuple[list[dict], dict]:
    penalty = [solve_scene(make_scene(process={"kind": kind}, discretisation=discretisation,
                                      penalty={"d": d}, solver=DIRECT, **sections))[2]
               for d in d_values]
    mixed = solve_scene(make_scene(process={"kind": kind},
                                   discretisation={**discretisation, "formulation": "mixed"},
                                   solver=DIRECT, **sections))[2]
    return penalty, mixed


def test_extrusion_mixed_matches_the_penalty_limit():
    """Example 1, h = 0.25 (measured: mixed 2.8029, penalty 2.8192 at d = 1e-5, 1e-7: -0.58 %); the
    mixed pressure is exactly divergence-free against P1 and its ram-face mean is the ram pressure,
    unlike the penalty's p_av at d = 1e-3 (1.63 there, docs/example1.md)."""
    penalty, mixed = limit_and_mixed("extrusion", {"mesh_size": 0.25}, (1e-5, 1e-7))
    # the d -> 0 limit
    assert penalty[0]["ram_pressure"] == pytest.approx(penalty[1]["ram_pressure"], rel=1e-4)
    assert (mixed["converged"]
            and mixed["ram_pressure"] == pytest.approx(penalty[1]["ram_pressure"], rel=0.01))
    assert mixed["discrete_divergence"] < 1e-10 and "discrete_divergence" not in penalty[0]
    assert mixed["mean_hydrostatic_pressure"] == pytest.approx(mixed["ram_pressure"], rel=0.01)
    assert not mixed["warnings"]


def test_drawing_mixed_with_contact_and_friction():
    """Example 2, mu = 0.2, h = 0.1 (measured: mixed 294.81, penalty limit 295.40 at d = 5e-7:
    -0.2 %)."""
    penalty, mixed = limit_and_mixed("drawing", {"mesh_size": 0.1, "element": "Q2",
                                                 "volumetric_integration": "reduced"}, (5e-7,),
                                     friction={"mu": 0.2})
    assert mixed["converged"] and mixed["force_balance_residual"] < 1e-3
    assert mixed["mean_die_pressure"] == pytest.approx(penalty[0]["mean_die_pressure"], rel=0.01)
    assert mixed["discrete_divergence"] < 1e-8


@pytest.mark.parametrize("sections, key", [
    ({"discretisation": {"formulation": "mixed", "element": "Q1"}}, "discretisation.formulation"),
    ({"discretisation": {"formulation": "stokes"}}, "discretisation.formulation"),
])
def test_mixed_scene_checks(sections, key):
    with pytest.raises(SceneError) as error:
        make_scene(**sections)
    assert error.value.key == key


def test_newton_on_the_mixed_formulation():
    """Newton's method on the saddle-point system, Example 1 at h = 0.5 (measured: 14 solves against
    190 for the direct method at delta = 1e-5, ram pressures 2.6607701 and 2.6607735, 1.3e-6 apart,
    0.13 % of the 1e-3 allowed; at delta = 1e-6 319 solves, 2e-9 apart; at h = 0.25, 13 against 537
    solves, 25 s instead of 4 s, 2.6158210 and 2.6158201); every iterate stays discretely
    divergence-free, so the energy remains the line search's merit function."""
    discretisation = {"mesh_size": 0.5, "formulation": "mixed", "averaging": "quadrature"}
    newton = solve_scene(make_scene(discretisation=discretisation, solver={"method": "newton"}))[2]
    direct = solve_scene(make_scene(discretisation=discretisation, solver={
        "method": "direct", "tolerance": 1e-5, "max_iterations": 1000}))[2]
    assert newton["converged"] and newton["linear_solves"] <= 15
    assert newton["ram_pressure"] == pytest.approx(direct["ram_pressure"], rel=1e-3)
    assert newton["discrete_divergence"] < 1e-10

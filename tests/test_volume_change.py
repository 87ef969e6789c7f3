"""summary.json's volume_change (post/diagnostics.py): int div u dx over the throughput equals the
net flux through the whole boundary (plane and axisymmetric), is O(d) under the penalty and zero
up to rounding under the mixed formulation (docs/outputs.md, docs/free_surface.md)."""
from pathlib import Path

import pytest
import ufl

from forming_fenicsx.app.run import solve_scene
from forming_fenicsx.config.loader import load_scene
from forming_fenicsx.post.flux import throughput
from forming_fenicsx.post.integrals import integrate

DEMOS = Path(__file__).resolve().parents[1] / "demos"
COARSE = ["discretisation.mesh_size=0.1"]


def _change_and_net_flux(demo: str, changes: list[str]) -> tuple[float, float]:
    problem, _, summary = solve_scene(load_scene(DEMOS / demo, changes))
    assert summary["converged"]
    net = integrate(problem, ufl.dot(problem.u, problem.n) * problem.ds) / throughput(problem)
    return summary["volume_change"], net


@pytest.mark.parametrize("demo, changes", [("example2_drawing.toml", COARSE),
                                           ("copper_wire.toml", [])])
def test_the_volume_change_is_the_net_flux_through_the_boundary(demo, changes):
    """The divergence theorem, with the axisymmetric weights (the round wire, -7.2e-7 measured)."""
    change, net = _change_and_net_flux(demo, changes)
    assert change != 0.0 and change == pytest.approx(net, abs=1e-12)


def test_the_penalty_changes_the_volume_by_order_d():
    """Example 2 (h = 0.1) with the paper's d = 0.005: -5.6e-4 of the throughput (the strip is
    compressed in the die), -3.2e-4 with d halved (the pressure changes with d too, measured)."""
    paper = _change_and_net_flux("example2_drawing.toml", COARSE)[0]
    halved = _change_and_net_flux("example2_drawing.toml", COARSE + ["penalty.d=0.0025"])[0]
    assert -1e-3 < paper < -2e-4
    assert 0.45 < halved / paper < 0.7


def test_the_mixed_formulation_keeps_the_volume():
    """The same strip on Q2 with the discontinuous linear pressure: 3e-15 measured, against the
    penalty's 5.6e-4."""
    change = _change_and_net_flux("example2_drawing.toml", COARSE + [
        "discretisation.element=Q2", "discretisation.formulation=mixed"])[0]
    assert abs(change) < 1e-12

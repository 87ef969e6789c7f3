"""Flow-stress laws (4.5) and the pure power law: values, condition (2.10), rejection of bad constants."""
import math

import numpy as np
import pytest

from forming_fenicsx.errors import SceneError
from forming_fenicsx.material import PiecewisePowerLaw, PowerLaw


def test_piecewise_power_law_branches():
    law = PiecewisePowerLaw(A=2.0, alpha=0.2, rate1=1e-2, rate2=1e2)
    rates = np.array([1e-4, 1e-2, 1.0, 1e2, 1e4])
    expected = [2.0 * 1e-2**0.2 / 1e-2 * 1e-4, 2.0 * 1e-2**0.2, 2.0, 2.0 * 1e2**0.2, 2.0 * 1e2**0.2 / 1e2 * 1e4]
    assert np.allclose(law.flow_stress(rates), expected, rtol=1e-14)


def test_power_law_floor_relative_to_the_process_rate():
    law = PowerLaw(A=3.0, n=0.5).resolve(100.0)
    assert (law.rate_floor, law.rate_floor_relative) == (pytest.approx(1e-4, rel=1e-12), 1e-6)
    with pytest.raises(SceneError, match="both"):
        PowerLaw(rate_floor=1e-4, rate_floor_relative=1e-6).resolve(1.0)


def test_power_law_floor():
    law = PowerLaw(A=3.0, n=0.5, rate_floor=1e-4)
    assert law.flow_stress(np.array([4.0]))[0] == pytest.approx(6.0, rel=1e-14)
    assert law.secant(np.array([0.0]))[0] == pytest.approx(3.0 * 1e-4**-0.5, rel=1e-14)


@pytest.mark.parametrize("law", [PiecewisePowerLaw(), PiecewisePowerLaw(alpha=1.0), PowerLaw(n=0.3).resolve(1.0)])
def test_condition_2_10(law):
    """eta1 <= sigma_p' <= sigma_p/rate <= eta2: sigma_p increasing and the secant non-increasing."""
    rates = np.logspace(-8, 6, 2001)
    sigma, secant = law.flow_stress(rates), law.secant(rates)
    slope = np.diff(sigma) / np.diff(rates)
    assert np.all(slope > 0)
    assert np.all(np.diff(secant) <= 1e-12 * secant[:-1])
    assert np.all(slope <= secant[:-1] * (1 + 1e-9))
    assert math.isfinite(secant.max())


@pytest.mark.parametrize("law, key", [(PiecewisePowerLaw(alpha=1.5), "material.alpha"),
                                      (PiecewisePowerLaw(alpha=0.0), "material.alpha"),
                                      (PiecewisePowerLaw(A=-1.0), "material.A"),
                                      (PiecewisePowerLaw(rate1=0.0), "material.rate1"),
                                      (PiecewisePowerLaw(rate1=10.0, rate2=1.0), "material.rate2"),
                                      (PowerLaw(n=1.2), "material.n"),
                                      (PowerLaw(rate_floor=0.0), "material.rate_floor")])
def test_laws_breaking_2_10_are_rejected(law, key):
    with pytest.raises(SceneError) as error:
        law.check()
    assert error.value.key == key


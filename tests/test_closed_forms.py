"""Closed-form drawing loads against the published worked examples (round-products reference, section 2)."""
from __future__ import annotations

import math

import pytest

from forming_fenicsx.closed_forms import (avitzur_drawing_stress, avitzur_optimum_angle,
                                          avitzur_optimum_angle_approx, central_burst_indicator,
                                          sachs_drawing_stress)


def test_dieter_worked_example():
    """K = 1300 MPa, n = 0.3, 20 % reduction, 6 degrees, mu = 0.09, Y = K eps1^n/(1 + n): 240.4-240.6 MPa."""
    eps1 = -math.log(0.8)
    mean_flow_stress = 1300 * eps1**0.3 / 1.3
    assert mean_flow_stress * sachs_drawing_stress(0.2, 6.0, 0.09) == pytest.approx(240.5, abs=0.1)


def test_sachs_frictionless_limit_and_back_tension():
    assert sachs_drawing_stress(0.3, 10.0, 0.0) == pytest.approx(-math.log(0.7), rel=1e-14)
    assert sachs_drawing_stress(0.3, 10.0, 1e-9) == pytest.approx(-math.log(0.7), rel=1e-7)  # O(B)
    # back tension sigma_b adds sigma_b (A1/A0)^B
    b = 0.1 / math.tan(math.radians(8.0))
    assert (sachs_drawing_stress(0.25, 8.0, 0.1, 0.2) - sachs_drawing_stress(0.25, 8.0, 0.1)
            == pytest.approx(0.2 * 0.75**b, rel=1e-12))


def test_avitzur_optimum():
    """20 % reduction, m = 0.1: optimum about 7.4 degrees at sigma/sigma0 about 0.42 (reference)."""
    angle = avitzur_optimum_angle(0.2, 0.1)
    assert angle == pytest.approx(7.4, abs=0.05)
    assert avitzur_optimum_angle_approx(0.2, 0.1) == pytest.approx(7.41, abs=0.01)
    assert avitzur_drawing_stress(0.2, angle, 0.1) == pytest.approx(0.422, abs=0.001)
    # the bound exceeds the ideal work ln(A0/A1) and grows with the land
    assert avitzur_drawing_stress(0.2, 10.0, 0.0) > -math.log(0.8)
    assert avitzur_drawing_stress(0.2, 10.0, 0.1, land=0.5) == pytest.approx(
        avitzur_drawing_stress(0.2, 10.0, 0.1) + 2 / math.sqrt(3) * 0.1 * 0.5, rel=1e-12)


def test_central_burst_indicator():
    alpha = math.radians(6.0)
    assert central_burst_indicator(0.2, 6.0, True) == pytest.approx(alpha / 0.2 * (1 + math.sqrt(0.8)) ** 2)
    assert central_burst_indicator(0.2, 6.0, False) == pytest.approx(alpha / 0.2 * 1.8)

"""Measurement helpers."""
import math

import pytest

from forming_fenicsx.core.report import markdown_table
from forming_fenicsx.core.richardson import richardson


def test_richardson_recovers_a_known_limit():
    sizes = [0.4, 0.2, 0.1]
    values = [2.0 + 3.0 * h**1.5 for h in sizes]
    limit, order = richardson(sizes, values)
    assert limit == pytest.approx(2.0, rel=1e-12) and order == pytest.approx(1.5, rel=1e-12)
    assert math.isnan(richardson(sizes, [1.0, 2.0, 1.5])[0])


def test_markdown_table():
    text = markdown_table("T", ["a", "b"], [[1.234567, "x"]])
    assert text.splitlines()[-1] == "| 1.2346 | x |"
    assert markdown_table("T", ["a"], []) == ""

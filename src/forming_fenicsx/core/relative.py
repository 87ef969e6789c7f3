"""Values with units given absolute or relative to one of the scene's scales (sections.Scales)."""
from __future__ import annotations

import math
from typing import Any

from forming_fenicsx.core.errors import SceneError


def check_positive(key: str, value: float | None) -> None:
    """A value that must be > 0 when it is given."""
    if value is not None and not value > 0:
        raise SceneError(key, f"must be a finite number > 0; got {value}")


def resolve_pair(section: str, table: Any, key: str, scale: float, default: float
                 ) -> tuple[float, float]:
    """The absolute value of ``table.key`` and its relative value ``table.key_relative``
    (= key / scale), from whichever the table gives, else from the default relative value."""
    name, absolute, relative = (f"{section}.{key}", getattr(table, key),
                                getattr(table, f"{key}_relative"))
    if absolute is not None and relative is not None:
        raise SceneError(name, f"give {name} (absolute) or {name}_relative, not both")
    check_positive(name, absolute)
    check_positive(f"{name}_relative", relative)
    if absolute is None:
        absolute = (default if relative is None else relative) * scale
    if not (math.isfinite(scale) and scale > 0 and math.isfinite(absolute) and absolute > 0):
        raise SceneError(name, f"its scale {scale:g} (from the scene's velocity, size and flow "
                         f"stress) makes it {absolute:g}: give {name} or check the material's "
                         "flow stress and the process data")
    return absolute, absolute / scale


def set_pair(section: str, table: Any, key: str, scale: float, default: float) -> None:
    """resolve_pair, written into the (mutable) table."""
    absolute, relative = resolve_pair(section, table, key, scale, default)
    setattr(table, key, absolute)
    setattr(table, f"{key}_relative", relative)

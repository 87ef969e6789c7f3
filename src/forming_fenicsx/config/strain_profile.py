"""The equivalent strain across a section, y from the axis (or the strip's mid-plane) to the
surface: the "hardness profile" a hardening run writes for its product (exit_strain.csv: the
strain along the streamlines, the outermost two elements' mean at the surface,
exit_profiles.exit_strain_profile), read back as the inflow strain of the next pass
(``material.initial_strain_file``), so a pass schedule is a sequence of runs.

File: CSV with the header ``y,equivalent_strain`` (units in brackets after a name are allowed, as
the run writes them: ``y [mm]``), y rising from 0 to the half-size of the section.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from forming_fenicsx.core.csv_table import read_rows
from forming_fenicsx.core.errors import SceneError

HEADER = ("y", "equivalent_strain")


def read_strain_profile(path: str | Path, key: str) -> np.ndarray:
    """The (y, eps) rows of a strain-profile CSV, (N, 2). Refused, naming ``key`` and the row: a
    missing file, another header, fewer than two rows, a value that is not a finite number, y not
    rising from 0, or a negative strain."""
    name = Path(path).name
    points: list[list[float]] = []
    for number, values in read_rows(path, key, HEADER):
        if values[1] < 0:
            raise SceneError(key, f"{name} row {number}: the strain {values[1]} must be >= 0")
        if (not points and values[0] != 0) or (points and values[0] <= points[-1][0]):
            raise SceneError(key, f"{name} row {number}: y = {values[0]} must rise from 0")
        points.append(values)
    if len(points) < 2:
        raise SceneError(key, f"{name}: needs at least two rows; got {len(points)}")
    return np.array(points)


def check_section(profile: np.ndarray, half_size: float, key: str) -> None:
    """The profile must span the entry section: its last y within 2 % of the entry half-size (a
    previous pass's exit is this pass's entry)."""
    if abs(profile[-1, 0] / half_size - 1) > 0.02:
        raise SceneError(key, f"the profile spans y = 0 to {profile[-1, 0]:.6g}, the entry section "
                              f"0 to {half_size:.6g}: it must be the strain across this entry (the "
                              "previous pass's exit size is this pass's entry size)")


def profile_values(profile: np.ndarray, y: np.ndarray, half_size: float) -> np.ndarray:
    """The strain at heights y of a section of ``half_size``, linear between the rows, the profile
    stretched to end where the section does (the sizes agree within 2 %, check_section)."""
    return np.interp(y * profile[-1, 0] / half_size, profile[:, 0], profile[:, 1])


def section_mean(profile: np.ndarray, round_section: bool) -> float:
    """The profile's mean over its section: int eps dy / Y across a strip, 2 int eps y dy / Y^2
    across a round section of radius Y (trapezoidal between the rows)."""
    y, strain = profile[:, 0], profile[:, 1]
    weight = strain * y if round_section else strain
    integral = float(np.sum(0.5 * (weight[1:] + weight[:-1]) * np.diff(y)))
    return 2 * integral / y[-1] ** 2 if round_section else integral / y[-1]

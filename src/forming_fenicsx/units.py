"""Units of a scene: labels of a consistent unit system, with no conversion.

A scene may use any consistent system: a length unit L, a time unit T and a stress unit S, with
velocities in L/T, strain rates in 1/T, forces in S L^2 (a strip's per unit width: S L, unless the
scene gives its width) and the
material constants in the units their law implies (e.g. A of sigma_p = A rate^n in S T^n). The
``[units]`` section names them so that summary.json, the CSV headers and the figures say what the
numbers are; known names are checked for consistency (force = stress x length^2).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

from .errors import SceneError

# SI factors of the unit names the consistency check knows; other names are taken as labels only
LENGTHS = {"m": 1.0, "cm": 1e-2, "mm": 1e-3, "um": 1e-6, "µm": 1e-6, "km": 1e3, "in": 0.0254, "ft": 0.3048}
TIMES = {"s": 1.0, "ms": 1e-3, "min": 60.0, "h": 3600.0}
STRESSES = {"Pa": 1.0, "kPa": 1e3, "MPa": 1e6, "GPa": 1e9, "N/mm2": 1e6, "N/mm^2": 1e6, "N/m2": 1.0,
            "N/m^2": 1.0, "bar": 1e5, "psi": 6894.757293168361, "ksi": 6894757.293168361}
FORCES = {"N": 1.0, "kN": 1e3, "MN": 1e6, "lbf": 4.4482216152605, "kip": 4448.2216152605, "kgf": 9.80665}

# the dimension of every quantity a run reports, by its key in summary.json and the CSV files
DIMENSIONS = {
    "ram_pressure": "stress", "mean_hydrostatic_pressure": "stress", "drawing_stress": "stress",
    "mean_die_pressure": "stress", "ram_force": "force_per_width", "drawing_force": "force_per_width",
    "die_force_x": "force_per_width", "die_normal_force_x": "force_per_width",
    "die_friction_force_x": "force_per_width", "applied_force_x": "force_per_width",
    "die_separation_force": "force_per_width",
    "contact_length": "length", "contact_end_x": "length", "divergence_l2": "velocity",
    "s": "length", "x": "length", "y": "length", "contact_pressure": "stress",
    "averaged_normal_stress": "stress", "friction_stress": "stress", "velocity": "velocity",
    "strain_rate": "strain_rate", "flow_stress": "stress", "length": "length",
    "mean_flow_stress": "stress", "product_flow_stress": "stress", "temperature": "temperature",
    "mean_exit_temperature": "temperature", "max_exit_temperature": "temperature",
    "min_exit_temperature": "temperature", "min_temperature": "temperature",
    "max_temperature": "temperature",
}


@dataclass
class Units:
    """Labels of the scene's consistent unit system: ``length``, ``time``, ``stress``, ``force`` (each
    optional; no conversion is done). Example: mm, s, MPa, N; m, s, Pa, N; in, s, psi, lbf."""

    length: str | None = None
    time: str | None = None
    stress: str | None = None
    force: str | None = None

    def check(self) -> None:
        """Reject empty labels and a force unit that is not stress x length^2 (for known names)."""
        for key in ("length", "time", "stress", "force"):
            value = getattr(self, key)
            if value is not None and not value.strip():
                raise SceneError(f"units.{key}", "must be a non-empty label (or left out)")
        if self.length in LENGTHS and self.stress in STRESSES and self.force in FORCES:
            implied = STRESSES[self.stress] * LENGTHS[self.length] ** 2
            if not math.isclose(FORCES[self.force], implied, rel_tol=1e-6):
                raise SceneError("units.force",
                                 f"{self.force} is not {self.stress} x {self.length}^2 (= {implied:.6g} N): the "
                                 f"units are not consistent; use {self._consistent_force()} or other units")

    def _consistent_force(self) -> str:
        implied = STRESSES[self.stress] * LENGTHS[self.length] ** 2
        names = [name for name, value in FORCES.items() if math.isclose(value, implied, rel_tol=1e-6)]
        return names[0] if names else f"a force unit of {implied:.6g} N"

    @property
    def given(self) -> bool:
        return any(getattr(self, key) is not None for key in ("length", "time", "stress", "force"))

    def label(self, dimension: str) -> str | None:
        """The unit of a dimension (length, time, stress, force, velocity, strain_rate, force_per_width,
        temperature), or None when the labels it needs are not given."""
        length, time, stress, force = self.length, self.time, self.stress, self.force
        if force is None and stress is not None and length is not None:
            force = f"{stress}*{length}^2"
        composed = {
            "length": length, "time": time, "stress": stress, "force": force,
            "velocity": f"{length}/{time}" if length and time else None,
            "strain_rate": f"1/{time}" if time else None,
            "force_per_width": f"{force}/{length}" if force and length else None,
            "temperature": "K",  # kelvin in every system ([thermal], thermal.py)
        }
        return composed.get(dimension)

    def labelled(self, text: str, dimension: str) -> str:
        """An axis label: ``text [unit]`` when the unit of the dimension is known, else ``text``."""
        unit = self.label(dimension)
        return f"{text} [{unit}]" if unit else text

    def column(self, name: str) -> str:
        """A CSV header: ``name [unit]`` for a quantity of DIMENSIONS when its unit is known, else ``name``."""
        return self.labelled(name, DIMENSIONS.get(name, ""))

    @staticmethod
    def dimension(key: str, whole_forces: bool = False) -> str:
        """The dimension of a reported quantity ("" when unknown); ``whole_forces``: the forces
        are forces (a round product's, a strip's of a given width), not per unit width."""
        found = DIMENSIONS.get(key, "")
        return "force" if whole_forces and found == "force_per_width" else found

    def summary(self, keys: list[str], whole_forces: bool = False) -> dict[str, object]:
        """What summary.json says of the units: the labels, and the unit of each reported quantity
        (``whole_forces`` as in ``dimension``)."""
        if not self.given:
            return {"system": "not given: any consistent system ([units] names it; README, 'Units')"}

        quantities = {key: self.label(self.dimension(key, whole_forces))
                      for key in keys if key in DIMENSIONS}
        return {"length": self.length, "time": self.time, "stress": self.stress, "force": self.force,
                "quantities": {key: unit for key, unit in quantities.items() if unit}}

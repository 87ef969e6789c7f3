"""Units of a scene: labels of a consistent unit system, with no conversion.

A scene may use any consistent system: a length unit L, a time unit T and a stress unit S, with
velocities in L/T, strain rates in 1/T, forces in S L^2 (a strip's per unit width: S L, unless the
scene gives its width) and the material constants in the units their law implies (e.g. A of
sigma_p = A rate^n in S T^n). The ``[units]`` section names them so that summary.json, the CSV
headers and the figures say what the numbers are; known names are checked for consistency
(force = stress x length^2).

Temperatures are kelvin in the scene, the solver and summary.json; ``temperature = "C"`` shows them
in Celsius in the figures and beside the kelvin column of the CSV files. A figure shows stresses
far from 1 in the scene's unit (e.g. 1.2e8 Pa) in another unit of its family (120 MPa). Every such
difference between the numbers stored and those shown is here.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from forming_fenicsx.core.errors import SceneError

# SI factors of the unit names the consistency check knows; other names are taken as labels only
LENGTHS = {"m": 1.0, "cm": 1e-2, "mm": 1e-3, "um": 1e-6, "µm": 1e-6, "km": 1e3, "in": 0.0254,
           "ft": 0.3048}
TIMES = {"s": 1.0, "ms": 1e-3, "min": 60.0, "h": 3600.0}
STRESSES = {"Pa": 1.0, "kPa": 1e3, "MPa": 1e6, "GPa": 1e9, "N/mm2": 1e6, "N/mm^2": 1e6,
            "N/m2": 1.0, "N/m^2": 1.0, "bar": 1e5, "psi": 6894.757293168361,
            "ksi": 6894757.293168361}
FORCES = {"N": 1.0, "kN": 1e3, "MN": 1e6, "lbf": 4.4482216152605, "kip": 4448.2216152605,
          "kgf": 9.80665}
# the stress units a figure may change to within a family, and the range of the largest value that
# keeps the scene's own unit
STRESS_FAMILIES = (("Pa", "kPa", "MPa", "GPa"), ("psi", "ksi"))
READABLE = (1e-2, 1e4)
# units.temperature: the kelvin at zero of each unit figures and CSV files may show temperatures in
TEMPERATURE_ZEROS = {"K": 0.0, "C": 273.15}

# the dimension of every quantity a run reports, by its key in summary.json and the CSV files
DIMENSIONS = {
    "ram_pressure": "stress", "mean_hydrostatic_pressure": "stress", "drawing_stress": "stress",
    "mean_die_pressure": "stress", "ram_force": "force_per_width",
    "drawing_force": "force_per_width",
    "die_force_x": "force_per_width", "die_normal_force_x": "force_per_width",
    "die_friction_force_x": "force_per_width", "applied_force_x": "force_per_width",
    "die_separation_force": "force_per_width", "die_side_force": "force_per_width",
    "contact_area": "area", "entry_section_area": "area", "exit_section_area": "area",
    "z": "length",
    "contact_length": "length", "contact_end_x": "length", "divergence_l2": "velocity",
    "s": "length", "x": "length", "y": "length", "contact_pressure": "stress",
    "averaged_normal_stress": "stress", "friction_stress": "stress", "velocity": "velocity",
    "strain_rate": "strain_rate", "flow_stress": "stress", "length": "length",
    "mean_flow_stress": "stress", "product_flow_stress": "stress", "temperature": "temperature",
    "mean_exit_temperature": "temperature", "max_exit_temperature": "temperature",
    "min_exit_temperature": "temperature", "min_temperature": "temperature",
    "max_temperature": "temperature",
    "roll_force": "force_per_width", "roll_torque": "torque_per_width",
    "roll_power": "power_per_width", "entry_speed": "velocity", "exit_speed": "velocity",
    "neutral_x": "length", "shear_stress": "stress", "slip": "velocity",
    "max_strain_at": "length",
}
# a quantity per unit width of a strip, and what it is for the strip of a given width
WHOLE = {"force_per_width": "force", "torque_per_width": "torque", "power_per_width": "power"}


def bracketed(text: str, unit: str | None) -> str:
    """``text [unit]``, or ``text`` when the unit is not known."""
    return f"{text} [{unit}]" if unit else text


@dataclass
class Units:
    """Labels of the scene's consistent unit system: ``length``, ``time``, ``stress``, ``force``
    (each optional; no conversion is done). Example: mm, s, MPa, N; m, s, Pa, N; in, s, psi, lbf.
    ``temperature`` ("K", the default, or "C") is the unit figures and CSV files show temperatures
    in; they stay kelvin everywhere else."""

    length: str | None = None
    time: str | None = None
    stress: str | None = None
    force: str | None = None
    temperature: str | None = None

    def check(self) -> None:
        """Reject empty labels, a temperature unit other than K and C, and a force unit that is not
        stress x length^2 (for known names)."""
        for key in ("length", "time", "stress", "force"):
            value = getattr(self, key)
            if value is not None and not value.strip():
                raise SceneError(f"units.{key}", "must be a non-empty label (or left out)")
        if self.temperature is not None and self.temperature not in TEMPERATURE_ZEROS:
            raise SceneError("units.temperature", 'must be "K" or "C" (the unit of the figures and '
                             "CSV files; the scene's temperatures stay kelvin); got "
                             f"{self.temperature!r}")
        if self.length in LENGTHS and self.stress in STRESSES and self.force in FORCES:
            implied = STRESSES[self.stress] * LENGTHS[self.length] ** 2
            if not math.isclose(FORCES[self.force], implied, rel_tol=1e-6):
                raise SceneError("units.force",
                                 f"{self.force} is not {self.stress} x {self.length}^2 "
                                 f"(= {implied:.6g} N): the units are not consistent; use "
                                 f"{self._consistent_force()} or other units")

    def _consistent_force(self) -> str:
        implied = STRESSES[self.stress] * LENGTHS[self.length] ** 2
        names = [name for name, value in FORCES.items()
                 if math.isclose(value, implied, rel_tol=1e-6)]
        return names[0] if names else f"a force unit of {implied:.6g} N"

    @property
    def given(self) -> bool:
        """Whether the scene names a unit of its consistent system (length, time, stress,
        force)."""
        return any(getattr(self, key) is not None for key in ("length", "time", "stress", "force"))

    @property
    def shown_temperature(self) -> str:
        """The unit figures and CSV files show temperatures in."""
        return self.temperature or "K"

    def shown(self, dimension: str, values: np.ndarray,
              largest: float | None = None) -> tuple[np.ndarray, str | None]:
        """Values of a dimension as a figure shows them, and their unit: temperatures (kelvin) in
        units.temperature; stresses whose largest magnitude (``largest``, else that of the values)
        lies outside READABLE in the unit of the scene's family that brings it into 1 to 1000 (an
        axis in Pa then reads 120 MPa, not 1.2 with "1e8" above it); anything else unchanged."""
        values = np.asarray(values, dtype=float)
        if dimension == "temperature":
            unit = self.shown_temperature
            return values - TEMPERATURE_ZEROS[unit], unit
        unit = self.label(dimension)
        family = next((f for f in STRESS_FAMILIES if unit in f), None) \
            if dimension == "stress" else None
        if largest is None:
            largest = float(np.nanmax(np.abs(values), initial=0.0))
        if family is None or largest == 0 or READABLE[0] <= largest < READABLE[1]:
            return values, unit
        magnitude = largest * STRESSES[unit]
        fitting = [name for name in family if STRESSES[name] <= magnitude]
        target = max(fitting, key=STRESSES.get) if fitting else family[0]
        return values * (STRESSES[unit] / STRESSES[target]), target

    def columns(self, name: str, values: np.ndarray) -> list[tuple[str, np.ndarray]]:
        """A CSV file's columns of a quantity: ``name [unit]`` with the values as computed, and for
        a temperature shown in another unit than kelvin, the values in it beside them."""
        columns = [(self.column(name), np.asarray(values, dtype=float))]
        if DIMENSIONS.get(name) == "temperature" and self.shown_temperature != "K":
            shown, unit = self.shown("temperature", values)
            columns.append((f"{name} [{unit}]", shown))
        return columns

    def label(self, dimension: str) -> str | None:
        """The unit of a dimension (length, area, time, stress, force, velocity, strain_rate,
        force_per_width, torque and power, and each per width, temperature), or None when the
        labels it needs are not given."""
        length, time, stress, force = self.length, self.time, self.stress, self.force
        if force is None and stress is not None and length is not None:
            force = f"{stress}*{length}^2"
        composed = {
            "length": length, "time": time, "stress": stress, "force": force,
            "velocity": f"{length}/{time}" if length and time else None,
            "strain_rate": f"1/{time}" if time else None,
            "force_per_width": f"{force}/{length}" if force and length else None,
            "torque": f"{force}*{length}" if force and length else None,
            "torque_per_width": f"{force}*{length}/{length}" if force and length else None,
            "power": f"{force}*{length}/{time}" if force and length and time else None,
            "power_per_width": (f"{force}*{length}/{time}/{length}" if force and length and time
                                else None),
            "area": f"{length}^2" if length else None,
            "temperature": "K",  # kelvin in every system ([thermal], thermal.py)
        }
        return composed.get(dimension)

    def labelled(self, text: str, dimension: str) -> str:
        """An axis label: ``text [unit]`` when the unit of the dimension is known, else ``text``."""
        return bracketed(text, self.label(dimension))

    def column(self, name: str) -> str:
        """A CSV header: ``name [unit]`` for a quantity of DIMENSIONS when its unit is known, else
        ``name``."""
        return self.labelled(name, DIMENSIONS.get(name, ""))

    @staticmethod
    def dimension(key: str, whole_forces: bool = False) -> str:
        """The dimension of a reported quantity ("" when unknown); ``whole_forces``: the forces
        are forces (a round product's, a strip's of a given width), not per unit width."""
        found = DIMENSIONS.get(key, "")
        return WHOLE.get(found, found) if whole_forces else found

    def summary(self, keys: list[str], whole_forces: bool = False) -> dict[str, object]:
        """What summary.json says of the units: the labels, and the unit of each reported quantity
        (``whole_forces`` as in ``dimension``); with temperatures, ``temperature`` "K"
        (summary.json's) and ``temperature_shown`` when the figures and CSV files show them in
        another unit."""
        temperatures = {}  # summary.json's temperatures are kelvin, whatever the figures show
        if self.temperature is not None or "temperature" in {DIMENSIONS.get(key) for key in keys}:
            temperatures["temperature"] = "K"
            if self.shown_temperature != "K":
                temperatures["temperature_shown"] = self.shown_temperature
        if not self.given:
            return {"system": "not given: any consistent system ([units] names it; README, "
                              "'Units')", **temperatures}

        quantities = {key: self.label(self.dimension(key, whole_forces))
                      for key in keys if key in DIMENSIONS}
        return {"length": self.length, "time": self.time, "stress": self.stress,
                "force": self.force,
                **temperatures,
                "quantities": {key: unit for key, unit in quantities.items() if unit}}

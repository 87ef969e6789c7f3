"""The named materials a scene cites by ``material.name``, and the flow law of a [material] table.

A named material's values are in MPa (and 1/s for a hot-working law's A), converted to the
scene's units; any key of the scene's [material] table overrides the named one. ``SOLIDUS`` gives
where each named material melts.
"""
from __future__ import annotations

import dataclasses
import math
from typing import Any

from forming_fenicsx.config.coercion import build_section
from forming_fenicsx.core.errors import SceneError
from forming_fenicsx.core.units import STRESSES, TIMES
from forming_fenicsx.physics.flow_laws import LAWS, FlowLaw, PiecewisePowerLaw

# Cold working: Hollomon's K (MPa) and n; hot working: Sellars-Tegart in MPa, 1/s and J/mol
# (in_scene_units converts them)
MATERIALS: dict[str, dict] = {
    "copper_annealed": {"law": "hollomon", "K": 315.0, "n": 0.54},
    "low_carbon_steel_annealed": {"law": "hollomon", "K": 530.0, "n": 0.26},
    "aluminium_1100_O": {"law": "hollomon", "K": 180.0, "n": 0.20},
    "aluminium_6061_O": {"law": "hollomon", "K": 205.0, "n": 0.20},
    "aluminium_2024_T4": {"law": "hollomon", "K": 690.0, "n": 0.16},
    "stainless_304_annealed": {"law": "hollomon", "K": 1275.0, "n": 0.45},
    "AA6063": {"law": "sellars_tegart", "alpha_s": 0.040, "n": 5.385, "Q": 141550.0,
               "A": math.exp(22.5)},
    "AA6060": {"law": "sellars_tegart", "alpha_s": 0.035, "n": 4.67, "Q": 161000.0,
               "A": 7.6301e10},
}
_HANDBOOK = ("Kalpakjian & Schmid, Manufacturing Engineering and Technology, Table 2.3 "
             "(room temperature)")
MATERIAL_SOURCES = {**{name: _HANDBOOK for name, values in MATERIALS.items()
                       if values["law"] == "hollomon"},
                    "AA6063": "Sheppard, Extrusion of Aluminium Alloys (1999), Table 4.1",
                    "AA6060": "Verlinden (1993)"}
# Solidus temperatures (K) of the named materials: a [thermal] run whose workpiece passes it melts
# (ASM Handbook Vol. 2, Properties of Wrought Aluminum and Aluminum Alloys; ASM Metals Handbook
# Desk Edition: copper's melting point, carbon and 304 stainless steels' solidus)
SOLIDUS = {"copper_annealed": 1356.0, "low_carbon_steel_annealed": 1768.0,
           "aluminium_1100_O": 916.0, "aluminium_6061_O": 855.0, "aluminium_2024_T4": 775.0,
           "stainless_304_annealed": 1673.0, "AA6063": 888.0, "AA6060": 858.0}


def in_scene_units(name: str, units: dict[str, Any]) -> dict[str, Any]:
    """The named material's values (MPa, 1/s) in the scene's units.stress and units.time: Hollomon's
    K over the stress unit's MPa, Sellars-Tegart's alpha_s times it and A times the time unit's
    seconds (a rate in 1/min is 60 times the rate in 1/s). A unit the consistency check does not
    know (a label only) cannot be converted and is refused."""
    values = dict(MATERIALS[name])
    stress = units.get("stress")
    if stress not in STRESSES:
        raise SceneError("material.name", f"{name} is given in MPa: the scene needs a stress unit "
                         f"to convert it to ({', '.join(STRESSES)}; got units.stress = {stress!r})")
    per_mpa = STRESSES["MPa"] / STRESSES[stress]  # the scene's stress units in one MPa
    if values["law"] == "hollomon":
        values["K"] *= per_mpa
    else:
        time = units.get("time")
        if time not in TIMES:
            raise SceneError("material.name", f"{name}'s A is given in 1/s: the scene needs a "
                             f"time unit to convert it to ({', '.join(TIMES)}; got units.time = "
                             f"{time!r})")
        values["alpha_s"] /= per_mpa
        values["A"] *= TIMES[time]
    return values


def build_material(table: dict[str, Any], defaults: dict[str, Any],
                   units: dict[str, Any]) -> FlowLaw:
    """The flow law of [material]: ``law`` and its keys, or a named material (``name``, its values
    converted to the scene's units: in_scene_units) whose keys, in the scene's units, the table
    overrides."""
    name = table.get("name")
    if name is not None:
        if not isinstance(name, str) or name not in MATERIALS:
            raise SceneError("material.name",
                             f"must be one of {', '.join(MATERIALS)}; got {name!r}")
        table = {**in_scene_units(name, units), **table}
    law = table.get("law", PiecewisePowerLaw.law)
    if law == "power":
        raise SceneError("material.law", '"power" is now "rate_power": sigma = A rate^n, a '
                         'strain-rate law without hardening; strain hardening K eps^n is '
                         '"hollomon"')
    if not isinstance(law, str) or law not in LAWS:
        raise SceneError("material.law", f"must be one of {', '.join(LAWS)}; got {law!r}")
    names = {f.name for f in dataclasses.fields(LAWS[law])}
    return build_section(LAWS[law], table, "material",
                         {k: v for k, v in defaults.items() if k in names})

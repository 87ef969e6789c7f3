"""Reading a scene: the TOML file, ``--set section.key=value`` overrides, and the checked
:class:`Scene` built from the parsed document (loaded, resolved, checked before any meshing)."""
from __future__ import annotations

import dataclasses
import math
import tomllib
from pathlib import Path
from typing import Any

from forming_fenicsx.config.coercion import build_section, key_name
from forming_fenicsx.config.geometry import (ConicalExtrusionGeometry, DrawingGeometry,
                                             ExtrusionGeometry)
from forming_fenicsx.config.materials import build_material
from forming_fenicsx.config.roll_gap import RollingGeometry
from forming_fenicsx.config.scene import Scene
from forming_fenicsx.config.sections import (PROCESSES, Accuracy, Discretisation, FreeSurface,
                                             Friction, Output, Penalty, Process, Solver, Thermal)
from forming_fenicsx.core.errors import SceneError
from forming_fenicsx.core.units import Units

# Each process's defaults over the dataclass ones: the paper's process data (Example 1 and
# Example 2). Example 2's Q1 elements with complete integration lock (docs/example2.md): the drawing
# default is Q2 with reduced integration, as for extrusion; the demo scenes name the paper's.
PROCESS_DEFAULTS: dict[str, dict[str, dict[str, Any]]] = {
    "extrusion": {},
    "drawing": {
        "process": {"velocity": 1000.0, "drive": "pull"},
        "material": {"A": 100 * math.sqrt(3.0)},
    },
    # rolling (docs/rolling.md): Newton, the pure-penalty contact, and the x forces balanced to
    # 1e-4: the torque is the difference of the friction on both sides of the neutral point, off
    # by 2 % with the increment's rule alone and by 0.1 % at 1e-3 (Coulomb's cap at k: Scene)
    "rolling": {
        "solver": {"method": "newton", "force_tolerance": 1e-4},
        "discretisation": {"averaging": "quadrature"},
        "penalty": {"augmented": False},
    },
}
# The geometry of each process and geometry.die (the first is the default)
GEOMETRIES = {"extrusion": {"square": ExtrusionGeometry, "conical": ConicalExtrusionGeometry},
              "drawing": {"conical": DrawingGeometry}, "rolling": {"rolls": RollingGeometry}}
# The sections a scene may have (thermal only when it computes the temperature)
SECTIONS = ("process", "geometry", "material", "friction", "penalty", "discretisation", "solver",
            "output", "units", "thermal", "accuracy", "free_surface")


def geometry_class(kind: str, table: dict[str, Any]) -> type:
    """The geometry class that geometry.die names for the process."""
    dies = GEOMETRIES[kind]
    die = table.get("die", next(iter(dies)))
    if not isinstance(die, str) or die not in dies:
        raise SceneError("geometry.die",
                         f"must be one of {', '.join(dies)} for {kind}; got {die!r}")
    keys = {name: {field.name for field in dataclasses.fields(cls)} for name, cls in dies.items()}
    for key in table:
        other = next((name for name in dies if key in keys[name] - keys[die]), None)
        if other is not None:  # e.g. a die angle for the square die
            given = "" if "die" in table else f" ({kind}'s default)"
            raise SceneError(f"geometry.{key}", f"belongs to geometry.die = {other!r}; this "
                             f"scene's die is {die!r}{given}: set geometry.die = {other!r}")
    return dies[die]


def scene_from_dict(data: dict[str, Any]) -> Scene:
    """Build and check a scene from a parsed TOML document."""
    unknown = sorted(set(data) - set(SECTIONS))
    if unknown:
        raise SceneError(key_name(unknown[0]),
                         f"unknown section; allowed sections: {', '.join(SECTIONS)}")
    for name in SECTIONS:
        if name in data and not isinstance(data[name], dict):
            raise SceneError(name, f"must be a table ([{name}]); got {data[name]!r}")
    tables = {name: data.get(name, {}) for name in SECTIONS}
    if "kind" not in tables["process"]:
        raise SceneError("process.kind", f"missing; must be one of {', '.join(PROCESSES)}")
    kind = tables["process"]["kind"]
    if not isinstance(kind, str) or kind not in PROCESSES:
        raise SceneError("process.kind", f"must be one of {', '.join(PROCESSES)}; got {kind!r}")
    defaults = PROCESS_DEFAULTS[kind]
    if "roll_rpm" in tables["process"] and "velocity" in tables["process"]:
        raise SceneError("process.roll_rpm", "give the rolls' surface speed (process.velocity) or "
                         "their revolutions per minute (process.roll_rpm), not both")
    if kind == "rolling" and "drive" in tables["process"]:
        raise SceneError("process.drive", "does not apply to rolling: the rolls drive the strip "
                         "(process.velocity is their surface speed)")
    process = build_section(Process, tables["process"], "process", defaults.get("process"))
    process.check()
    classes = {"geometry": geometry_class(kind, tables["geometry"]), "friction": Friction,
               "penalty": Penalty, "discretisation": Discretisation, "solver": Solver,
               "output": Output, "units": Units, "accuracy": Accuracy,
               "free_surface": FreeSurface}
    built = {name: build_section(cls, tables[name], name, defaults.get(name))
             for name, cls in classes.items()}
    if "thermal" in data:  # heat transfer only when the scene asks for it
        if kind != "extrusion":
            for key in ("container_h", "container_temperature"):
                if key in tables["thermal"]:
                    raise SceneError(f"thermal.{key}", f"{kind} has no container; leave it out")
        built["thermal"] = build_section(Thermal, tables["thermal"], "thermal")
    material = build_material(tables["material"], defaults.get("material", {}), tables["units"])
    scene = Scene(process=process, material=material, **built)
    if "method" not in tables["solver"] and scene.coupled:
        scene.solver.method = "newton"  # docs/hardening.md: 11 to 15 solves against 18 to 933
    if "averaging" not in tables["discretisation"] and (
            scene.solver.method == "newton" or scene.coupled):
        scene.discretisation.averaging = "quadrature"
    scene.resolve()
    scene.check()
    return scene


def parse_override(text: str) -> tuple[list[str], Any]:
    """Split ``section.key=value``; the value is read as TOML, else taken as a bare string."""
    if "=" not in text:
        raise SceneError(text, "an override must look like section.key=value")
    path, raw = text.split("=", 1)
    keys = path.strip().split(".")
    if len(keys) < 2 or not all(keys):
        raise SceneError(path, "an override must name section.key")
    if not raw.strip():
        raise SceneError(path, "missing value after '='")
    try:
        value = tomllib.loads(f"v = {raw}")["v"]
    except tomllib.TOMLDecodeError:
        value = raw.strip()
    return keys, value


# a material named or a law other than the scene's starts a fresh [material]: the scene's own
# parameters (a law's A beside a named material's, say) belong to the material they replace
MATERIAL_IDENTITY = ("name", "law")


def apply_overrides(data: dict[str, Any], overrides: list[str]) -> dict[str, Any]:
    """Apply ``--set section.key=value`` overrides to a parsed scene document; ``material.name`` or
    ``material.law`` set to another value than the scene's replaces its [material] section by the
    ``material.*`` overrides given."""
    parsed = [parse_override(text) for text in overrides]
    material = data.get("material")
    if isinstance(material, dict) and any(
            len(keys) == 2 and keys[0] == "material" and keys[1] in MATERIAL_IDENTITY
            and material.get(keys[1]) != value for keys, value in parsed):
        data["material"] = {}
    for keys, value in parsed:
        table = data
        for depth, key in enumerate(keys[:-1]):
            table = table.setdefault(key, {})
            if not isinstance(table, dict):
                raise SceneError(".".join(keys[: depth + 1]), "is a value, not a table")
        table[keys[-1]] = value
    return data


def read_scene_data(path: str | Path, overrides: list[str] | None = None) -> dict[str, Any]:
    """Read a scene file and apply overrides, without validating; a relative mesh_file,
    die_profile_file or initial_strain_file is taken relative to the scene file."""
    path = Path(path)
    try:
        data = tomllib.loads(path.read_text())
    except FileNotFoundError:
        raise SceneError(str(path), "scene file not found") from None
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise SceneError(str(path), f"not valid TOML: {exc}") from None
    data = apply_overrides(data, overrides or [])
    geometry = data.get("geometry")
    for key in ("mesh_file", "die_profile_file"):  # relative to the scene file
        if isinstance(geometry, dict) and isinstance(geometry.get(key), str):
            geometry[key] = str(path.parent / geometry[key])
    material = data.get("material")
    if isinstance(material, dict) and isinstance(material.get("initial_strain_file"), str):
        material["initial_strain_file"] = str(path.parent / material["initial_strain_file"])
    return data


def load_scene(path: str | Path, overrides: list[str] | None = None) -> Scene:
    """Read, override and validate a scene file."""
    return scene_from_dict(read_scene_data(path, overrides))

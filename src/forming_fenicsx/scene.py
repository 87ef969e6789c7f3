"""Scenes: the TOML input that says everything about one run, validated before any meshing.

A scene has the sections ``process``, ``geometry``, ``material``, ``friction``, ``penalty``,
``discretisation``, ``solver`` and ``output``. Every value has a default (the paper's value for the
process); :func:`load_scene` rejects unknown keys, mistyped or non-physical values with a
:class:`SceneError` that names the key and what is allowed.
"""
from __future__ import annotations

import dataclasses
import json
import math
import tomllib
import types
import typing
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from .errors import SceneError
from .material import LAWS, FlowLaw, PiecewisePowerLaw

PROCESSES = ("extrusion", "drawing")


@dataclass
class Process:
    """What is formed and how: the process velocity u_N^0 on Gamma1 (2.5) and the force F_N on Gamma5 (2.7).

    ``drive`` says where the velocity is prescribed: "pull" at the exit face (drawing), "push" at the
    entry face (extrusion's ram). F_N acts on the other end face, which is free without it.
    """

    kind: str = "extrusion"
    velocity: float = 1.0
    applied_force: float | None = None
    drive: str = "push"

    def check(self) -> None:
        if self.kind not in PROCESSES:
            raise SceneError("process.kind", f"must be one of {', '.join(PROCESSES)}; got {self.kind!r}")
        if not (math.isfinite(self.velocity) and self.velocity > 0):
            raise SceneError("process.velocity", f"must be a finite number > 0; got {self.velocity}")
        if self.applied_force is not None and not math.isfinite(self.applied_force):
            raise SceneError("process.applied_force", f"must be a finite number; got {self.applied_force}")
        if self.drive not in ("push", "pull"):
            raise SceneError("process.drive", f"must be one of push, pull; got {self.drive!r}")


def _check_strip(geometry, positive: tuple[str, ...]) -> None:
    """Lengths finite and > 0, a die that reduces the thickness, an existing .msh file if one is named."""
    if geometry.mesh_file is not None:
        path = Path(geometry.mesh_file)
        if path.suffix != ".msh" or not path.is_file():
            raise SceneError("geometry.mesh_file", f"must name an existing Gmsh .msh file; got {geometry.mesh_file!r}")
    for key in positive:
        value = getattr(geometry, key)
        if not (math.isfinite(value) and value > 0):
            raise SceneError(f"geometry.{key}", f"must be a finite number > 0; got {value}")
    if geometry.exit_thickness >= geometry.entry_thickness:
        raise SceneError("geometry.exit_thickness",
                         f"must be < geometry.entry_thickness ({geometry.entry_thickness}): "
                         f"the die must reduce; got {geometry.exit_thickness}")


class _Strip:
    """What every strip geometry (full thicknesses entry_thickness > exit_thickness) shares.

    ``mesh_file`` names a Gmsh .msh file to use instead of the built-in geometry; its boundary roles
    are the physical groups named gamma1_velocity ... gamma6_symmetry (as `forming mesh` writes them).
    """

    exit_thickness: float
    mesh_file: str | None

    @property
    def thinnest(self) -> float:
        """Half-thickness of the thinnest section (the half model's exit)."""
        return 0.5 * self.exit_thickness


@dataclass
class ExtrusionGeometry(_Strip):
    """Plane-strain extrusion through a square die (Example 1); full thicknesses, half model built."""

    length: float = 20.0
    entry_thickness: float = 10.0
    exit_thickness: float = 5.0
    die_position: float = 10.0
    mesh_file: str | None = None

    def check(self) -> None:
        _check_strip(self, ("length", "entry_thickness", "exit_thickness", "die_position"))
        if self.die_position >= self.length:
            raise SceneError("geometry.die_position",
                             f"must be < geometry.length ({self.length}); got {self.die_position}")


@dataclass
class DrawingGeometry(_Strip):
    """Plane-strain strip drawing through a conical die with a land (Example 2); full thicknesses.

    The strip meets the die at x = die_entry; the die face falls at the semi-angle die_angle (degrees)
    to the exit half-thickness, then runs parallel for land_length.
    """

    length: float = 7.8
    entry_thickness: float = 1.625
    exit_thickness: float = 1.5
    die_angle: float = 6.0
    land_length: float = 0.15
    die_entry: float = 3.0
    mesh_file: str | None = None

    def check(self) -> None:
        _check_strip(self, ("length", "entry_thickness", "exit_thickness", "die_entry"))
        if not (math.isfinite(self.die_angle) and 0 < self.die_angle < 90):
            raise SceneError("geometry.die_angle", f"must lie in (0, 90) degrees (the semi-angle); got {self.die_angle}")
        if not (math.isfinite(self.land_length) and self.land_length >= 0):
            raise SceneError("geometry.land_length", f"must be a finite number >= 0; got {self.land_length}")
        if self.die_exit >= self.length:
            raise SceneError("geometry.land_length",
                             f"the die (entry at {self.die_entry}, cone {self.cone_length:.4g} long, land "
                             f"{self.land_length}) must end before geometry.length ({self.length})")

    @property
    def cone_length(self) -> float:
        """Axial length of the conical die face."""
        return 0.5 * (self.entry_thickness - self.exit_thickness) / math.tan(math.radians(self.die_angle))

    @property
    def die_exit(self) -> float:
        """x at the end of the land."""
        return self.die_entry + self.cone_length + self.land_length


NORMAL_STRESSES = ("averaged", "local")


@dataclass
class Friction:
    """Coulomb friction on Gamma3 (2.9), regularised by d_T (3.11).

    The bound tau_f = mu * sigma_N-bar uses the averaged (mollified) normal stress over
    ``mollification_length`` (default: the mesh size), or the local penalty stress of (3.4).
    """

    mu: float = 0.0
    d_T: float = 1e-6
    normal_stress: str = "averaged"
    mollification_length: float | None = None

    def check(self) -> None:
        if not (math.isfinite(self.mu) and self.mu >= 0):
            raise SceneError("friction.mu", f"must be a finite number >= 0; got {self.mu}")
        if not (math.isfinite(self.d_T) and self.d_T > 0):
            raise SceneError("friction.d_T", f"must be a finite number > 0; got {self.d_T}")
        if self.normal_stress not in NORMAL_STRESSES:
            raise SceneError("friction.normal_stress",
                             f"must be one of {', '.join(NORMAL_STRESSES)}; got {self.normal_stress!r}")
        length = self.mollification_length
        if length is not None and not (math.isfinite(length) and length > 0):
            raise SceneError("friction.mollification_length", f"must be a finite number > 0; got {length}")


@dataclass
class Penalty:
    """Penalty constants of (3.4): volumetric d and contact d_N."""

    d: float = 1e-3
    d_N: float = 1e-6

    def check(self) -> None:
        for key in ("d", "d_N"):
            value = getattr(self, key)
            if not (math.isfinite(value) and value > 0):
                raise SceneError(f"penalty.{key}", f"must be a finite number > 0; got {value}")


@dataclass
class Discretisation:
    """Element, incompressibility (penalty (3.5) with complete or reduced quadrature of the volumetric
    term, or a mixed velocity-pressure formulation: Q2 velocity with discontinuous P1 pressure, the
    limit d -> 0 of Theorem 3.1), mesh size and grading toward the die corner."""

    element: str = "Q2"
    volumetric_integration: str = "reduced"
    mesh_size: float = 0.5
    corner_grading: float = 4.0
    averaging: str = "nodes"
    formulation: str = "penalty"

    def check(self) -> None:
        choices = {"element": ("Q1", "Q2"), "volumetric_integration": ("reduced", "complete"),
                   "averaging": ("nodes", "centres", "quadrature"), "formulation": ("penalty", "mixed")}
        for key, allowed in choices.items():
            if getattr(self, key) not in allowed:
                raise SceneError(f"discretisation.{key}",
                                 f"must be one of {', '.join(allowed)}; got {getattr(self, key)!r}")
        if not (math.isfinite(self.mesh_size) and self.mesh_size > 0):
            raise SceneError("discretisation.mesh_size", f"must be a finite number > 0; got {self.mesh_size}")
        if not (math.isfinite(self.corner_grading) and 1 <= self.corner_grading <= 1e3):
            raise SceneError("discretisation.corner_grading",
                             "must lie in [1, 1000] (ratio of the largest to the smallest element "
                             f"on a graded edge; 1 is uniform); got {self.corner_grading}")

    @property
    def degree(self) -> int:
        return int(self.element[1])


@dataclass
class Solver:
    """Nonlinear iteration: the secant-modulus methods direct (3.13) or modified (3.33), or Newton's
    method after ``secant_start`` direct iterates (newton.py, both formulations); all stopped by the rule
    of (4.4).

    ``dual_start``: Newton's dual stress at the switch from the secant iterates, as a fraction of
    tau(u); below 1 it keeps the first Newton step's stiffness along the flow direction at about
    (1 - dual_start) times the secant's instead of alpha times (docs/solvers.md).
    ``stall_window``: inner iterations (a fifth of it for outer ones) without a new smallest increment
    after which the run stops as stalled or oscillating. ``force_tolerance`` (0: off, as in the
    paper) also requires the x force balance residual
    to fall below it before the run counts as converged: a small increment is not a small error.
    """

    method: str = "modified"
    tolerance: float = 1e-4
    secant_start: int = 3
    dual_start: float = 0.99
    max_iterations: int = 200
    max_outer_iterations: int = 50
    stall_window: int = 40
    reference_strain_rate: float | None = None
    force_tolerance: float = 0.0
    petsc_options: dict[str, Any] = field(default_factory=lambda: {
        "ksp_type": "preonly", "pc_factor_mat_solver_type": "mumps"})

    def check(self) -> None:
        if self.method not in ("direct", "modified", "newton"):
            raise SceneError("solver.method", f"must be one of direct, modified, newton; got {self.method!r}")
        if not (isinstance(self.secant_start, int) and self.secant_start >= 0):
            raise SceneError("solver.secant_start", f"must be an integer >= 0; got {self.secant_start!r}")
        start = self.dual_start
        if isinstance(start, bool) or not (isinstance(start, (int, float)) and 0 <= start <= 1):
            raise SceneError("solver.dual_start",
                             f"must lie in [0, 1] (a fraction of the stress); got {self.dual_start!r}")
        if not (math.isfinite(self.tolerance) and 0 < self.tolerance < 1):
            raise SceneError("solver.tolerance", f"must lie in (0, 1) (delta of (4.4)); got {self.tolerance}")
        for key in ("max_iterations", "max_outer_iterations", "stall_window"):
            if getattr(self, key) < 1:
                raise SceneError(f"solver.{key}", f"must be an integer >= 1; got {getattr(self, key)}")
        if not (math.isfinite(self.force_tolerance) and 0 <= self.force_tolerance < 1):
            raise SceneError("solver.force_tolerance", f"must lie in [0, 1) (0: off); got {self.force_tolerance}")
        rate = self.reference_strain_rate
        if rate is not None and not (math.isfinite(rate) and rate > 0):
            raise SceneError("solver.reference_strain_rate", f"must be a finite number > 0; got {rate}")
        for key, value in self.petsc_options.items():
            if not isinstance(value, (str, int, float, bool)):
                raise SceneError(f"solver.petsc_options.{key}",
                                 f"must be a string, number or boolean; got {type(value).__name__}")


DIE_PRESSURES = ("penalty", "stress")


@dataclass
class Output:
    """What a run writes besides summary.json and history.csv, and how the die pressure is measured.

    ``die_pressure``: the contact pressure from the penalty (3.4) u_N^+/d_N, or from the stress
    -n.sigma.n; ``die_entry_trim``: length of die face after the die entry left out of q_av.
    """

    fields: bool = True
    figures: bool = True
    die_pressure: str = "penalty"
    die_entry_trim: float = 0.0

    def check(self) -> None:
        if self.die_pressure not in DIE_PRESSURES:
            raise SceneError("output.die_pressure",
                             f"must be one of {', '.join(DIE_PRESSURES)}; got {self.die_pressure!r}")
        if not (math.isfinite(self.die_entry_trim) and self.die_entry_trim >= 0):
            raise SceneError("output.die_entry_trim", f"must be a finite number >= 0; got {self.die_entry_trim}")


GEOMETRIES = {"extrusion": ExtrusionGeometry, "drawing": DrawingGeometry}

# The paper's constants for each process (Example 1 and Example 2), over the dataclass defaults.
PROCESS_DEFAULTS: dict[str, dict[str, dict[str, Any]]] = {
    "extrusion": {},
    "drawing": {
        "process": {"velocity": 1000.0, "drive": "pull"},
        "material": {"A": 100 * math.sqrt(3.0)},
        "penalty": {"d": 0.005, "d_N": 0.01},
        "discretisation": {"element": "Q1", "volumetric_integration": "complete", "mesh_size": 0.05,
                           "corner_grading": 1.0},
    },
}


@dataclass
class Scene:
    """One run, fully specified."""

    process: Process
    geometry: ExtrusionGeometry | DrawingGeometry
    material: FlowLaw
    friction: Friction
    penalty: Penalty
    discretisation: Discretisation
    solver: Solver
    output: Output

    def check(self) -> None:
        """Checks of each section, then of values that are valid alone but not together."""
        for section in dataclasses.fields(self):
            getattr(self, section.name).check()
        if self.solver.method == "newton" and self.discretisation.averaging != "quadrature":
            raise SceneError("solver.method", 'newton differentiates G at the integration points: it needs '
                             f'discretisation.averaging = "quadrature"; got {self.discretisation.averaging!r}')
        if self.discretisation.formulation == "mixed" and self.discretisation.element != "Q2":
            raise SceneError("discretisation.formulation", "mixed uses Q2 velocity with discontinuous P1 "
                             f'pressure: it needs discretisation.element = "Q2"; got {self.discretisation.element!r}')
        if self.discretisation.mesh_size > self.geometry.thinnest:
            raise SceneError("discretisation.mesh_size",
                             f"must be <= the thinnest half-thickness ({self.geometry.thinnest}) so that "
                             f"at least one element spans it; got {self.discretisation.mesh_size}")

    @property
    def mollification_length(self) -> float:
        """Length of the normal-stress averaging: the scene's, else about one element."""
        given = self.friction.mollification_length
        return given if given is not None else self.discretisation.mesh_size

    @property
    def reference_strain_rate(self) -> float:
        """Strain rate of the uniform starting modulus: the scene's, else velocity over entry thickness."""
        given = self.solver.reference_strain_rate
        return given if given is not None else self.process.velocity / self.geometry.entry_thickness

    @property
    def reference_flow_stress(self) -> float:
        """sigma_p at the reference strain rate: the stress scale of the process."""
        return float(self.material.flow_stress([self.reference_strain_rate])[0])

    def to_dict(self) -> dict[str, Any]:
        """Every resolved value, section by section."""
        return {f.name: dataclasses.asdict(getattr(self, f.name)) for f in dataclasses.fields(self)}


def _typename(tp: Any) -> str:
    names = {float: "a number", int: "an integer", str: "a string", bool: "true or false", dict: "a table"}
    args = [a for a in typing.get_args(tp) if a is not type(None)]
    if args:
        return " or ".join(_typename(a) for a in args)
    return names.get(typing.get_origin(tp) or tp, str(tp))


def _coerce(key: str, value: Any, tp: Any) -> Any:
    """Check a TOML value against a field type; integers are accepted where numbers are."""
    origin = typing.get_origin(tp)
    if origin in (typing.Union, types.UnionType):
        for option in typing.get_args(tp):
            if option is type(None):
                continue
            try:
                return _coerce(key, value, option)
            except SceneError:
                pass
        raise SceneError(key, f"must be {_typename(tp)}; got {value!r}")
    base = origin or tp
    ok = {float: isinstance(value, (int, float)) and not isinstance(value, bool),
          int: isinstance(value, int) and not isinstance(value, bool),
          bool: isinstance(value, bool), str: isinstance(value, str), dict: isinstance(value, dict)}[base]
    if not ok:
        raise SceneError(key, f"must be {_typename(tp)}; got {value!r}")
    if base is float:
        return float(value)
    if base is dict:
        return dict(value)
    return value


def _build(cls: type, table: dict[str, Any], section: str, defaults: dict[str, Any] | None = None) -> Any:
    hints = typing.get_type_hints(cls)
    fields = {f.name: f for f in dataclasses.fields(cls)}
    unknown = sorted(set(table) - set(fields))
    if unknown:
        raise SceneError(f"{section}.{key_name(unknown[0])}",
                         f"unknown key; allowed keys in [{section}]: {', '.join(fields)}")
    values = dict(defaults or {})
    for key, value in table.items():
        value = _coerce(f"{section}.{key}", value, hints[key])
        if isinstance(value, dict):  # a table is merged over the default one, key by key
            default = values.get(key, fields[key].default_factory())
            value = {**default, **value}
        values[key] = value
    return cls(**values)


def key_name(name: Any) -> str:
    """A key as it appears in messages: plain names as they are, anything else quoted."""
    return name if isinstance(name, str) and name.isidentifier() else json.dumps(str(name))


def _material(table: dict[str, Any], defaults: dict[str, Any]) -> FlowLaw:
    law = table.get("law", PiecewisePowerLaw.law)
    if not isinstance(law, str) or law not in LAWS:
        raise SceneError("material.law", f"must be one of {', '.join(LAWS)}; got {law!r}")
    names = {f.name for f in dataclasses.fields(LAWS[law])}
    return _build(LAWS[law], table, "material", {k: v for k, v in defaults.items() if k in names})


SECTIONS = ("process", "geometry", "material", "friction", "penalty", "discretisation", "solver", "output")


def scene_from_dict(data: dict[str, Any]) -> Scene:
    """Build and check a scene from a parsed TOML document."""
    unknown = sorted(set(data) - set(SECTIONS))
    if unknown:
        raise SceneError(key_name(unknown[0]), f"unknown section; allowed sections: {', '.join(SECTIONS)}")
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
    process = _build(Process, tables["process"], "process", defaults.get("process"))
    process.check()
    classes = {"geometry": GEOMETRIES[kind], "friction": Friction, "penalty": Penalty,
               "discretisation": Discretisation, "solver": Solver, "output": Output}
    built = {name: _build(cls, tables[name], name, defaults.get(name)) for name, cls in classes.items()}
    scene = Scene(process=process, material=_material(tables["material"], defaults.get("material", {})), **built)
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


def apply_overrides(data: dict[str, Any], overrides: list[str]) -> dict[str, Any]:
    """Apply ``--set section.key=value`` overrides to a parsed scene document."""
    for text in overrides:
        keys, value = parse_override(text)
        table = data
        for depth, key in enumerate(keys[:-1]):
            table = table.setdefault(key, {})
            if not isinstance(table, dict):
                raise SceneError(".".join(keys[: depth + 1]), "is a value, not a table")
        table[keys[-1]] = value
    return data


def read_scene_data(path: str | Path, overrides: list[str] | None = None) -> dict[str, Any]:
    """Read a scene file and apply overrides, without validating; a relative mesh_file is taken
    relative to the scene file."""
    path = Path(path)
    try:
        data = tomllib.loads(path.read_text())
    except FileNotFoundError:
        raise SceneError(str(path), "scene file not found") from None
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise SceneError(str(path), f"not valid TOML: {exc}") from None
    data = apply_overrides(data, overrides or [])
    geometry = data.get("geometry")
    if isinstance(geometry, dict) and isinstance(geometry.get("mesh_file"), str):
        geometry["mesh_file"] = str(path.parent / geometry["mesh_file"])  # relative to the scene file
    return data


def load_scene(path: str | Path, overrides: list[str] | None = None) -> Scene:
    """Read, override and validate a scene file."""
    return scene_from_dict(read_scene_data(path, overrides))

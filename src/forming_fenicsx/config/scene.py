"""Scenes: the TOML input that says everything about one run, validated before any meshing.

A scene has the sections ``process``, ``geometry``, ``material``, ``friction``, ``penalty``,
``discretisation``, ``solver``, ``output`` and ``units``, and ``thermal`` when it computes the
temperature. Every value has a default; :func:`load_scene`
rejects unknown keys, mistyped, non-finite or non-physical values with a :class:`SceneError` that names
the key and what is allowed.

Values with units that are not physical data (penalties, regularisations, mesh size, lengths left out)
default to multiples of the scene's own scales (:class:`Scales`: the process velocity, the entry
thickness and the flow stress at the process strain rate) and are turned into absolute values when the
scene is resolved, so that a scene gives the same dimensionless answer in any consistent unit system.
The paper's absolute values stay available: a scene that gives ``penalty.d`` uses it as it is.
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
from typing import Any, ClassVar

from forming_fenicsx.core.errors import SceneError
from forming_fenicsx.physics.material import LAWS, MATERIALS, SOLIDUS, FlowLaw, PiecewisePowerLaw
from forming_fenicsx.config.strain_profile import check_section, read_strain_profile
from forming_fenicsx.physics.coordinates import SYMMETRIES
from forming_fenicsx.config.die_profile import DieProfile, parametric_profile, polyline_profile, read_profile_csv
from forming_fenicsx.config.mesh_file import mesh_dimensions
from forming_fenicsx.core.relative import check_positive, set_pair
from forming_fenicsx.core.units import Units

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


class _Strip:
    """What every strip geometry (full thicknesses entry_thickness > exit_thickness) shares.

    Lengths left out are the paper's example geometry (``PAPER``) scaled by entry_thickness over the
    paper's; the length left out keeps the paper's (scaled) length after the die. ``mesh_file`` names a Gmsh
    .msh file to use instead of the built-in geometry: its roles are the physical groups named
    gamma1_velocity ... gamma6_symmetry (as `forming mesh` writes them), and the thicknesses and length
    are read from it (scene values that disagree with it are rejected; die data do not apply).
    """

    PAPER: ClassVar[dict[str, float]]
    DIE_KEYS: ClassVar[tuple[str, ...]]
    width: float | None
    LENGTH_KEY: ClassVar[str]  # the key named when the die does not fit in the strip
    entry_thickness: float | None
    exit_thickness: float | None
    entry_diameter: float | None
    exit_diameter: float | None
    length: float | None
    mesh_file: str | None
    symmetry: str

    @property
    def axisymmetric(self) -> bool:
        return self.symmetry == "axisymmetric"

    @property
    def whole_forces(self) -> bool:
        """Whether the reported forces are forces (a round product's, or a strip's of the given
        ``width``) rather than forces per unit width of a strip."""
        return self.axisymmetric or self.width is not None

    def _diameters(self) -> None:
        """A round product's diameters are the half model's full thicknesses: entry_diameter and
        exit_diameter with symmetry = "axisymmetric", entry_thickness and exit_thickness for a strip."""
        if self.symmetry not in SYMMETRIES:
            raise SceneError("geometry.symmetry",
                             f"must be one of {', '.join(SYMMETRIES)}; got {self.symmetry!r}")
        for end in ("entry", "exit"):
            thickness, diameter = f"{end}_thickness", f"{end}_diameter"
            if not self.axisymmetric and getattr(self, diameter) is not None:
                raise SceneError(f"geometry.{diameter}", 'names a round product: it needs geometry.symmetry'
                                 f' = "axisymmetric" (a plane-strain strip has geometry.{thickness})')
            if self.axisymmetric and getattr(self, thickness) is not None:
                raise SceneError(f"geometry.{thickness}", "names a strip; a round product (symmetry = "
                                 f'"axisymmetric") has geometry.{diameter}')
            if self.axisymmetric:
                setattr(self, thickness, getattr(self, diameter))

    @property
    def thinnest(self) -> float:
        """Half-thickness (radius) of the thinnest section (the half model's exit)."""
        return 0.5 * self.exit_thickness

    def _record_diameters(self) -> None:
        if self.axisymmetric:
            self.entry_diameter, self.exit_diameter = self.entry_thickness, self.exit_thickness

    def resolve(self) -> None:
        """Fill in the lengths left out: from the mesh file, or the paper's geometry scaled."""
        self._diameters()
        self._die_file()
        for key in ("entry_thickness", "exit_thickness"):
            check_positive(f"geometry.{key.replace('thickness', self.thickness_name)}", getattr(self, key))
        if self.mesh_file is not None:
            self._from_mesh()
            self._record_diameters()
            return
        paper = self.PAPER
        factor = 1.0 if self.entry_thickness is None else self.entry_thickness / paper["entry_thickness"]
        for key, value in paper.items():
            if getattr(self, key) is None and key != "length":
                setattr(self, key, value if key == "die_angle" else value * factor)
        self.check_die()
        if self.length is None:  # the paper's length after the die, scaled, so that the die always fits
            self.length = paper["length"] * factor + (self.die_end - self._paper_die_end() * factor)
        self._record_diameters()

    @property
    def thickness_name(self) -> str:
        return "diameter" if self.axisymmetric else "thickness"

    def _from_mesh(self) -> None:
        path = Path(self.mesh_file)
        if path.suffix != ".msh" or not path.is_file():
            raise SceneError("geometry.mesh_file", f"must name an existing Gmsh .msh file; got {self.mesh_file!r}")
        measured = mesh_dimensions(str(path))
        for key in ("entry_thickness", "exit_thickness", "length"):
            given, value = getattr(self, key), getattr(measured, key)
            if given is not None and not math.isclose(given, value, rel_tol=1e-6):
                raise SceneError(f"geometry.{key}", f"is {given} but the mesh file {self.mesh_file} has {value:.9g}; "
                                 "leave it out (it is read from the mesh) or correct it")
            setattr(self, key, value)
        for key in self.DIE_KEYS:
            if getattr(self, key) is not None:
                raise SceneError(f"geometry.{key}", "does not apply with geometry.mesh_file (the die is the "
                                 "mesh's gamma3_contact); leave it out")

    def check_die(self) -> None:
        """The die's own data (not with a mesh file)."""

    def _die_file(self) -> None:
        """Read the die's own file, if it has one."""

    def check(self) -> None:
        """Lengths finite and > 0, a die that reduces the thickness and ends before the strip does."""
        name = self.thickness_name
        for key in ("length", "entry_thickness", "exit_thickness"):
            check_positive(f"geometry.{key.replace('thickness', name)}", getattr(self, key))
        if self.width is not None:
            if self.axisymmetric:
                raise SceneError("geometry.width", "applies to a plane-strain strip only: a round "
                                 "product's forces are the whole body's; leave it out")
            check_positive("geometry.width", self.width)
        if self.exit_thickness >= self.entry_thickness:
            raise SceneError(f"geometry.exit_{name}", f"must be < geometry.entry_{name} ({self.entry_thickness}): "
                             f"the die must reduce; got {self.exit_thickness}")
        if self.mesh_file is None:
            self.check_die()
            if self.die_end >= self.length:
                raise SceneError(self.LENGTH_KEY, f"the die must end before geometry.length ({self.length}); {self._die_text()}")


@dataclass
class ExtrusionGeometry(_Strip):
    """Plane-strain extrusion through a square die (Example 1); full thicknesses, half model built.

    Left out: the paper's 20 long, 10 -> 5 strip with the die face at x = 10, scaled."""

    PAPER: ClassVar[dict[str, float]] = {"length": 20.0, "entry_thickness": 10.0, "exit_thickness": 5.0,
                                         "die_position": 10.0}
    DIE_KEYS: ClassVar[tuple[str, ...]] = ("die_position",)
    LENGTH_KEY: ClassVar[str] = "geometry.die_position"
    length: float | None = None
    entry_thickness: float | None = None
    exit_thickness: float | None = None
    die_position: float | None = None
    mesh_file: str | None = None
    symmetry: str = "plane_strain"
    entry_diameter: float | None = None
    exit_diameter: float | None = None
    die: str = "square"
    width: float | None = None  # of a strip: its forces in force units (else per unit width)

    @property
    def die_end(self) -> float:
        return self.die_position

    def _paper_die_end(self) -> float:
        return self.PAPER["die_position"]

    def check_die(self) -> None:
        check_positive("geometry.die_position", self.die_position)

    def _die_text(self) -> str:
        return f"geometry.die_position is {self.die_position}"


@dataclass
class _ProfiledDie(_Strip):
    """A die whose wall is a profile (die_profile.py): a cone of semi-angle ``die_angle`` (degrees)
    met by the workpiece at x = ``die_entry``, an optional entry cone at ``second_angle`` over the
    axial length ``second_angle_length`` before it, an ``entry_radius`` rounding the corner where the
    workpiece meets the die, and a land (bearing) of ``land_length`` at the exit size; or the polyline
    of a CSV file ``die_profile_file`` (header x,y; from the entry size down to the exit size, with the
    land as its last level part), whose ends give the thicknesses when they are left out."""

    PROFILE_KEYS: ClassVar[tuple[str, ...]] = ("die_angle", "entry_radius", "second_angle",
                                               "second_angle_length", "land_length", "die_entry")
    DIE_KEYS: ClassVar[tuple[str, ...]] = (*PROFILE_KEYS, "die_profile_file")
    LENGTH_KEY: ClassVar[str] = "geometry.land_length"
    length: float | None = None
    entry_thickness: float | None = None
    exit_thickness: float | None = None
    die_angle: float | None = None
    land_length: float | None = None
    die_entry: float | None = None
    mesh_file: str | None = None
    symmetry: str = "plane_strain"
    entry_diameter: float | None = None
    exit_diameter: float | None = None
    entry_radius: float | None = None
    second_angle: float | None = None
    second_angle_length: float | None = None
    die_profile_file: str | None = None
    die: str = "conical"
    width: float | None = None  # of a strip: its forces in force units (else per unit width)

    def _die_file(self) -> None:
        """With die_profile_file: the thicknesses (when left out), die_entry and the recorded
        die_angle (the effective one, DieProfile.effective_angle) from the CSV polyline; the
        parametric keys do not apply."""
        if self.mesh_file is not None:
            return
        if self.die_profile_file is None:
            if self.entry_radius is None:
                self.entry_radius = 0.0
            return
        for key in self.PROFILE_KEYS:
            if getattr(self, key) is not None:
                raise SceneError(f"geometry.{key}", "does not apply with geometry.die_profile_file (the "
                                 "die is the file's polyline); leave it out")
        points = read_profile_csv(self.die_profile_file, "geometry.die_profile_file")
        for end, y in (("entry", points[0, 1]), ("exit", points[-1, 1])):
            key = f"{end}_thickness"
            given = getattr(self, key)
            if given is not None and not math.isclose(given, 2 * y, rel_tol=1e-9):
                raise SceneError(f"geometry.{end}_{self.thickness_name}",
                                 f"is {given} but geometry.die_profile_file runs from y = "
                                 f"{points[0, 1]:.9g} to {points[-1, 1]:.9g} (half-sizes): leave it out "
                                 "or correct it")
            setattr(self, key, 2 * y)
        self._polyline = points
        if self.exit_thickness >= self.entry_thickness:
            raise SceneError("geometry.die_profile_file", "must fall from the entry size to a smaller "
                             "exit size")
        profile = polyline_profile(points)
        self.die_entry, self.entry_radius = float(points[0, 0]), 0.0
        self.land_length = profile.end[0] - profile.land_start
        self.die_angle = profile.effective_angle

    def check_die(self) -> None:
        check_positive("geometry.die_entry", self.die_entry)
        if self.die_profile_file is not None:
            return
        for key in ("die_angle", "second_angle"):
            value = getattr(self, key)
            if value is not None and not 0 < value < 90:
                raise SceneError(f"geometry.{key}", f"must lie in (0, 90) degrees (a semi-angle); got {value}")
        for key in ("land_length", "entry_radius"):
            if not getattr(self, key) >= 0:
                raise SceneError(f"geometry.{key}", f"must be a finite number >= 0; got {getattr(self, key)}")
        if (self.second_angle is None) != (self.second_angle_length is None):
            raise SceneError("geometry.second_angle" if self.second_angle is None else
                             "geometry.second_angle_length",
                             "a two-angle die needs both geometry.second_angle and second_angle_length")
        if self.second_angle_length is not None:
            check_positive("geometry.second_angle_length", self.second_angle_length)
        try:
            profile = self.profile()
        except ValueError as error:
            key = "geometry.entry_radius" if "radius" in str(error) else "geometry.second_angle_length"
            raise SceneError(key, str(error)) from None
        if profile.start[0] <= 0:
            raise SceneError("geometry.die_entry", f"the die begins at x = {profile.start[0]:.4g}: "
                             "it must begin after the entry face x = 0 (raise die_entry)")

    def profile(self) -> DieProfile:
        """The die wall (die_profile.py)."""
        if self.die_profile_file is not None:
            return polyline_profile(self._polyline)
        return parametric_profile(self.die_entry, 0.5 * self.entry_thickness, 0.5 * self.exit_thickness,
                                  self.die_angle, self.land_length, self.entry_radius, self.second_angle,
                                  self.second_angle_length or 0.0)

    @property
    def semi_angle(self) -> float:
        """The semi-angle (degrees) closed forms and the central-burst indicator take: die_angle
        (for a CSV profile the recorded effective one), the chord's from the die entry to the land
        (DieProfile.effective_angle) for a two-angle die."""
        return self.die_angle if self.second_angle is None else self.profile().effective_angle

    def _die_text(self) -> str:
        return (f"the die (entry at {self.die_entry}, cone {self.cone_length:.4g} long, land "
                f"{self.land_length}) ends at {self.die_exit:.4g}")

    @property
    def cone_length(self) -> float:
        """Axial length from the die entry to the land."""
        if self.die_profile_file is not None or self.second_angle is not None:
            return self.profile().land_start - self.die_entry
        return 0.5 * (self.entry_thickness - self.exit_thickness) / math.tan(math.radians(self.die_angle))

    @property
    def die_exit(self) -> float:
        """x at the end of the land."""
        if self.die_profile_file is not None or self.second_angle is not None:
            return self.profile().end[0]
        return self.die_entry + self.cone_length + self.land_length

    @property
    def die_end(self) -> float:
        return self.die_exit

    def _paper_die_end(self) -> float:
        paper = type(self)(**{k: v for k, v in self.PAPER.items() if k != "length"})
        return paper.die_exit


@dataclass
class DrawingGeometry(_ProfiledDie):
    """Plane-strain strip (or round bar) drawing through a conical die with a land (Example 2); full
    thicknesses. Left out: the paper's 7.8 long, 1.625 -> 1.5 strip, a 6 degree die met at x = 3 with a
    land of 0.15, scaled (the angle is not)."""

    PAPER: ClassVar[dict[str, float]] = {"length": 7.8, "entry_thickness": 1.625, "exit_thickness": 1.5,
                                         "die_angle": 6.0, "land_length": 0.15, "die_entry": 3.0}


@dataclass
class ConicalExtrusionGeometry(_ProfiledDie):
    """Extrusion through a conical die (``die = "conical"``): the ram pushes the billet along a
    container (in contact, x from 0 to die_entry) into the die. Left out: a 10 -> 5 billet, a
    45 degree die at x = 10 with a land of 1, 10 of product after it, scaled (the angle is not)."""

    PAPER: ClassVar[dict[str, float]] = {"length": 23.5, "entry_thickness": 10.0, "exit_thickness": 5.0,
                                         "die_angle": 45.0, "land_length": 1.0, "die_entry": 10.0}


NORMAL_STRESSES = ("averaged", "local")
# Default relative values (docs/penalties.md measures them): d = D_RELATIVE rate0/sigma0,
# d_N = D_N_RELATIVE U/sigma0, d_T = D_T_RELATIVE U.
D_RELATIVE = 1e-4
D_N_RELATIVE = 1e-3
D_T_RELATIVE = 1e-6


@dataclass(frozen=True)
class Scales:
    """The scene's own scales: the process velocity U, the length H (entry thickness), the process
    strain rate rate0 (solver.reference_strain_rate, default U/H) and the flow stress
    sigma0 = sigma_p(rate0). Relative penalties are multiples of them."""

    velocity: float
    length: float
    strain_rate: float
    flow_stress: float


FRICTION_LAWS = ("coulomb", "factor")


@dataclass
class Friction:
    """Friction on Gamma3, regularised by d_T (3.11): absolute, or ``d_T_relative`` times the process
    velocity (default D_T_RELATIVE). ``law``: "coulomb" (2.9), tau_f = mu * sigma_N-bar, or "factor",
    tau_f = m k with k = sigma_p/sqrt(3) the workpiece's shear flow stress (0 <= m <= 1).

    Coulomb's bound uses the averaged (mollified) normal stress over ``mollification_length``
    (default: the mesh size), or the local penalty stress of (3.4).
    """

    law: str = "coulomb"
    mu: float = 0.0
    m: float = 0.0
    d_T: float | None = None
    d_T_relative: float | None = None
    normal_stress: str = "averaged"
    mollification_length: float | None = None

    def resolve(self, scales: Scales) -> None:
        set_pair("friction", self, "d_T", scales.velocity, D_T_RELATIVE)

    def check(self) -> None:
        if self.law not in FRICTION_LAWS:
            raise SceneError("friction.law", f"must be one of {', '.join(FRICTION_LAWS)}; got {self.law!r}")
        if not self.mu >= 0:
            raise SceneError("friction.mu", f"must be a finite number >= 0; got {self.mu}")
        if not 0 <= self.m <= 1:
            raise SceneError("friction.m", f"must lie in [0, 1] (the friction factor); got {self.m}")
        unused = {"coulomb": ("m", self.m), "factor": ("mu", self.mu)}[self.law]
        if unused[1] != 0:
            raise SceneError(f"friction.{unused[0]}", f'does not apply to friction.law = "{self.law}" '
                             f'({"mu" if self.law == "coulomb" else "m"} is its coefficient); leave it out')
        check_positive("friction.d_T", self.d_T)
        if self.normal_stress not in NORMAL_STRESSES:
            raise SceneError("friction.normal_stress",
                             f"must be one of {', '.join(NORMAL_STRESSES)}; got {self.normal_stress!r}")
        check_positive("friction.mollification_length", self.mollification_length)


@dataclass
class Penalty:
    """Penalty constants of (3.4): volumetric d (sigma_H = div u / d) and contact d_N
    (sigma_N = -u_N^+ / d_N), absolute, or relative to the scene's scales (the default):
    d = d_relative rate0 / sigma0 (div u / rate0 = d_relative sigma_H / sigma0) and
    d_N = d_N_relative U / sigma0 (u_N / U = d_N_relative sigma_N / sigma0). ``augmented``: the contact
    pressure is carried by a multiplier updated once the iterate settles, so that the workpiece does
    not enter the die (contact.py); false is the paper's pure penalty."""

    d: float | None = None
    d_N: float | None = None
    d_relative: float | None = None
    d_N_relative: float | None = None
    augmented: bool = True

    def resolve(self, scales: Scales) -> None:
        set_pair("penalty", self, "d", scales.strain_rate / scales.flow_stress, D_RELATIVE)
        set_pair("penalty", self, "d_N", scales.velocity / scales.flow_stress, D_N_RELATIVE)

    def check(self) -> None:
        for key in ("d", "d_N"):
            check_positive(f"penalty.{key}", getattr(self, key))


@dataclass
class Discretisation:
    """Element, incompressibility (penalty (3.5) with complete or reduced quadrature of the volumetric
    term, or a mixed velocity-pressure formulation: Q2 velocity with discontinuous P1 pressure, the
    limit d -> 0 of Theorem 3.1), mesh size (absolute, or ``mesh_size_relative`` times the exit
    half-thickness) and grading toward the die corner."""

    element: str = "Q2"
    volumetric_integration: str = "reduced"
    mesh_size: float | None = None
    mesh_size_relative: float | None = None
    corner_grading: float = 4.0
    averaging: str = "nodes"
    formulation: str = "penalty"

    def resolve(self, thinnest: float, default_relative: float) -> None:
        set_pair("discretisation", self, "mesh_size", thinnest, default_relative)

    def check(self) -> None:
        choices = {"element": ("Q1", "Q2"), "volumetric_integration": ("reduced", "complete"),
                   "averaging": ("nodes", "centres", "quadrature"), "formulation": ("penalty", "mixed")}
        for key, allowed in choices.items():
            if getattr(self, key) not in allowed:
                raise SceneError(f"discretisation.{key}",
                                 f"must be one of {', '.join(allowed)}; got {getattr(self, key)!r}")
        check_positive("discretisation.mesh_size", self.mesh_size)
        if not 1 <= self.corner_grading <= 1e3:
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
    ``coupling_tolerance`` (a hardening law, or a law reading the [thermal] temperature): the run has
    converged only when the transported strain (relative, weighted L2) and the temperature (relative
    to its rise) would change by less than it when taken from the last velocity.
    """

    method: str = "modified"
    tolerance: float = 1e-4
    coupling_tolerance: float = 1e-3
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
        if not 0 < self.tolerance < 1:
            raise SceneError("solver.tolerance", f"must lie in (0, 1) (delta of (4.4)); got {self.tolerance}")
        for key in ("max_iterations", "max_outer_iterations", "stall_window"):
            if getattr(self, key) < 1:
                raise SceneError(f"solver.{key}", f"must be an integer >= 1; got {getattr(self, key)}")
        if not 0 < self.coupling_tolerance < 1:
            raise SceneError("solver.coupling_tolerance",
                             f"must lie in (0, 1) (a relative change); got {self.coupling_tolerance}")
        if not 0 <= self.force_tolerance < 1:
            raise SceneError("solver.force_tolerance", f"must lie in [0, 1) (0: off); got {self.force_tolerance}")
        check_positive("solver.reference_strain_rate", self.reference_strain_rate)
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
        if not self.die_entry_trim >= 0:
            raise SceneError("output.die_entry_trim", f"must be a finite number >= 0; got {self.die_entry_trim}")


@dataclass
class Thermal:
    """Steady heat transfer in the workpiece (thermal.py, docs/thermal.md), built only when the
    scene has a [thermal] section. Values in the scene's units (heat is stress x volume: with mm,
    s, MPa the heat is in mJ = N mm): ``heat_capacity`` rho c in stress/K (MPa/K; aluminium 2.98),
    ``conductivity`` kappa in force/(time K) (N/(s K), the number of W/(m K); aluminium 201),
    ``heat_fraction`` beta (the plastic work turned into heat), heat transfer coefficients ``*_h``
    in force/(length time K) (N/(mm s K) = 1000 W/(m^2 K)), temperatures in kelvin (a
    Zener-Hollomon law reads them). ``inflow_temperature``: the billet or wire entering;
    ``die_*``: the die contact (Gamma3), ``container_*`` (extrusion): the container wall, the die's
    values unless given; ``air_*``: the free surfaces (``air_h`` 0: insulated); ``friction_share``:
    the share of the friction heat into the workpiece (the rest into the die); ``solidus``: where
    the workpiece starts to melt (a named material's unless given; sanity.py checks it)."""

    heat_capacity: float | None = None
    conductivity: float | None = None
    inflow_temperature: float | None = None
    heat_fraction: float = 0.9
    die_h: float = 0.0
    die_temperature: float | None = None
    container_h: float | None = None
    container_temperature: float | None = None
    air_h: float = 0.0
    air_temperature: float = 293.15
    friction_share: float = 0.5
    solidus: float | None = None

    REQUIRED: ClassVar[tuple[str, ...]] = ("heat_capacity", "conductivity", "inflow_temperature")

    def resolve(self) -> None:
        """The tool temperatures left out: the die at the inflow temperature, the container as the
        die."""
        for key in self.REQUIRED:
            if getattr(self, key) is None:
                raise SceneError(f"thermal.{key}", "missing; [thermal] needs heat_capacity, "
                                 "conductivity and inflow_temperature")
        if self.die_temperature is None:
            self.die_temperature = self.inflow_temperature
        if self.container_h is None:
            self.container_h = self.die_h
        if self.container_temperature is None:
            self.container_temperature = self.die_temperature

    def check(self) -> None:
        check_positive("thermal.heat_capacity", self.heat_capacity)
        for key in ("conductivity", "die_h", "container_h", "air_h"):
            value = getattr(self, key)
            if value is not None and not value >= 0:
                raise SceneError(f"thermal.{key}", f"must be a finite number >= 0; got {value}")
        for key in ("inflow_temperature", "die_temperature", "container_temperature",
                    "air_temperature", "solidus"):
            if getattr(self, key) is not None and not getattr(self, key) > 0:
                raise SceneError(f"thermal.{key}",
                                 f"must be > 0 (kelvin); got {getattr(self, key)}")
        for key in ("heat_fraction", "friction_share"):
            if not 0 <= getattr(self, key) <= 1:
                raise SceneError(f"thermal.{key}", f"must lie in [0, 1]; got {getattr(self, key)}")
        if self.solidus is not None and not self.inflow_temperature < self.solidus:
            raise SceneError("thermal.inflow_temperature", f"{self.inflow_temperature:g} K is not "
                             f"below the solidus {self.solidus:g} K: the workpiece enters molten")

    @property
    def coldest(self) -> float:
        """The lowest temperature that enters or surrounds the workpiece: with no heat sink in it,
        no point of a steady workpiece can be colder (the maximum principle)."""
        around = [self.inflow_temperature, self.die_temperature]
        around += [self.container_temperature] if self.container_h else []
        around += [self.air_temperature] if self.air_h else []
        return min(around)


# The summary numbers accuracy on demand can drive, by process; the first is the default
ACCURACY_QUANTITIES = {
    "extrusion": ("ram_pressure", "ram_force", "die_force_x", "mean_hydrostatic_pressure"),
    "drawing": ("drawing_stress", "drawing_force", "die_force_x", "mean_die_pressure")}


@dataclass
class Accuracy:
    """Accuracy on demand (accuracy.py): with a ``target`` (relative, e.g. 0.01), the scene is
    solved on meshes of sizes h_0 > h_1 > ..., each started from the previous solution, until the
    estimated relative error of ``quantity`` (default: ram_pressure, drawing_stress) is below the
    target or ``max_levels`` meshes are used. ``ratio`` is the refinement h_k/h_(k+1) of the first
    levels; the scene's mesh size is the third level's. No target (the default): one run on the
    scene's mesh."""

    target: float | None = None
    quantity: str | None = None
    ratio: float = 2.0
    max_levels: int = 6

    def check(self) -> None:
        if self.target is not None and not 0 < self.target < 1:
            raise SceneError("accuracy.target", "must lie in (0, 1) (a relative error, 0.01 is "
                             f"1 %); got {self.target}")
        if not 1.25 <= self.ratio <= 4:
            raise SceneError("accuracy.ratio",
                             f"must lie in [1.25, 4] (h_k/h_(k+1)); got {self.ratio}")
        if not 3 <= self.max_levels <= 12:
            raise SceneError("accuracy.max_levels", "must be an integer in [3, 12] (three meshes "
                             f"give the first estimate); got {self.max_levels}")


# The geometry of each process and geometry.die (the first is the default)
GEOMETRIES = {"extrusion": {"square": ExtrusionGeometry, "conical": ConicalExtrusionGeometry},
              "drawing": {"conical": DrawingGeometry}}


def geometry_class(kind: str, table: dict[str, Any]) -> type:
    """The geometry class that geometry.die names for the process."""
    dies = GEOMETRIES[kind]
    die = table.get("die", next(iter(dies)))
    if not isinstance(die, str) or die not in dies:
        raise SceneError("geometry.die", f"must be one of {', '.join(dies)} for {kind}; got {die!r}")
    return dies[die]

# Each process's defaults over the dataclass ones: the paper's process data (Example 1 and Example 2).
# Example 2's Q1 elements with complete integration lock (docs/example2.md): the drawing default is Q2
# with reduced integration, as for extrusion; the demo scenes name the paper's.
PROCESS_DEFAULTS: dict[str, dict[str, dict[str, Any]]] = {
    "extrusion": {},
    "drawing": {
        "process": {"velocity": 1000.0, "drive": "pull"},
        "material": {"A": 100 * math.sqrt(3.0)},
        "discretisation": {"corner_grading": 1.0},
    },
}
# The default mesh size over the exit half-thickness: about 5 elements across it (Example 1's 0.5),
# 15 for drawing (Example 2's 0.05)
MESH_SIZE_RELATIVE = {"extrusion": 0.2, "drawing": 1 / 15}


@dataclass
class Scene:
    """One run, fully specified (after :meth:`resolve`, every value absolute)."""

    process: Process
    geometry: ExtrusionGeometry | ConicalExtrusionGeometry | DrawingGeometry
    material: FlowLaw
    friction: Friction
    penalty: Penalty
    discretisation: Discretisation
    solver: Solver
    output: Output
    units: Units = field(default_factory=Units)
    thermal: Thermal | None = None  # only when the scene has [thermal]
    accuracy: Accuracy = field(default_factory=Accuracy)

    def resolve(self) -> None:
        """Turn the values left out or given relative into absolute ones, in the order they depend on each
        other: geometry (from the mesh file or the paper's, scaled), the scales, then penalties, the
        slip regularisation, the power law's rate floor, the mesh size and the mollification length."""
        self.geometry.resolve()
        self.geometry.check()
        if self.material.law == "sellars_tegart":  # T: the [thermal] field, or the law's own
            if self.thermal is not None:
                if self.material.temperature is not None:
                    raise SceneError("material.temperature", "the scene has [thermal]: the flow "
                                     "reads its temperature field; leave material.temperature out")
                self.thermal.resolve()
                self.material = dataclasses.replace(self.material,
                                                    temperature=self.thermal.inflow_temperature)
            elif self.material.temperature is None:
                raise SceneError("material.temperature", f"material.law = {self.material.law!r} "
                                 "needs the workpiece's temperature (kelvin), or a [thermal] section")
        self.material = self.material.resolve(self.reference_strain_rate)
        self.material.check()
        scales = self.scales
        if not (math.isfinite(scales.flow_stress) and scales.flow_stress > 0):
            raise SceneError("material", f"gives the flow stress {scales.flow_stress} at the process strain rate "
                             f"{scales.strain_rate:.6g}: it must be a finite number > 0")
        self.penalty.resolve(scales)
        self.friction.resolve(scales)
        self.discretisation.resolve(self.geometry.thinnest, MESH_SIZE_RELATIVE[self.process.kind])
        if self.friction.mollification_length is None:  # about one element, recorded as used
            self.friction.mollification_length = self.discretisation.mesh_size
        if self.thermal is not None:
            self.thermal.resolve()
            if self.thermal.solidus is None:
                self.thermal.solidus = SOLIDUS.get(getattr(self.material, "name", None))
        self._not_molten()

    def _not_molten(self) -> None:
        """An isothermal law's temperature must lie below the named material's solidus."""
        temperature = getattr(self.material, "temperature", None)
        solidus = SOLIDUS.get(getattr(self.material, "name", None))
        if self.thermal is None and temperature is not None and solidus is not None \
                and not temperature < solidus:
            raise SceneError("material.temperature", f"{temperature:g} K is not below the solidus "
                             f"of {self.material.name} ({solidus:g} K): the workpiece is molten")

    def check(self) -> None:
        """Checks of each section, then of values that are valid alone but not together."""
        for section in dataclasses.fields(self):
            if getattr(self, section.name) is not None:
                getattr(self, section.name).check()
        if self.solver.method == "newton" and self.discretisation.averaging != "quadrature":
            raise SceneError("solver.method", 'newton differentiates G at the integration points: it needs '
                             f'discretisation.averaging = "quadrature"; got {self.discretisation.averaging!r}')
        coupled = self.material.hardens or (self.material.heats and self.thermal is not None)
        if coupled and self.discretisation.averaging != "quadrature":
            raise SceneError("discretisation.averaging", f"material.law = {self.material.law!r} "
                             'reads the strain or temperature at the integration points: it needs '
                             f'"quadrature"; got {self.discretisation.averaging!r}')
        if self.material.hardens and self.material.initial_strain_file is not None:
            check_section(read_strain_profile(self.material.initial_strain_file, "material.initial_strain_file"),
                          self.geometry.entry_thickness / 2, "material.initial_strain_file")
        if self.discretisation.formulation == "mixed" and self.discretisation.element != "Q2":
            raise SceneError("discretisation.formulation", "mixed uses Q2 velocity with discontinuous P1 "
                             f'pressure: it needs discretisation.element = "Q2"; got {self.discretisation.element!r}')
        thermal = self.thermal
        if thermal is not None and self.geometry.mesh_file is not None and (
                thermal.container_h, thermal.container_temperature) != (thermal.die_h,
                                                                         thermal.die_temperature):
            raise SceneError("thermal.container_h", "a mesh file's Gamma3 is one boundary: the "
                             "container takes the die's values (leave container_* out)")
        quantities = ACCURACY_QUANTITIES[self.process.kind]
        if self.accuracy.quantity is None:
            self.accuracy.quantity = quantities[0]
        elif self.accuracy.quantity not in quantities:
            raise SceneError("accuracy.quantity", f"must be one of {', '.join(quantities)} for "
                             f"{self.process.kind}; got {self.accuracy.quantity!r}")
        if self.discretisation.mesh_size > self.geometry.thinnest:
            raise SceneError("discretisation.mesh_size",
                             f"must be <= the thinnest half-thickness ({self.geometry.thinnest}) so that "
                             f"at least one element spans it; got {self.discretisation.mesh_size}")

    @property
    def reference_strain_rate(self) -> float:
        """Strain rate of the uniform starting modulus: the scene's, else velocity over entry thickness."""
        given = self.solver.reference_strain_rate
        return given if given is not None else self.process.velocity / self.geometry.entry_thickness

    @property
    def reference_flow_stress(self) -> float:
        """sigma_p at the reference strain rate: the stress scale of the process."""
        return float(self.material.flow_stress([self.reference_strain_rate])[0])

    @property
    def scales(self) -> Scales:
        return Scales(self.process.velocity, self.geometry.entry_thickness, self.reference_strain_rate,
                      self.reference_flow_stress)

    def to_dict(self) -> dict[str, Any]:
        """Every resolved value, section by section."""
        return {f.name: dataclasses.asdict(getattr(self, f.name)) for f in dataclasses.fields(self)
                if getattr(self, f.name) is not None}


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
        errors = []
        for option in typing.get_args(tp):
            if option is type(None):
                continue
            try:
                return _coerce(key, value, option)
            except SceneError as error:
                errors.append(error)
        if len(errors) == 1:  # e.g. float | None: the float's own message (finite, a number)
            raise errors[0]
        raise SceneError(key, f"must be {_typename(tp)}; got {value!r}")
    base = origin or tp
    ok = {float: isinstance(value, (int, float)) and not isinstance(value, bool),
          int: isinstance(value, int) and not isinstance(value, bool),
          bool: isinstance(value, bool), str: isinstance(value, str), dict: isinstance(value, dict)}[base]
    if not ok:
        raise SceneError(key, f"must be {_typename(tp)}; got {value!r}")
    if base is float:
        if not math.isfinite(value):
            raise SceneError(key, f"must be a finite number; got {value!r}")
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


def _material(table: dict[str, Any], defaults: dict[str, Any], units: dict[str, Any]) -> FlowLaw:
    """The flow law of [material]: ``law`` and its keys, or a named material (``name``, values in
    MPa, so the scene's units.stress must be MPa) whose keys the table overrides."""
    name = table.get("name")
    if name is not None:
        if not isinstance(name, str) or name not in MATERIALS:
            raise SceneError("material.name", f"must be one of {', '.join(MATERIALS)}; got {name!r}")
        if units.get("stress") != "MPa":
            raise SceneError("material.name", f"{name} is given in MPa: the scene needs units.stress = "
                             f'"MPa" (got {units.get("stress")!r})')
        if MATERIALS[name]["law"] == "sellars_tegart" and units.get("time") != "s":
            raise SceneError("material.name", f"{name}'s A is given in 1/s: the scene needs "
                             f'units.time = "s" (got {units.get("time")!r})')
        table = {**MATERIALS[name], **table}
    law = table.get("law", PiecewisePowerLaw.law)
    if law == "power":
        raise SceneError("material.law", '"power" is now "rate_power": sigma = A rate^n, a strain-rate '
                         'law without hardening; strain hardening K eps^n is "hollomon"')
    if not isinstance(law, str) or law not in LAWS:
        raise SceneError("material.law", f"must be one of {', '.join(LAWS)}; got {law!r}")
    names = {f.name for f in dataclasses.fields(LAWS[law])}
    return _build(LAWS[law], table, "material", {k: v for k, v in defaults.items() if k in names})


SECTIONS = ("process", "geometry", "material", "friction", "penalty", "discretisation", "solver", "output",
            "units", "thermal", "accuracy")


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
    classes = {"geometry": geometry_class(kind, tables["geometry"]), "friction": Friction, "penalty": Penalty,
               "discretisation": Discretisation, "solver": Solver, "output": Output, "units": Units,
               "accuracy": Accuracy}
    built = {name: _build(cls, tables[name], name, defaults.get(name)) for name, cls in classes.items()}
    if "thermal" in data:  # heat transfer only when the scene asks for it
        if kind == "drawing":
            for key in ("container_h", "container_temperature"):
                if key in tables["thermal"]:
                    raise SceneError(f"thermal.{key}", "drawing has no container; leave it out")
        built["thermal"] = _build(Thermal, tables["thermal"], "thermal")
    scene = Scene(process=process, material=_material(tables["material"], defaults.get("material", {}),
                                                      tables["units"]), **built)
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

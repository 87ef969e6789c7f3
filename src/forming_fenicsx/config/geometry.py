"""The scene's [geometry] section: the strip or round bar of each process and its die.

Full thicknesses (diameters of a round product) are given; the half model is built. Lengths left
out are the paper's example geometry scaled by the entry thickness, or read from a Gmsh mesh file.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import ClassVar

from forming_fenicsx.config.die_profile import (DieProfile, parametric_profile, polyline_profile,
                                                read_profile_csv)
from forming_fenicsx.config.mesh_file import mesh_dimensions
from forming_fenicsx.core.errors import SceneError
from forming_fenicsx.core.relative import check_positive
from forming_fenicsx.physics.coordinates import SYMMETRIES

SECTIONS = ("rectangle", "round")  # of a 3D product (geometry.section)


class _Strip:
    """What every strip geometry (full thicknesses entry_thickness > exit_thickness) shares.

    Lengths left out are the paper's example geometry (``PAPER``) scaled by entry_thickness over
    the paper's; the length left out keeps the paper's (scaled) length after the die. ``mesh_file``
    names a Gmsh .msh file to use instead of the built-in geometry: its roles are the physical
    groups named gamma1_velocity ... gamma6_symmetry (as `forming mesh` writes them), and the
    thicknesses and length are read from it (scene values that disagree with it are rejected; die
    data do not apply).
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
    section: str | None
    entry_height: float | None
    exit_height: float | None
    entry_width: float | None
    exit_width: float | None

    @property
    def axisymmetric(self) -> bool:
        return self.symmetry == "axisymmetric"

    @property
    def three_dimensional(self) -> bool:
        return self.symmetry == "3d"

    @property
    def round(self) -> bool:
        """A round product: axisymmetric, or the 3D quarter of one (section = "round")."""
        return self.axisymmetric or self.section == "round"

    @property
    def whole_forces(self) -> bool:
        """Whether the reported forces are forces (a round product's, a 3D bar's, or a strip's of
        the given ``width``) rather than forces per unit width of a strip."""
        return self.axisymmetric or self.three_dimensional or self.width is not None

    def _diameters(self) -> None:
        """The model's full thicknesses from the sizes its product is given by: entry_thickness
        and exit_thickness for a strip, entry_diameter and exit_diameter for a round product
        (axisymmetric, or 3D with section = "round"), entry_height and exit_height (with
        entry_width and exit_width) for a 3D bar of rectangular section; the other sizes are
        refused."""
        if self.symmetry not in SYMMETRIES:
            raise SceneError("geometry.symmetry",
                             f"must be one of {', '.join(SYMMETRIES)}; got {self.symmetry!r}")
        self._section()
        given = {"strip": "thickness", "round": "diameter", "rectangle": "height"}[self.shape]
        for end in ("entry", "exit"):
            for size in ("thickness", "diameter", "height", "width"):
                if size == given or (size == "width" and self.shape == "rectangle"):
                    continue
                if getattr(self, f"{end}_{size}") is not None:
                    # the symmetry a size of this name describes (a round bar's diameter)
                    meant = {"diameter": 'symmetry = "axisymmetric"',
                             "height": 'symmetry = "3d" with section = "rectangle"'}.get(size)
                    raise SceneError(f"geometry.{end}_{size}", f"does not describe a {self.shape} "
                                     f"(symmetry = {self.symmetry!r}); it has geometry.{end}_"
                                     f"{given}" + (" and _width" if self.shape == "rectangle"
                                                   else "")
                                     + (f" (a {size} is given with geometry.{meant})"
                                        if meant and self.shape == "strip" else ""))
            if given != "thickness":
                setattr(self, f"{end}_thickness", getattr(self, f"{end}_{given}"))

    def _section(self) -> None:
        """geometry.section: a 3D product's cross-section, "rectangle" (the default) or "round";
        2D models take their shape from the symmetry."""
        if not self.three_dimensional:
            if self.section is not None:
                raise SceneError("geometry.section", 'applies to symmetry = "3d" only')
            return
        if self.section is None:
            self.section = "rectangle"
        if self.section not in SECTIONS:
            square = ('; a square bar is a rectangle: section = "rectangle" with entry_width = '
                      'entry_height and exit_width = exit_height'
                      if str(self.section).lower() == "square" else "")
            raise SceneError("geometry.section",
                             f"must be one of {', '.join(SECTIONS)}; got {self.section!r}{square}")

    @property
    def shape(self) -> str:
        """What the sizes describe: a "strip", a "round" product or a "rectangle" (3D bar)."""
        if self.three_dimensional:
            return self.section or "rectangle"
        return "round" if self.axisymmetric else "strip"

    @property
    def area_ratio(self) -> float:
        """A1/A0: the exit section over the entry section (of thicknesses for a strip)."""
        ratio = self.exit_thickness / self.entry_thickness
        if self.shape == "rectangle":
            return ratio * self.exit_width / self.entry_width
        return ratio**2 if self.round else ratio

    @property
    def ideal_strain(self) -> float:
        """The equivalent strain of homogeneous deformation through the pass: ln(A0/A1), in plane
        strain 2/sqrt3 ln(h0/h1). Differences of logarithms: the ratio of two valid sizes can
        underflow (A1/A0 of a 1e162 mm entry did)."""
        def log_ratio(size: str) -> float:
            entry, exit_ = getattr(self, f"entry_{size}"), getattr(self, f"exit_{size}")
            return math.log(entry) - math.log(exit_)
        if self.shape == "strip":
            return 2 / math.sqrt(3) * log_ratio("thickness")
        if self.shape == "rectangle":
            return log_ratio("thickness") + log_ratio("width")
        return 2 * log_ratio("thickness")

    @property
    def thinnest(self) -> float:
        """Half-thickness (radius) of the thinnest section (the half model's exit; a 3D bar's
        smaller half-size there)."""
        if self.shape == "rectangle":
            return 0.5 * min(self.exit_thickness, self.exit_width)
        return 0.5 * self.exit_thickness

    def _record_diameters(self) -> None:
        if self.shape == "round":
            self.entry_diameter, self.exit_diameter = self.entry_thickness, self.exit_thickness
        elif self.shape == "rectangle":
            self.entry_height, self.exit_height = self.entry_thickness, self.exit_thickness

    def resolve(self) -> None:
        """Fill in the lengths left out: from the mesh file, or the paper's geometry scaled."""
        self._diameters()
        self._die_file()
        for key in ("entry_thickness", "exit_thickness"):
            check_positive(f"geometry.{key.replace('thickness', self.thickness_name)}",
                           getattr(self, key))
        if self.mesh_file is not None:
            self._from_mesh()
            self._record_diameters()
            return
        paper = self.PAPER
        factor = (1.0 if self.entry_thickness is None
                  else self.entry_thickness / paper["entry_thickness"])
        if self.three_dimensional and self.die_entry is None and hasattr(self, "die_entry"):
            # a 3D model's stock ahead of the die: one entry size (the paper's 2D strips model
            # 2 to 4 of them)
            self.die_entry = self.entry_thickness
        for key, value in paper.items():
            if getattr(self, key) is None and key != "length":
                setattr(self, key, value if key == "die_angle" else value * factor)
        self.check_die()
        if self.length is None and self.three_dimensional:
            # 1.5 exit sizes of product after the die, where the flow is rigid again
            self.length = self.die_end + 1.5 * self.exit_thickness
        if self.length is None:  # the paper's length after the die, scaled: the die always fits
            self.length = paper["length"] * factor + (self.die_end - self._paper_die_end() * factor)
        self._record_diameters()

    @property
    def thickness_name(self) -> str:
        return {"strip": "thickness", "round": "diameter", "rectangle": "height"}[self.shape]

    def _from_mesh(self) -> None:
        path = Path(self.mesh_file)
        if path.suffix != ".msh" or not path.is_file():
            raise SceneError("geometry.mesh_file",
                             f"must name an existing Gmsh .msh file; got {self.mesh_file!r}")
        measured = mesh_dimensions(str(path), self.three_dimensional)
        widths = ("entry_width", "exit_width") if self.shape == "rectangle" else ()
        for key in ("entry_thickness", "exit_thickness", "length", *widths):
            given, value = getattr(self, key), getattr(measured, key)
            if given is not None and not math.isclose(given, value, rel_tol=1e-6):
                raise SceneError(f"geometry.{key}", f"is {given} but the mesh file "
                                 f"{self.mesh_file} has {value:.9g}; leave it out (it is read "
                                 "from the mesh) or correct it")
            setattr(self, key, value)
        for key in self.DIE_KEYS:
            if getattr(self, key) is not None:
                raise SceneError(f"geometry.{key}", "does not apply with geometry.mesh_file (the "
                                 "die is the mesh's gamma3_contact); leave it out")

    def check_die(self) -> None:
        """The die's own data (not with a mesh file)."""

    def check_3d(self) -> None:
        """What a 3D model supports: the built-in quarter models of a bar drawn or extruded
        through a straight converging die with a land (die = "conical")."""
        raise SceneError("geometry.die", "a 3D bar is drawn or extruded through a converging "
                         'die (die = "conical"); the square die is a 2D model')

    def _die_file(self) -> None:
        """Read the die's own file, if it has one."""

    def check(self) -> None:
        """Lengths finite and > 0, a die that reduces the thickness and ends before the strip
        does."""
        name = self.thickness_name
        for key in ("length", "entry_thickness", "exit_thickness"):
            check_positive(f"geometry.{key.replace('thickness', name)}", getattr(self, key))
        if self.width is not None:
            if self.symmetry != "plane_strain":
                raise SceneError("geometry.width", "applies to a plane-strain strip only: a round "
                                 "product's and a 3D bar's forces are the whole body's; leave it "
                                 "out")
            check_positive("geometry.width", self.width)
        if self.shape == "rectangle":
            check_positive("geometry.entry_width", self.entry_width)
            check_positive("geometry.exit_width", self.exit_width)
            if self.exit_width > self.entry_width:
                raise SceneError("geometry.exit_width", f"must be <= geometry.entry_width "
                                 f"({self.entry_width}): the die may not widen; got "
                                 f"{self.exit_width}")
        if self.exit_thickness >= self.entry_thickness:
            raise SceneError(f"geometry.exit_{name}", f"must be < geometry.entry_{name} "
                             f"({self.entry_thickness}): the die must reduce; got "
                             f"{self.exit_thickness}")
        if self.three_dimensional:
            self.check_3d()
        if self.mesh_file is None:
            self.check_die()
            if self.die_end >= self.length:
                raise SceneError(self.LENGTH_KEY, "the die must end before geometry.length "
                                 f"({self.length}); {self._die_text()}")


@dataclass
class ExtrusionGeometry(_Strip):
    """Plane-strain extrusion through a square die (Example 1); full thicknesses, half model built.

    Left out: the paper's 20 long, 10 -> 5 strip with the die face at x = 10, scaled."""

    PAPER: ClassVar[dict[str, float]] = {"length": 20.0, "entry_thickness": 10.0,
                                         "exit_thickness": 5.0, "die_position": 10.0}
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
    section: str | None = None
    entry_height: float | None = None
    exit_height: float | None = None
    entry_width: float | None = None
    exit_width: float | None = None

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
    axial length ``second_angle_length`` before it, an ``entry_radius`` rounding the corner where
    the workpiece meets the die, and a land (bearing) of ``land_length`` at the exit size; or the
    polyline of a CSV file ``die_profile_file`` (header x,y; from the entry size down to the exit
    size, with the land as its last level part), whose ends give the thicknesses when they are left
    out."""

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
    section: str | None = None
    entry_height: float | None = None
    exit_height: float | None = None
    entry_width: float | None = None
    exit_width: float | None = None

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
                raise SceneError(f"geometry.{key}", "does not apply with "
                                 "geometry.die_profile_file (the die is the file's polyline); "
                                 "leave it out")
        points = read_profile_csv(self.die_profile_file, "geometry.die_profile_file")
        if not points[0, 0] > 0:  # the die starts at its first x: the stock is modelled ahead
            raise SceneError("geometry.die_profile_file",
                             f"starts at x = {points[0, 0]:.9g}, where the die meets the "
                             "workpiece: the stock is modelled from x = 0 to there, so the "
                             "polyline's first x must be > 0 (shift its x by the stock's length "
                             "to model ahead of the die)")
        for end, y in (("entry", points[0, 1]), ("exit", points[-1, 1])):
            key = f"{end}_thickness"
            given = getattr(self, key)
            if given is not None and not math.isclose(given, 2 * y, rel_tol=1e-9):
                raise SceneError(f"geometry.{end}_{self.thickness_name}",
                                 f"is {given} but geometry.die_profile_file runs from y = "
                                 f"{points[0, 1]:.9g} to {points[-1, 1]:.9g} (half-sizes): leave "
                                 "it out or correct it")
            setattr(self, key, 2 * y)
        self._polyline = points
        if self.exit_thickness >= self.entry_thickness:
            raise SceneError("geometry.die_profile_file", "must fall from the entry size to a "
                             "smaller exit size")
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
                raise SceneError(f"geometry.{key}",
                                 f"must lie in (0, 90) degrees (a semi-angle); got {value}"
                                 + (' (a flat die face is geometry.die = "square")'
                                    if value == 90 and key == "die_angle"
                                    and isinstance(self, ConicalExtrusionGeometry) else ""))
            if value is not None and math.tan(math.radians(value)) == 0:
                raise SceneError(f"geometry.{key}", f"{value} degrees is too small for a cone: "
                                 "its tangent underflows to 0 (a cone infinitely long)")
        for key in ("land_length", "entry_radius"):
            if not getattr(self, key) >= 0:
                raise SceneError(f"geometry.{key}",
                                 f"must be a finite number >= 0; got {getattr(self, key)}")
        if (self.second_angle is None) != (self.second_angle_length is None):
            raise SceneError("geometry.second_angle" if self.second_angle is None else
                             "geometry.second_angle_length",
                             "a two-angle die needs both geometry.second_angle and "
                             "second_angle_length")
        if self.second_angle_length is not None:
            check_positive("geometry.second_angle_length", self.second_angle_length)
        try:
            profile = self.profile()
        except ValueError as error:
            key = ("geometry.entry_radius" if "radius" in str(error)
                   else "geometry.second_angle_length")
            raise SceneError(key, str(error)) from None
        if profile.start[0] <= 0:
            raise SceneError("geometry.die_entry", f"the die begins at x = {profile.start[0]:.4g}: "
                             "it must begin after the entry face x = 0 (raise die_entry)")

    def check_3d(self) -> None:
        """A 3D die is straight faces and a land (or a user's mesh): the faces' profile keys that
        shape a 2D die (entry radius, second angle, a CSV profile) are refused for now."""
        for key, unset in (("die_profile_file", None), ("second_angle", None),
                           ("entry_radius", 0.0)):
            if getattr(self, key) not in (None, unset):
                raise SceneError(f"geometry.{key}", 'is not available with symmetry = "3d" yet: '
                                 "the 3D die has straight faces (geometry.die_angle) and a land")

    @property
    def width_angle(self) -> float:
        """A 3D rectangular die's semi-angle (degrees) of the faces that reduce the width: they
        converge over the same cone length as the height faces (die_angle); 0 where the width
        does not change."""
        return math.degrees(math.atan2(0.5 * (self.entry_width - self.exit_width),
                                       self.cone_length))

    def profile(self) -> DieProfile:
        """The die wall (die_profile.py)."""
        if self.die_profile_file is not None:
            return polyline_profile(self._polyline)
        return parametric_profile(self.die_entry, 0.5 * self.entry_thickness,
                                  0.5 * self.exit_thickness, self.die_angle, self.land_length,
                                  self.entry_radius, self.second_angle,
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
        return (0.5 * (self.entry_thickness - self.exit_thickness)
                / math.tan(math.radians(self.die_angle)))

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
    """Plane-strain strip (or round bar) drawing through a conical die with a land (Example 2);
    full thicknesses. Left out: the paper's 7.8 long, 1.625 -> 1.5 strip, a 6 degree die met at
    x = 3 with a land of 0.15, scaled (the angle is not)."""

    PAPER: ClassVar[dict[str, float]] = {"length": 7.8, "entry_thickness": 1.625,
                                         "exit_thickness": 1.5, "die_angle": 6.0,
                                         "land_length": 0.15, "die_entry": 3.0}


@dataclass
class ConicalExtrusionGeometry(_ProfiledDie):
    """Extrusion through a conical die (``die = "conical"``): the ram pushes the billet along a
    container (in contact, x from 0 to die_entry) into the die. Left out: a 10 -> 5 billet, a
    45 degree die at x = 10 with a land of 1, 10 of product after it, scaled (the angle is not)."""

    PAPER: ClassVar[dict[str, float]] = {"length": 23.5, "entry_thickness": 10.0,
                                         "exit_thickness": 5.0, "die_angle": 45.0,
                                         "land_length": 1.0, "die_entry": 10.0}

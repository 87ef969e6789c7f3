"""The [geometry] of flat rolling: a strip between two equal rigid rolls, modelled by its upper half
(the mid-plane y = 0 is a symmetry plane) in plane strain.

The strip runs along x: ``entry_length`` of incoming strip at the entry thickness h0, the roll's
arc from the bite (x_b, h0/2) down to the roll gap (x_g, h1/2) at the line of the roll centres,
then ``exit_length`` of product at the exit thickness h1 (the roll gap: the rolls are rigid). The
top roll's centre is (x_g, h1/2 + R); the arc's projected length is the contact length
L = sqrt(R^2 - (R - dh/2)^2), dh = h0 - h1, and its angle at the bite the bite angle
alpha = asin(L/R).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

from forming_fenicsx.config.die_profile import DieProfile, Segment
from forming_fenicsx.config.geometry import _Strip
from forming_fenicsx.core.errors import SceneError
from forming_fenicsx.core.relative import check_positive

# the strip modelled before the bite and after the gap, in entry thicknesses (left out)
ENTRY_LENGTH_RELATIVE = 1.5
EXIT_LENGTH_RELATIVE = 1.5


@dataclass
class RollingGeometry(_Strip):
    """Flat rolling between rolls of radius ``roll_radius`` from ``entry_thickness`` to
    ``exit_thickness`` (full thicknesses), with ``entry_length`` of strip before the bite and
    ``exit_length`` after the roll gap (left out: 1.5 entry thicknesses each). ``width``: the
    strip's, for forces and torques in force units (else per unit width)."""

    DIE_KEYS = ()
    LENGTH_KEY = "geometry.exit_length"
    entry_thickness: float | None = None
    exit_thickness: float | None = None
    roll_radius: float | None = None
    entry_length: float | None = None
    exit_length: float | None = None
    width: float | None = None
    die: str = "rolls"
    symmetry: str = "plane_strain"
    length: float | None = None  # derived: entry_length + contact length + exit_length
    mesh_file: str | None = None
    entry_diameter: float | None = None
    exit_diameter: float | None = None
    section: str | None = None
    entry_height: float | None = None
    exit_height: float | None = None
    entry_width: float | None = None
    exit_width: float | None = None

    # what the profiled dies' post-processing reads: no land, no entry rounding, no second cone
    land_length = 0.0
    entry_radius = 0.0
    second_angle = None
    second_angle_length = None
    die_profile_file = None

    def resolve(self) -> None:
        if self.symmetry != "plane_strain":
            raise SceneError("geometry.symmetry", 'rolling models a flat strip in plane strain: '
                             f'it needs "plane_strain"; got {self.symmetry!r}')
        for key in ("mesh_file", "length"):
            if getattr(self, key) is not None:
                raise SceneError(f"geometry.{key}", "does not apply to rolling (the strip is "
                                 "built from the roll gap and entry_length, exit_length); leave "
                                 "it out")
        self._diameters()
        for key in ("entry_thickness", "exit_thickness", "roll_radius"):
            if getattr(self, key) is None:
                raise SceneError(f"geometry.{key}", "missing: rolling needs entry_thickness, "
                                 "exit_thickness and roll_radius")
            check_positive(f"geometry.{key}", getattr(self, key))
        if self.exit_thickness >= self.entry_thickness:
            raise SceneError("geometry.exit_thickness", "must be < geometry.entry_thickness "
                             f"({self.entry_thickness}): the rolls must reduce; got "
                             f"{self.exit_thickness}")
        if not self.half_draft < self.roll_radius:
            raise SceneError("geometry.roll_radius", f"{self.roll_radius} cannot bite a draft of "
                             f"{self.entry_thickness - self.exit_thickness:.6g} (half of it must "
                             "be below the radius: a bite angle under 90 degrees)")
        for key, relative in (("entry_length", ENTRY_LENGTH_RELATIVE),
                              ("exit_length", EXIT_LENGTH_RELATIVE)):
            if getattr(self, key) is None:
                setattr(self, key, relative * self.entry_thickness)
            check_positive(f"geometry.{key}", getattr(self, key))
        self.length = self.die_exit + self.exit_length
        if not self.die_entry < self.die_exit < self.length:
            raise SceneError("geometry.roll_radius", f"{self.roll_radius:.6g} makes a contact "
                             f"length of {self.cone_length:.6g} against entry_length "
                             f"{self.entry_length:.6g} and exit_length {self.exit_length:.6g}: "
                             "the strip's lengths vanish beside it in double precision")

    def check_die(self) -> None:
        """Checked in resolve (the strip's length is derived)."""

    @property
    def half_draft(self) -> float:
        """dh/2 = (h0 - h1)/2, the drop of the half model's top surface."""
        return 0.5 * (self.entry_thickness - self.exit_thickness)

    @property
    def cone_length(self) -> float:
        """The contact length L = sqrt(R^2 - (R - dh/2)^2) = sqrt(dh/2 (2 R - dh/2)), the arc's
        projection on x (the second form: R^2 overflowed for a radius of 1.3e154, a fuzzed
        scene)."""
        half = self.half_draft
        return math.sqrt(half * (2.0 * self.roll_radius - half))

    @property
    def bite_angle(self) -> float:
        """alpha = asin(L/R) (radians): the roll's angle at the bite from the line of centres."""
        return math.asin(self.cone_length / self.roll_radius)

    @property
    def die_angle(self) -> float:
        """The bite angle in degrees (figures' headings)."""
        return math.degrees(self.bite_angle)

    semi_angle = die_angle

    @property
    def die_entry(self) -> float:
        """x of the bite."""
        return self.entry_length

    @property
    def die_exit(self) -> float:
        """x of the roll gap (the line of the roll centres)."""
        return self.entry_length + self.cone_length

    @property
    def die_end(self) -> float:
        return self.die_exit

    @property
    def roll_centre(self) -> tuple[float, float]:
        """The top roll's centre (x_g, h1/2 + R)."""
        return self.die_exit, 0.5 * self.exit_thickness + self.roll_radius

    def profile(self) -> DieProfile:
        """The top roll's arc from the bite to the roll gap."""
        return DieProfile((Segment((self.die_entry, 0.5 * self.entry_thickness),
                                   (self.die_exit, 0.5 * self.exit_thickness),
                                   self.roll_centre),))

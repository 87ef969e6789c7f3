"""Scenes: the TOML input that says everything about one run, validated before any meshing.

A scene has the sections ``process``, ``geometry``, ``material``, ``friction``, ``penalty``,
``discretisation``, ``solver``, ``output`` and ``units``, and ``thermal`` when it computes the
temperature. Every value has a default; loading a scene (loader.py) rejects unknown keys,
mistyped, non-finite or non-physical values with a :class:`SceneError` that names the key and what
is allowed.

Values with units that are not physical data (penalties, regularisations, mesh size, lengths left
out) default to multiples of the scene's own scales (:class:`Scales`: the process velocity, the
entry thickness and the flow stress at the process strain rate) and are turned into absolute values
when the scene is resolved, so that a scene gives the same dimensionless answer in any consistent
unit system. The paper's absolute values stay available: a scene that gives ``penalty.d`` uses it
as it is.
"""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from typing import Any

from forming_fenicsx.config.geometry import (ConicalExtrusionGeometry, DrawingGeometry,
                                             ExtrusionGeometry)
from forming_fenicsx.config.roll_gap import RollingGeometry
from forming_fenicsx.config.materials import SOLIDUS
from forming_fenicsx.config.sections import (ACCURACY_QUANTITIES, D_N_RELATIVE, D_T_RELATIVE,
                                             ROLLING_D_N_RELATIVE, ROLLING_D_T_RELATIVE, Accuracy,
                                             Discretisation, FreeSurface, Friction, Output,
                                             Penalty, Process, Scales, Solver, Thermal)
from forming_fenicsx.config.strain_profile import (check_section, read_strain_profile,
                                                   section_mean)
from forming_fenicsx.core.errors import SceneError
from forming_fenicsx.core.units import TIMES, Units
from forming_fenicsx.physics.flow_laws import FlowLaw, rate_sensitivity
from forming_fenicsx.physics.friction import RATE_SENSITIVE, STICKING_RATE_SENSITIVITY


# The default mesh size over the exit half-thickness: about 5 elements across it (Example 1's 0.5),
# 15 for drawing (Example 2's 0.05)
MESH_SIZE_RELATIVE = {"extrusion": 0.2, "drawing": 1 / 15, "rolling": 0.125}
# a 3D model's default: 4 elements across its thinnest half-size (its unknowns grow with the cube
# of the refinement; docs/three_d.md measures the mesh error)
MESH_SIZE_RELATIVE_3D = 0.25


@dataclass
class Scene:
    """One run, fully specified (after :meth:`resolve`, every value absolute)."""

    process: Process
    geometry: ExtrusionGeometry | ConicalExtrusionGeometry | DrawingGeometry | RollingGeometry
    material: FlowLaw
    friction: Friction
    penalty: Penalty
    discretisation: Discretisation
    solver: Solver
    output: Output
    units: Units = field(default_factory=Units)
    thermal: Thermal | None = None  # only when the scene has [thermal]
    accuracy: Accuracy = field(default_factory=Accuracy)
    free_surface: FreeSurface = field(default_factory=FreeSurface)

    def resolve(self) -> None:
        """Turn the values left out or given relative into absolute ones, in the order they depend
        on each other: geometry (from the mesh file or the paper's, scaled), the scales, then
        penalties, the slip regularisation, the flow law's rate floor, the mesh size and the
        mollification length."""
        self.geometry.resolve()
        self.geometry.check()
        if self.process.roll_rpm is not None:
            self._surface_speed()
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
                                 "needs the workpiece's temperature (kelvin), or a [thermal] "
                                 "section")
        self.material = self.material.resolve(self.reference_strain_rate)
        self.material.check()
        scales = self.scales
        if not (math.isfinite(scales.flow_stress) and scales.flow_stress > 0):
            raise SceneError("material", f"gives the flow stress {scales.flow_stress} at the "
                             f"process strain rate {scales.strain_rate:.6g}: it must be a finite "
                             "number > 0")
        rolling = self.process.kind == "rolling"
        self.penalty.resolve(scales, ROLLING_D_N_RELATIVE if rolling else D_N_RELATIVE)
        self.friction.resolve(scales, ROLLING_D_T_RELATIVE if rolling else D_T_RELATIVE)
        if self.friction.shear_limit is None:
            self.friction.shear_limit = rolling and not self.rate_sensitive
        if self.friction.sticks is None:
            self.friction.sticks = self.friction.law == "sticking" or self._factor_limit_sticks
        relative = (MESH_SIZE_RELATIVE_3D if self.geometry.three_dimensional
                    else MESH_SIZE_RELATIVE[self.process.kind])
        self.discretisation.resolve(self.geometry.thinnest, relative)
        if self.friction.mollification_length is None:  # about one element, recorded as used
            self.friction.mollification_length = self.discretisation.mesh_size
        if self.thermal is not None:
            self.thermal.resolve()
            if self.thermal.solidus is None:
                self.thermal.solidus = SOLIDUS.get(getattr(self.material, "name", None))
        self._not_molten()

    def _surface_speed(self) -> None:
        """process.velocity from process.roll_rpm: v_R = 2 pi R n / 60 in the scene's length over
        its time unit (units.time, required)."""
        time = self.units.time
        if time not in TIMES:
            raise SceneError("process.roll_rpm", "needs units.time (one of "
                             f"{', '.join(TIMES)}) to make a surface speed of revolutions per "
                             f"minute; got {time!r}")
        self.process.velocity = (2 * math.pi * self.geometry.roll_radius * self.process.roll_rpm
                                 / 60.0 * TIMES[time])

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
            raise SceneError("solver.method", "newton differentiates G at the integration points: "
                             'it needs discretisation.averaging = "quadrature"; got '
                             f"{self.discretisation.averaging!r}")
        if self.thermal is not None and self.geometry.three_dimensional:
            raise SceneError("thermal", 'heat transfer is not available with symmetry = "3d" yet '
                             "(a 3D run solves the flow and the strain); leave [thermal] out or "
                             "model the product in 2D")
        if self.coupled and self.discretisation.averaging != "quadrature":
            raise SceneError("discretisation.averaging", f"material.law = {self.material.law!r} "
                             'reads the strain or temperature at the integration points: it needs '
                             f'"quadrature"; got {self.discretisation.averaging!r}')
        if self.geometry.three_dimensional and \
                getattr(self.material, "initial_strain_file", None) is not None:
            raise SceneError("material.initial_strain_file", "is a profile across a 2D entry "
                             '(y from the axis); symmetry = "3d" cannot read one yet (nor a 3D '
                             "run's exit_strain.csv): give the stock's strain as a uniform "
                             "material.initial_strain, e.g. the previous pass's mean_exit_strain")
        if self.material.hardens and self.material.initial_strain_file is not None:
            key = "material.initial_strain_file"
            check_section(read_strain_profile(self.material.initial_strain_file, key),
                          self.geometry.entry_thickness / 2, key)
        if self.solver.linear == "iterative" and self.discretisation.formulation != "mixed":
            raise SceneError("solver.linear", '"iterative" solves the mixed formulation\'s saddle '
                             'point (the penalty\'s 1/d makes multigrid fail): set '
                             'discretisation.formulation = "mixed", or solver.linear = "direct"')
        if self.discretisation.formulation == "mixed" and self.discretisation.element != "Q2":
            raise SceneError("discretisation.formulation", "mixed uses Q2 velocity with "
                             'discontinuous P1 pressure: it needs discretisation.element = "Q2"; '
                             f"got {self.discretisation.element!r}")
        thermal = self.thermal
        container = None if thermal is None else (thermal.container_h,
                                                  thermal.container_temperature)
        if thermal is not None and self.geometry.mesh_file is not None \
                and container != (thermal.die_h, thermal.die_temperature):
            raise SceneError("thermal.container_h", "a mesh file's Gamma3 is one boundary: the "
                             "container takes the die's values (leave container_* out)")
        self._check_free_surface()
        if self.friction.law == "sticking" and self.process.kind != "rolling":
            raise SceneError("friction.law", '"sticking" holds the strip to the rolls, and is '
                             "rolling's only: in drawing and extrusion the velocity prescribed "
                             "where the die's surface begins (the ram's face at the container "
                             "wall) slips against it, and the penalised slip's stress, k0/d_T "
                             "times that slip, has no bound there (Example 1 with it: a ram "
                             'pressure of 6955 k). friction.law = "factor" with m = 1 bounds the '
                             "friction at the shear flow stress k")
        self._check_sticks()
        if self.process.kind == "rolling" and self.friction.coefficient <= 0:
            key = "friction.m" if self.friction.law == "factor" else "friction.mu"
            raise SceneError(key, "must be > 0 for rolling: the rolls draw the strip in by "
                             "friction alone, and a frictionless bite has no steady state")
        if self.process.kind == "rolling" and self.accuracy.target is not None:
            raise SceneError("accuracy.target", "accuracy on demand does not run rolling scenes "
                             "yet: refine discretisation.mesh_size and compare")
        quantities = ACCURACY_QUANTITIES[self.process.kind]
        if self.accuracy.quantity is None:
            self.accuracy.quantity = quantities[0]
        elif self.accuracy.quantity not in quantities:
            raise SceneError("accuracy.quantity", f"must be one of {', '.join(quantities)} for "
                             f"{self.process.kind}; got {self.accuracy.quantity!r}")
        if self.discretisation.mesh_size > self.geometry.thinnest:
            raise SceneError("discretisation.mesh_size",
                             "must be <= the thinnest half-thickness "
                             f"({self.geometry.thinnest}) so that at least one element spans it; "
                             f"got {self.discretisation.mesh_size}")

    def _check_sticks(self) -> None:
        """friction.sticks: always with law "sticking", and otherwise only at the factor law's
        m = 1 in rolling, the law whose limit sticking is."""
        law = self.friction
        if law.law == "sticking" and law.sticks is False:
            raise SceneError("friction.sticks", 'friction.law = "sticking" is sticking: leave '
                             'friction.sticks out, or give friction.law = "factor" with m = 1')
        if law.sticks and law.law != "sticking" and not (
                law.law == "factor" and law.m == 1.0 and self.process.kind == "rolling"):
            given = f"{law.law!r}" + (f" with m = {law.m:g}" if law.law == "factor" else "")
            raise SceneError("friction.sticks", "solves rolling's factor law at m = 1 as "
                             f"sticking, its limit; it does not apply to friction.law = {given} "
                             f"in {self.process.kind}: leave it out")

    def _check_free_surface(self) -> None:
        """The free-surface update re-meshes the built-in 2D workpiece of a profiled die."""
        if not self.free_surface.update:
            return
        g = self.geometry
        if self.process.kind == "rolling":
            raise SceneError("free_surface.update", "rolling's strip leaves the rigid rolls at "
                             "the roll gap: the update is for drawing and extrusion dies")
        if g.three_dimensional:
            raise SceneError("geometry.symmetry", "the free-surface update is 2D for now (plane "
                             "strain or axisymmetric); a 3D model keeps the drawn surfaces")
        if g.mesh_file is not None:
            raise SceneError("geometry.mesh_file", "a user's mesh has no geometry to move: the "
                             "free-surface update re-meshes the built-in workpiece")
        if self.accuracy.target is not None:
            raise SceneError("accuracy.target", "accuracy on demand and the free-surface update "
                             "are not combined yet: give one or the other")

    @property
    def coupled(self) -> bool:
        """Whether the flow law reads a transported field at the integration points: the strain
        of a hardening law, or the [thermal] temperature of a law that heats."""
        return self.material.hardens or (self.material.heats and self.thermal is not None)

    @property
    def _factor_limit_sticks(self) -> bool:
        """Whether rolling's factor law is at m = 1 on a metal that does not harden, of rate
        sensitivity at least friction.STICKING_RATE_SENSITIVITY. There the interface is exactly
        as strong as the metal under it, the slip's split between them is free but for d_T, and
        Newton creeps along it (up to 279 linear solves); the roll force lies 1.8 to 3.5 % below
        its d_T -> 0 limit, which sticking meets within 0.07 to 0.6 % in about 10 solves
        (docs/rolling.md)."""
        law = self.friction
        return (self.process.kind == "rolling" and law.law == "factor" and law.m == 1.0
                and not self.material.hardens
                and self.rate_sensitivity >= STICKING_RATE_SENSITIVITY)

    @property
    def rate_sensitivity(self) -> float:
        """The flow law's d ln sigma_p / d ln rate at the reference strain rate
        (flow_laws.rate_sensitivity)."""
        return rate_sensitivity(self.material, self.reference_strain_rate)

    @property
    def rate_sensitive(self) -> bool:
        """Whether the flow law's d ln sigma_p / d ln rate at the reference strain rate is at least
        friction.RATE_SENSITIVE. Rolling caps Coulomb's bound at k only on a metal that is not:
        long gaps at mu = 0.2, 0.3 on the slab grid's nearly rate-independent law took up to 46
        linear solves without the cap, 22 with. On a rate-sensitive metal the surface layer bounds
        the friction at its own rate, and the cap at k of the element's rate left the roll force
        up to 1.9 % below its d_T -> 0 limit, moving by 0.3 to 0.9 % for d_T doubled
        (docs/rolling.md)."""
        return self.rate_sensitivity >= RATE_SENSITIVE

    @property
    def reference_strain_rate(self) -> float:
        """Strain rate of the uniform starting modulus: the scene's, else velocity over entry
        thickness."""
        given = self.solver.reference_strain_rate
        return given if given is not None else self.process.velocity / self.geometry.entry_thickness

    @property
    def reference_flow_stress(self) -> float:
        """The stress scale of the process (the penalties' sigma0): sigma_p at the reference
        strain rate; for a hardening law its mean over the pass, from the inflow strain to that
        plus the ideal strain. An annealed stock's flow stress is the law's value at its strain
        floor, a tenth of the pass's for annealed copper, and the penalties scaled by it made
        the answers depend on that floor (docs/hardening.md)."""
        rate, law = self.reference_strain_rate, self.material
        if not law.hardens:
            return float(law.flow_stress([rate])[0])
        inflow = self.inflow_strain
        return law.mean_flow_stress(rate, inflow, inflow + self.geometry.ideal_strain)

    @property
    def inflow_strain(self) -> float:
        """A hardening law's strain flowing in: initial_strain, or the mean of
        initial_strain_file's profile over the entry section."""
        law = self.material
        if law.initial_strain_file is None:
            return law.initial_strain
        key = "material.initial_strain_file"
        return section_mean(read_strain_profile(law.initial_strain_file, key),
                            self.geometry.round)

    @property
    def scales(self) -> Scales:
        """The scene's own scales, of which relative values are multiples."""
        return Scales(self.process.velocity, self.geometry.entry_thickness,
                      self.reference_strain_rate, self.reference_flow_stress)

    def to_dict(self) -> dict[str, Any]:
        """Every resolved value, section by section."""
        return {f.name: dataclasses.asdict(getattr(self, f.name)) for f in dataclasses.fields(self)
                if getattr(self, f.name) is not None}

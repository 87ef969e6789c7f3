"""The scene's sections besides [geometry] and [material], each a dataclass validated alone by its
``check()``: process, friction, penalty, discretisation, solver, output, thermal and accuracy.

Values that are not physical data (penalties, regularisations) default to multiples of the scene's
own scales (:class:`Scales`) and are made absolute by the sections' ``resolve()``.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, ClassVar

from forming_fenicsx.core.errors import SceneError
from forming_fenicsx.core.relative import check_positive, set_pair

PROCESSES = ("extrusion", "drawing", "rolling")


@dataclass
class Process:
    """What is formed and how: the process velocity u_N^0 on Gamma1 (2.5) and the normal stress
    F_N on Gamma5 (2.7), positive pulling the face outward.

    ``drive`` says where the velocity is prescribed: "pull" at the exit face (drawing), "push" at
    the entry face (extrusion's ram). F_N acts on the other end face, which is free without it.

    Rolling: ``velocity`` is the rolls' surface speed (or ``roll_rpm`` their revolutions per
    minute) and the strip's speed is the problem's; the end faces carry the ``back_tension``
    (entry) and ``front_tension`` (exit), stresses >= 0.
    """

    kind: str = "extrusion"
    velocity: float = 1.0
    applied_force: float | None = None
    drive: str = "push"
    back_tension: float = 0.0
    front_tension: float = 0.0
    roll_rpm: float | None = None

    def check(self) -> None:
        if self.kind not in PROCESSES:
            raise SceneError("process.kind",
                             f"must be one of {', '.join(PROCESSES)}; got {self.kind!r}")
        if not (math.isfinite(self.velocity) and self.velocity > 0):
            raise SceneError("process.velocity",
                             f"must be a finite number > 0; got {self.velocity}")
        if self.applied_force is not None and not math.isfinite(self.applied_force):
            raise SceneError("process.applied_force",
                             f"must be a finite number; got {self.applied_force}")
        if self.drive not in ("push", "pull"):
            raise SceneError("process.drive", f"must be one of push, pull; got {self.drive!r}")
        for key in ("back_tension", "front_tension"):
            value = getattr(self, key)
            if self.kind != "rolling" and value != 0:
                raise SceneError(f"process.{key}", "applies to rolling; a drawn or extruded "
                                 "product's end load is process.applied_force")
            if not (math.isfinite(value) and value >= 0):
                raise SceneError(f"process.{key}", f"must be a finite stress >= 0; got {value}")
        if self.roll_rpm is not None:
            if self.kind != "rolling":
                raise SceneError("process.roll_rpm", "applies to rolling only")
            if not (math.isfinite(self.roll_rpm) and self.roll_rpm > 0):
                raise SceneError("process.roll_rpm",
                                 f"must be a finite number > 0; got {self.roll_rpm}")
        if self.kind == "rolling" and self.applied_force is not None:
            raise SceneError("process.applied_force", "does not apply to rolling: its end faces "
                             "carry process.back_tension and process.front_tension")


NORMAL_STRESSES = ("averaged", "local")
# Default relative values (docs/penalties.md measures them): d = D_RELATIVE rate0/sigma0,
# d_N = D_N_RELATIVE U/sigma0, d_T = D_T_RELATIVE U.
D_RELATIVE = 1e-4
D_N_RELATIVE = 1e-3
D_T_RELATIVE = 1e-6
# rolling's (docs/rolling.md): its pure-penalty contact is stiffer, and its slip regularisation
# wider, which Newton needs at the neutral point (the roll force moves by 0.02 %)
ROLLING_D_N_RELATIVE = 1e-4
ROLLING_D_T_RELATIVE = 1e-3


@dataclass(frozen=True)
class Scales:
    """The scene's own scales: the process velocity U, the length H (entry thickness), the process
    strain rate rate0 (solver.reference_strain_rate, default U/H) and the flow stress
    sigma0 = sigma_p(rate0). Relative penalties are multiples of them."""

    velocity: float
    length: float
    strain_rate: float
    flow_stress: float


FRICTION_LAWS = ("coulomb", "factor", "sticking")


@dataclass
class Friction:
    """Friction on Gamma3, regularised by d_T (3.11): absolute, or ``d_T_relative`` times the
    process velocity (default D_T_RELATIVE). ``law``: "coulomb" (2.9), tau_f = mu * sigma_N-bar, or
    "factor", tau_f = m k with k = sigma_p/sqrt(3) the workpiece's shear flow stress (0 <= m <= 1),
    or "sticking", the workpiece held to the die (roll), its slip penalised, tau = -(k0/d_T) u_T
    with k0 the shear flow stress at the reference rate: the metal under the surface, not the
    interface, bounds the friction stress (friction.py).

    Coulomb's bound uses the averaged (mollified) normal stress over ``mollification_length``
    (default: the mesh size), or the local penalty stress of (3.4). ``shear_limit`` caps it at the
    shear flow stress, tau_f = min(mu sigma_N-bar, k) (default: in rolling on a metal that is not
    rate-sensitive; off elsewhere, the paper's law, and on a rate-sensitive metal, whose surface
    layer bounds the friction at its own rate: docs/rolling.md); the factor law never exceeds k.
    ``sticks``: whether the friction is solved as sticking: law "sticking", and by default in
    rolling the factor law at m = 1 on a metal that does not harden, of rate sensitivity at least
    friction.STICKING_RATE_SENSITIVITY, whose d_T -> 0 limit sticking is (docs/rolling.md); false
    keeps the factor law there.
    """

    law: str = "coulomb"
    mu: float = 0.0
    m: float = 0.0
    d_T: float | None = None
    d_T_relative: float | None = None
    normal_stress: str = "averaged"
    mollification_length: float | None = None
    shear_limit: bool | None = None
    sticks: bool | None = None

    @property
    def coefficient(self) -> float:
        """The law's coefficient: m of the factor law, mu of Coulomb's (0: no friction), 1 for
        sticking (the friction reaches the metal's shear strength)."""
        return {"factor": self.m, "coulomb": self.mu, "sticking": 1.0}[self.law]

    def resolve(self, scales: Scales, d_T_relative: float = D_T_RELATIVE) -> None:
        set_pair("friction", self, "d_T", scales.velocity, d_T_relative)

    def check(self) -> None:
        if self.law not in FRICTION_LAWS:
            raise SceneError("friction.law",
                             f"must be one of {', '.join(FRICTION_LAWS)}; got {self.law!r}")
        if not self.mu >= 0:
            raise SceneError("friction.mu", f"must be a finite number >= 0; got {self.mu}")
        if not 0 <= self.m <= 1:
            raise SceneError("friction.m",
                             f"must lie in [0, 1] (the friction factor); got {self.m}")
        unused = {"coulomb": [("m", self.m)], "factor": [("mu", self.mu)],
                  "sticking": [("mu", self.mu), ("m", self.m)]}[self.law]
        for key, value in unused:
            if value == 0:
                continue
            other = "factor" if key == "m" else "coulomb"
            own = {"coulomb": "mu is its coefficient", "factor": "m is its coefficient",
                   "sticking": "it has no coefficient"}[self.law]
            raise SceneError(f"friction.{key}", f'does not apply to friction.law = '
                             f'"{self.law}" ({own}): leave it out, or set friction.law = '
                             f'"{other}", whose coefficient it is')
        check_positive("friction.d_T", self.d_T)
        if self.normal_stress not in NORMAL_STRESSES:
            raise SceneError("friction.normal_stress",
                             f"must be one of {', '.join(NORMAL_STRESSES)}; "
                             f"got {self.normal_stress!r}")
        check_positive("friction.mollification_length", self.mollification_length)


@dataclass
class Penalty:
    """Penalty constants of (3.4): volumetric d (sigma_H = div u / d) and contact d_N
    (sigma_N = -u_N^+ / d_N), absolute, or relative to the scene's scales (the default):
    d = d_relative rate0 / sigma0 (div u / rate0 = d_relative sigma_H / sigma0) and
    d_N = d_N_relative U / sigma0 (u_N / U = d_N_relative sigma_N / sigma0). ``augmented``: the
    contact pressure is carried by a multiplier updated once the iterate settles, so that the
    workpiece does not enter the die (contact.py); false is the paper's pure penalty."""

    d: float | None = None
    d_N: float | None = None
    d_relative: float | None = None
    d_N_relative: float | None = None
    augmented: bool = True

    def resolve(self, scales: Scales, d_N_relative: float = D_N_RELATIVE) -> None:
        set_pair("penalty", self, "d", scales.strain_rate / scales.flow_stress, D_RELATIVE)
        set_pair("penalty", self, "d_N", scales.velocity / scales.flow_stress, d_N_relative)

    def check(self) -> None:
        for key in ("d", "d_N"):
            check_positive(f"penalty.{key}", getattr(self, key))


@dataclass
class Discretisation:
    """Element, incompressibility (penalty (3.5) with complete or reduced quadrature of the
    volumetric term, or a mixed velocity-pressure formulation: Q2 velocity with discontinuous P1
    pressure, the limit d -> 0 of Theorem 3.1), mesh size (absolute, or ``mesh_size_relative``
    times the exit half-thickness) and the gradings toward the die's corners and wall (defaults:
    the measured best, docs/accuracy.md)."""

    element: str = "Q2"
    volumetric_integration: str = "reduced"
    mesh_size: float | None = None
    mesh_size_relative: float | None = None
    corner_grading: float = 64.0
    wall_grading: float = 16.0
    averaging: str = "nodes"
    formulation: str = "penalty"

    def resolve(self, thinnest: float, default_relative: float) -> None:
        set_pair("discretisation", self, "mesh_size", thinnest, default_relative)

    def check(self) -> None:
        choices = {"element": ("Q1", "Q2"), "volumetric_integration": ("reduced", "complete"),
                   "averaging": ("nodes", "centres", "quadrature"),
                   "formulation": ("penalty", "mixed")}
        for key, allowed in choices.items():
            if getattr(self, key) not in allowed:
                raise SceneError(f"discretisation.{key}",
                                 f"must be one of {', '.join(allowed)}; got {getattr(self, key)!r}")
        check_positive("discretisation.mesh_size", self.mesh_size)
        for key in ("corner_grading", "wall_grading"):
            if not 1 <= getattr(self, key) <= 1e3:
                raise SceneError(f"discretisation.{key}",
                                 "must lie in [1, 1000] (ratio of the largest to the smallest "
                                 f"element on a graded edge; 1 is uniform); got "
                                 f"{getattr(self, key)}")

    @property
    def degree(self) -> int:
        return int(self.element[1])


# the direct solver's options (solver.petsc_options' default): MUMPS
DIRECT_OPTIONS = {"ksp_type": "preonly", "pc_factor_mat_solver_type": "mumps"}
LINEAR_SOLVERS = ("auto", "direct", "iterative")


@dataclass
class Solver:
    """Nonlinear iteration: the secant-modulus methods direct (3.13) or modified (3.33), or Newton's
    method after ``secant_start`` direct iterates (newton.py, both formulations); all stopped by the
    rule of (4.4).

    ``linear``: how the linear systems are solved: "direct" (MUMPS), "iterative" (the mixed
    formulation only: FGMRES with a fieldsplit Schur preconditioner and p-multigrid on the velocity,
    fem/saddle_point.py; its relative residual follows the nonlinear iteration) or "auto" (iterative
    for a 3D mixed problem of at least solvers/linear.ITERATIVE_FROM unknowns, else direct).
    ``dual_start``: Newton's dual stress at the switch from the secant iterates, as a fraction of
    tau(u); below 1 it keeps the first Newton step's stiffness along the flow direction at about
    (1 - dual_start) times the secant's instead of alpha times (docs/solvers.md).
    ``stall_window``: inner iterations (a fifth of it for outer ones) without a new smallest
    increment after which the run stops as stalled or oscillating. ``force_tolerance`` (0: off, as
    in the paper) also requires the x force balance residual to fall below it before the run counts
    as converged: a small increment is not a small error. ``coupling_tolerance`` (a hardening law,
    or a law reading the [thermal] temperature): the run has converged only when the transported
    strain (relative, weighted L2) and the temperature (relative to its rise) would change by less
    than it when taken from the last velocity.
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
    linear: str = "auto"
    petsc_options: dict[str, Any] = field(default_factory=lambda: dict(DIRECT_OPTIONS))

    def check(self) -> None:
        if self.method not in ("direct", "modified", "newton"):
            raise SceneError("solver.method",
                             f"must be one of direct, modified, newton; got {self.method!r}")
        if not (isinstance(self.secant_start, int) and self.secant_start >= 0):
            raise SceneError("solver.secant_start",
                             f"must be an integer >= 0; got {self.secant_start!r}")
        start = self.dual_start
        if isinstance(start, bool) or not (isinstance(start, (int, float)) and 0 <= start <= 1):
            raise SceneError("solver.dual_start",
                             "must lie in [0, 1] (a fraction of the stress); "
                             f"got {self.dual_start!r}")
        if not 0 < self.tolerance < 1:
            raise SceneError("solver.tolerance",
                             f"must lie in (0, 1) (delta of (4.4)); got {self.tolerance}")
        for key in ("max_iterations", "max_outer_iterations", "stall_window"):
            if getattr(self, key) < 1:
                raise SceneError(f"solver.{key}",
                                 f"must be an integer >= 1; got {getattr(self, key)}")
        if not 0 < self.coupling_tolerance < 1:
            raise SceneError("solver.coupling_tolerance",
                             "must lie in (0, 1) (a relative change); "
                             f"got {self.coupling_tolerance}")
        if not 0 <= self.force_tolerance < 1:
            raise SceneError("solver.force_tolerance",
                             f"must lie in [0, 1) (0: off); got {self.force_tolerance}")
        check_positive("solver.reference_strain_rate", self.reference_strain_rate)
        if self.linear not in LINEAR_SOLVERS:
            raise SceneError("solver.linear", f"must be one of {', '.join(LINEAR_SOLVERS)}; "
                             f"got {self.linear!r}")
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
                             f"must be one of {', '.join(DIE_PRESSURES)}; "
                             f"got {self.die_pressure!r}")
        if not self.die_entry_trim >= 0:
            raise SceneError("output.die_entry_trim",
                             f"must be a finite number >= 0; got {self.die_entry_trim}")


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

    def surroundings(self) -> dict[str, float]:
        """The temperatures that enter or surround the workpiece, by key: the inflow's, the die's,
        and the container's and the air's where they exchange heat."""
        around = {"inflow_temperature": self.inflow_temperature,
                  "die_temperature": self.die_temperature}
        if self.container_h:
            around["container_temperature"] = self.container_temperature
        if self.air_h:
            around["air_temperature"] = self.air_temperature
        return around

    @property
    def coldest(self) -> float:
        """The lowest temperature that enters or surrounds the workpiece: with no heat sink in it,
        no point of a steady workpiece can be colder (the maximum principle)."""
        return min(self.surroundings().values())


# The summary numbers accuracy on demand can drive, by process; the first is the default
ACCURACY_QUANTITIES = {
    "extrusion": ("ram_pressure", "ram_force", "die_force_x", "mean_hydrostatic_pressure"),
    "drawing": ("drawing_stress", "drawing_force", "die_force_x", "mean_die_pressure"),
    "rolling": ("roll_force", "roll_torque")}


@dataclass
class Accuracy:
    """Accuracy on demand (accuracy.py): with a ``target`` (relative, e.g. 0.01), the scene is
    solved on meshes of sizes h_0 > h_1 > ..., each started from the previous solution, until the
    estimated relative error of ``quantity`` (default: ram_pressure, drawing_stress) is below the
    target or ``max_levels`` meshes are used. ``ratio`` is the refinement h_k/h_(k+1) of the first
    levels; the scene's mesh size is the third level's. ``meshes``: "adapted" (after the first,
    the meshes are adapted to an error indicator, mesh/adapted.py; a 2D scene's own geometry only)
    or "refined" (the scene's blocks at a smaller size). No target (the default): one run on the
    scene's mesh."""

    target: float | None = None
    quantity: str | None = None
    ratio: float = 2.0
    max_levels: int = 6
    meshes: str = "adapted"

    def check(self) -> None:
        if self.target is not None and not 0 < self.target < 1:
            raise SceneError("accuracy.target", "must lie in (0, 1) (a relative error, 0.01 is "
                             f"1 %); got {self.target}")
        if not 1.25 <= self.ratio <= 4:
            raise SceneError("accuracy.ratio",
                             f"must lie in [1.25, 4] (h_k/h_(k+1)); got {self.ratio}")
        if self.meshes not in ("adapted", "refined"):
            raise SceneError("accuracy.meshes", f'must be "adapted" or "refined"; got '
                             f"{self.meshes!r}")
        if not 3 <= self.max_levels <= 12:
            raise SceneError("accuracy.max_levels", "must be an integer in [3, 12] (three meshes "
                             f"give the first estimate); got {self.max_levels}")


SURFACE_METHODS = ("flux_level", "least_squares")


@dataclass
class FreeSurface:
    """The free surfaces as the flow decides them (app/free_surface.py, docs/free_surface.md): with
    ``update``, the flow solve alternates with a surface update that makes the free surfaces
    streamlines (v.n = 0) and moves where the contact with the die starts and ends, until the
    surface moves by less than ``tolerance`` times the exit half-size or ``max_updates`` updates
    are made. Off by default: the fixed domain the scene draws (the paper's model)."""

    update: bool = False
    tolerance: float = 1e-3
    max_updates: int = 8
    # the streamline from where the contact ends: the flux level (post/free_surface.py) or the
    # least-squares surface form (post/surface_least_squares.py)
    method: str = "flux_level"

    def check(self) -> None:
        if self.method not in SURFACE_METHODS:
            raise SceneError("free_surface.method", f"must be one of {', '.join(SURFACE_METHODS)}"
                             f"; got {self.method!r}")
        if not 0 < self.tolerance < 0.1:
            raise SceneError("free_surface.tolerance", "must lie in (0, 0.1) (the largest move of "
                             f"the surface over the exit half-size); got {self.tolerance}")
        if not 1 <= self.max_updates <= 50:
            raise SceneError("free_surface.max_updates",
                             f"must be an integer in [1, 50]; got {self.max_updates}")

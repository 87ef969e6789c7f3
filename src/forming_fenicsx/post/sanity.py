"""Physical sanity of a run, checked after every run: what a converged iteration can still get
wrong.

Each check reads the run's summary and gives a :class:`Finding`: a warning (the answer may be off;
the run still counts as converged) or a failure (the answer cannot be right: the run counts as not
converged and the command exits with 3). Every message names what was measured, the likely cause
and the fix that fits the scene's settings; a ``cause`` (the law's rate window, drawability) is
checked before the symptoms it explains. Thresholds (docs/sanity.md gives the values measured on
correct and broken runs):

| check | warning above | failure above |
|---|---|---|
| plastic work at rates above rate2 of (4.5) | 10 % | |
| plastic work in a law's linear branch (below rate1 of (4.5), below a rate_floor) | 50 % | |
| die_penetration (inflow into the die / throughput); rolling's | 1 %; 0.2 % | 5 % |
| relative_divergence, penalty formulation | 0.1 | 0.5 |
| volume_change (volume gained or lost / throughput), penalty formulation | 1 % | 5 % |
| drawing stress / yield stress of the drawn product | 0.9 | 0.99 |
| exit_zone_rate_ratio (product deforming after the die) | | 0.1 |
| a hardening law's largest strain gained / the ideal strain ln(A0/A1) | 5 | 10 |
| a hardening law's strain below the entry strain / the ideal strain | 0.5 | |
| free_surface_crossing | 5 % | 20 % |
| factor friction where the die is not pressed, over the product's section / answer | 1 % | |
| rolling: friction at a rate-sensitive metal's shear strength / the friction's torque | 10 % | |
| die_contact_fraction | | 0 (no contact at all) |
| estimated linear-solve error / solver.tolerance | 1 % | |
| force_balance_residual (x forces of the driving face, the die and Gamma5) | 1 % | 5 % |
| [thermal] highest temperature / solidus (kelvin) | 0.95 | 1 |
| [thermal] lowest temperature below the coldest inflow, tool or air (K) | 1 | 10 |
| [thermal] energy-balance residuals (heat, global) | 1 % | 5 % |
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from forming_fenicsx.config.scene import Scene
from forming_fenicsx.config.sections import D_RELATIVE
from forming_fenicsx.physics.friction import STICKING_RATE_SENSITIVITY
from forming_fenicsx.physics.rolling_slab import bite_limit
from forming_fenicsx.solvers.secant import ILL_CONDITIONED

PENETRATION = (0.01, 0.05)
# rolling: the forward slip is a small difference of speeds that the flow into the rolls moves
# (a copper slab 8 -> 5 mm at 0.55 %: forward slip 2.7 % and roll force 0.7 % low; docs/rolling.md)
ROLLING_PENETRATION = (0.002, 0.05)
COMPRESSIBLE = (0.1, 0.5)
VOLUME_CHANGE = (0.01, 0.05)
DRAWING_LIMIT = (0.9, 0.99)
STOCK_YIELD = (0.8, 1.0)     # back tension over the stock's yield stress in tension
EXIT_ZONE_RIGID = 0.1
STRAIN_GAINED = (5.0, 10.0)  # the largest strain gained over the ideal strain
STRAIN_UNDERSHOOT = 0.5      # the entry strain less the smallest, over the ideal strain
# a strain gained, over the ideal strain, that no flow of the pass gives: a stopped iterate's
# transport (4e27 at the entry face of a wire stopped on Debian 13; the square die's runaway, a
# flow's, gained 29 times it)
STRAIN_NOT_A_FLOWS = 1e6
FREE_SURFACE = (0.05, 0.2)
UNPRESSED_FRICTION = 0.01
STRENGTH_FRICTION = 0.1
ABOVE_RATE2 = 0.1
BELOW_FLOOR = 0.5
FORCE_BALANCE = (0.01, 0.05)
SOLIDUS = (0.95, 1.0)        # highest temperature over the solidus, both in kelvin
UNDERCOOLED = (1.0, 10.0)    # K below the coldest temperature entering or around the workpiece
ENERGY_BALANCE = (0.01, 0.05)
KELVIN = 273.15
# a [thermal] temperature below this (kelvin) is most likely one meant in Celsius: only cryogenic
# forming (liquid nitrogen, 77 K) works so cold
CELSIUS_SLIP = 150.0


@dataclass(frozen=True)
class Finding:
    """One check's verdict: ``failure`` when the answer cannot be right; ``cause`` when it names
    why a run went wrong (the headline of a run that also failed to converge)."""

    check: str
    message: str
    failure: bool = False
    cause: bool = False


def _graded(check: str, value: float, levels: tuple[float, float], message: str
            ) -> Finding | None:
    """A warning above levels[0], a failure above levels[1], else None."""
    if not value > levels[0]:
        return None
    return Finding(check, message, failure=value > levels[1])


def product_name(scene: Scene) -> str:
    """What the process makes, named for its shape: a drawn wire or an extruded rod (round,
    axisymmetric or the 3D quarter of one), a bar (3D, rectangular section), or a strip (plane
    strain)."""
    g, drawing = scene.geometry, scene.process.kind == "drawing"
    if scene.process.kind == "rolling":
        return "rolled strip"
    shape = ("wire" if drawing else "rod") if g.round else "bar" if g.three_dimensional \
        else "strip"
    return f"{'drawn' if drawing else 'extruded'} {shape}"


def die_penetration(summary: dict[str, Any], scene: Scene, converged: bool) -> Finding | None:
    """Inflow into the die: the advice follows the scene's contact settings."""
    penalty = scene.penalty
    rolling = scene.process.kind == "rolling"
    tool = "the rolls" if rolling else "the die"
    if not penalty.augmented:
        fix = (f"Use penalty.augmented = true (a multiplier carries the pressure and the workpiece "
               f"does not enter {tool}), or a smaller penalty.d_N_relative (now "
               f"{penalty.d_N_relative:.3g})")
    elif not converged:
        fix = ("The contact is augmented, so a converged run does not let the workpiece through: "
               "its multiplier had not settled when the iteration stopped (the reason says why)")
    else:
        fix = ("The augmented contact's multiplier stops updating when it changes by less than "
               "100 solver.tolerance: use a smaller solver.tolerance")
    effect = ("the strip loses that share of its flow into the rolls, and its exit speed, "
              "forward slip and roll force come out low (a copper slab 8 -> 5 mm at 0.55 %: "
              "forward slip 9.41 % against the augmented contact's 9.68 %, roll force 0.7 % "
              "low; augmented, it took 27 solves instead of 20)" if rolling else
              "the workpiece passes through the die instead of being formed by it")
    return _graded("die_penetration", summary["die_penetration"],
                   ROLLING_PENETRATION if rolling else PENETRATION,
                   f"{100 * summary['die_penetration']:.3g} % of the throughput flows into "
                   f"{tool} (u_N > 0 on Gamma3; contact penalty "
                   f"d_N = {penalty.d_N:.3g}, {penalty.d_N_relative:.3g} times U/sigma0): "
                   f"{effect}. {fix}")


def compressibility(summary: dict[str, Any], scene: Scene, found: list[Finding]
                    ) -> Finding | None:
    """The volume change the penalty leaves (Theorem 3.1), locally (||div u||/||e(u)||) and in the
    whole (the throughput's change, volume_change), with the causes the scene shows."""
    if scene.discretisation.formulation != "penalty":
        return None
    value, penalty = summary["relative_divergence"], scene.penalty
    change = abs(summary["volume_change"])
    causes = []
    if any(f.check == "die_penetration" for f in found):
        causes.append("the die lets the workpiece through (above), so it is squeezed instead of "
                      "formed")
    if penalty.d_relative > 0.01:
        causes.append(f"penalty.d = {penalty.d:.3g} is {penalty.d_relative:.3g} times "
                      "rate0/sigma0, a soft volumetric penalty: use a smaller "
                      "penalty.d_relative or leave penalty.d out (default "
                      f"{D_RELATIVE:g}; Theorem 3.1: the error falls like O(d))")
    discretisation = scene.discretisation
    if discretisation.element == "Q1" and discretisation.volumetric_integration == "complete":
        causes.append("Q1 with complete integration of the penalty locks: use reduced integration "
                      "or Q2")
    if not causes:
        causes.append(f"penalty.d = {penalty.d:.3g} ({penalty.d_relative:.3g} times "
                      "rate0/sigma0): use a smaller one, or discretisation.formulation = "
                      "\"mixed\", which keeps the volume")
    if not (value > COMPRESSIBLE[0] or change > VOLUME_CHANGE[0]):
        return None
    failed = value > COMPRESSIBLE[1] or change > VOLUME_CHANGE[1]
    return Finding("compressibility",
                   f"the material compresses: the outflow differs from the inflow by "
                   f"{100 * change:.3g} % of the throughput (volume_change) and ||div u||/||e(u)|| "
                   f"= {value:.2g}; the velocities and volumes are those of a compressible "
                   f"material. Cause: {'; '.join(causes)}", failure=failed)


def stock_yield(summary: dict[str, Any], scene: Scene, converged: bool = True
                ) -> Finding | None:
    """A back tension (drawing's process.applied_force > 0 on the entry face, rolling's
    process.back_tension) against the stock's yield stress in tension at its entry strain (2k in
    plane strain, sigma0 for a round or 3D bar). In rolling the stock's crossing is what the
    strip's entry speed misses of continuity (the annealed copper demo: 2.55 %, docs/rolling.md).
    Near it the stock narrows before the die, which the fixed domain does not follow (an annealed
    steel wire: the stock's crossing 1.3 % without tension, 3.8 % at 0.91; at 0.94 its Newton
    iteration stopped as ill-conditioned on one mesh, docs/sanity.md). Above it a hardening stock
    stretches until it carries the tension; a stock that does not harden yields without end (no
    steady drawing: a failure). A cause: a run that stops is explained by it first (without the
    free-surface hint: its first solve is this one)."""
    ratio = summary.get("stock_yield_ratio", math.nan)
    if not ratio > STOCK_YIELD[0]:
        return None
    plane = scene.geometry.symmetry == "plane_strain"
    hardening = summary.get("mean_entry_strain") is not None
    limit = ("2k" if plane else "sigma0") + (" at its entry strain" if hardening else "")
    rolling = scene.process.kind == "rolling"
    tool, verb = ("the rolls", "roll") if rolling else ("the die", "draw")
    key, back = (("process.back_tension", scene.process.back_tension) if rolling else
                 ("process.applied_force", scene.process.applied_force))
    failed = ratio > STOCK_YIELD[1] and not hardening
    tail = (f"it yields under it and, not hardening, stretches without end: no steady "
            f"{'rolling' if rolling else 'drawing'} exists" if failed else
            f"it yields under it and stretches before {tool} until it hardens to carry it"
            if ratio > STOCK_YIELD[1] else f"it narrows before {tool}, close to yielding")
    crossing = summary.get("free_surface_crossing_stock", math.nan)
    entry = (f" The strip thins before the bite, and {100 * crossing:.3g} % of the throughput "
             "enters through its surface, which the model holds at the entry thickness: "
             "entry_speed lies that much below exit_speed h1/h0." if rolling else "")
    return Finding("stock_yield",
                   f"the back tension {key} = {back:.4g} is "
                   f"{ratio:.3g} times the yield stress in tension of the stock ({limit}): {tail}."
                   f"{entry} The fixed domain keeps the stock's size, and near this limit the "
                   f"iteration may not converge: lower the back tension (below {STOCK_YIELD[0]:g} "
                   f"of that stress) or {verb} a stronger stock (material.initial_strain)"
                   + ("" if failed or not converged else _update_hint(scene)),
                   failure=failed, cause=True)


def strain_runaway(summary: dict[str, Any], scene: Scene, converged: bool = True
                   ) -> list[Finding]:
    """A hardening law's transported strain against what the pass gives: about the ideal strain
    ln(A0/A1) above the entry strain (at most 4.4 times it on the demos and their variants, a cold
    rod at m = 0.8). Far above it, material that barely moves (a dead zone, a surface held by
    friction) keeps straining in the steady state, grows harder than the flow around it, and the
    flow turns away from it: annealed copper through a square die converged at 2061 MPa, where the
    law without hardening at the pass's mean flow stress gives 742 (docs/hardening.md). A cause: a
    run that stops is explained by it first, unless the strain is beyond any flow's
    (STRAIN_NOT_A_FLOWS): then it is the stopped iterate's, a symptom. Below the entry strain: the
    transport's undershoot, where the law reads its strain floor's stress."""
    if "max_strain" not in summary or not summary.get("ideal_strain", 0.0) > 0:
        return []
    ideal, entry = summary["ideal_strain"], scene.inflow_strain
    found = []
    gained = (summary["max_strain"] - entry) / ideal
    at = ", ".join(f"{value:.4g}" for value in summary["max_strain_at"])
    if not converged and not gained <= STRAIN_NOT_A_FLOWS:
        found.append(Finding(
            "strain_runaway",
            f"the stopped iterate's transported strain reaches {summary['max_strain']:.3g} at "
            f"({at}), {gained:.3g} times the pass's ideal strain {ideal:.3g}: no flow of the pass "
            "strains material that far, not even a dead zone's. It is the transport of the "
            "unconverged iterate, and the strains, flow stresses and forces of the files are "
            "not the process's; the iteration's reason says what stopped it", failure=True))
    elif gained > STRAIN_GAINED[0]:
        failed = gained > STRAIN_GAINED[1]
        found.append(Finding(
            "strain_runaway",
            f"the transported strain reaches {summary['max_strain']:.3g} at ({at}), {gained:.3g} "
            f"times the pass's ideal strain {ideal:.3g} above the entry's {entry:.3g}: material "
            "that barely moves (a dead zone, or a surface held by friction) keeps straining in a "
            "steady state, grows harder than the flow around it, and the flow turns away from it. "
            + ("The flow and the forces are those of that runaway, not of the process"
               if failed else "The flow and the forces may be those of that runaway")
            + " (docs/hardening.md). Model the pass without hardening at the law's mean flow "
            f"stress over it (material.law = \"rate_power\", A = {scene.reference_flow_stress:.4g}"
            ", n = 0.001), or with a die that leaves no dead zone (a smaller die angle, less "
            "friction)", failure=failed, cause=True))
    under = (entry - summary["min_strain"]) / ideal
    if under > STRAIN_UNDERSHOOT:
        found.append(Finding(
            "strain_undershoot",
            f"the transported strain falls to {summary['min_strain']:.3g}, below the entry's "
            f"{entry:.3g} by {under:.3g} times the pass's ideal strain {ideal:.3g}: the "
            "transport's undershoot where the flow stagnates (a dead zone's corner), where the "
            "law reads its strain floor's stress, softer than the metal. Its effect on the "
            "forces is not measured: compare a run on a finer mesh"))
    return found


def drawability(summary: dict[str, Any], scene: Scene, found: list[Finding]) -> list[Finding]:
    """The product must leave the die rigid. A drawn product's stress must stay below its yield
    stress in tension (2k = 2 sigma0/sqrt3 in plane strain, sigma0 for a round or 3D bar): when it
    reaches it the product yields after the die and the pass cannot be drawn (the ideal work
    reaches it at a reduction of 1 - 1/e = 63 %). A law in its linear (viscous) branch stretches
    the product under any load: then the cause is the rate window (``found``)."""
    product, drawing = product_name(scene), scene.process.kind == "drawing"
    ratio = summary["exit_zone_rate_ratio"]
    yields = math.isfinite(ratio) and ratio > EXIT_ZONE_RIGID
    window = next((f for f in found if f.check == "rate_window"), None)
    stress_ratio = summary.get("product_yield_ratio", math.nan) if drawing else math.nan
    limit = ("2k, a plane-strain strip" if scene.geometry.symmetry == "plane_strain" else
             "sigma0, a round bar" if scene.geometry.round else "sigma0, a bar in tension")
    stress = (f"the drawing stress {summary['drawing_stress']:.4g} is {stress_ratio:.3f} times the "
              f"yield stress in tension of the {product} ({limit})") if drawing else ""
    size = scene.geometry.thickness_name if scene.geometry.three_dimensional else "thickness"
    rigid = (f"its mean strain rate over the last exit {size} is {ratio:.3g} times the "
             f"workpiece's mean, where a rigid product has below {EXIT_ZONE_RIGID:g}")
    if yields and window is not None:
        return [Finding("exit_zone", f"the {product} deforms after the die ({rigid}) because "
                        "the flow law is viscous at this velocity: " + window.message, failure=True,
                        cause=True)]
    if yields and drawing and stress_ratio > DRAWING_LIMIT[0]:
        return [Finding("drawability", f"not drawable: {stress}, and the {product} yields "
                        f"after the die ({rigid}). No steady drawing exists at this reduction "
                        f"({100 * summary.get('reduction', math.nan):.3g} %) and friction: reduce "
                        "the reduction per pass (the ideal limit is 63 %; real passes stay below "
                        "about 35 %) or the friction", failure=True, cause=True)]
    if yields:
        load = "the drawing force" if drawing else "the back force on the product (Gamma5)" \
            if scene.process.applied_force else "the front tension" \
            if scene.process.front_tension else "the flow"
        return [Finding("exit_zone", f"the {product} deforms after the die: {rigid}. It yields "
                        f"under {load}: not a steady process. Check process.applied_force and the "
                        "die (a product that leaves the land still converging), or refine the mesh "
                        "at the die exit", failure=True)]
    if not drawing:
        return []
    finding = _graded("drawability", stress_ratio, DRAWING_LIMIT, f"{stress}: ")
    if finding is None:
        return []
    tail = ("it yields after the die, so no steady drawing exists at this reduction and friction "
            "(not drawable): reduce the reduction or the friction" if finding.failure else
            "close to the drawing limit, where the product may neck; industrial passes stay below "
            "about 0.6 to 0.8")
    return [Finding(finding.check, finding.message + tail, finding.failure, finding.failure)]


def free_surfaces(summary: dict[str, Any], scene: Scene) -> Finding | None:
    """Flow across the free surfaces of the fixed domain (2.6)."""
    value = summary["free_surface_crossing"]
    causes = ("the stock yields before the bite (a soft stock, a back tension: entry_speed then "
              "misses continuity with exit_speed h1/h0 by the stock's share), the strip yields "
              "after the roll gap (a front tension), or a coarse mesh (refine "
              "discretisation.mesh_size)" if scene.process.kind == "rolling" else
              "the product yields after the die, the die leaves a gap the fixed domain ignores, "
              "or a coarse mesh (the crossing falls like the mesh size: refine "
              "discretisation.mesh_size)")
    return _graded("free_surface_crossing", value, FREE_SURFACE,
                   f"{100 * value:.3g} % of the throughput crosses the free surfaces of the fixed "
                   "domain (2.6): the real free surface lies elsewhere and the forces are those "
                   f"of another shape. Usual causes: {causes}" + _update_hint(scene))


def unpressed_friction(summary: dict[str, Any], scene: Scene) -> Finding | None:
    """The friction factor's m k (in rolling also sticking's penalised slip) on the die where the
    workpiece does not press on it (a land or bearing the product would leave): its x-force taken
    over the product's section, the back pull it puts on the pass, against the answer (drawing:
    that force over the drawing force; extrusion: over the ram force times A1/A0)."""
    if scene.process.kind == "rolling":
        return _unpressed_roll(summary, scene)
    force = summary.get("unpressed_friction_force_x", 0.0)
    if not force > 0:
        return None
    drawing = scene.process.kind == "drawing"
    share = force / (summary["drawing_force"] if drawing
                     else summary["ram_force"] * scene.geometry.area_ratio)
    if not share > UNPRESSED_FRICTION:
        return None
    product = product_name(scene)
    end = summary.get("contact_end_x")
    where = f"; the contact ends at x = {end:.4g}" if end is not None and math.isfinite(end) \
        else ""
    answer = "drawing stress" if drawing else "ram pressure"
    hint = "" if not _update_applies(scene) else (
        "; free_surface.update = true lets the contact decide where the product leaves the die "
        "(docs/free_surface.md)")
    return Finding("unpressed_friction",
                   f"the friction factor's m k acts where the {product} does not press on the die "
                   f"(its contact pressure is zero there{where}): that friction's force over the "
                   f"{product}'s section is about {100 * share:.2g} % of the {answer}. The fixed "
                   f"domain holds the {product} on the die where it would leave it, and the factor "
                   "law, unlike Coulomb's mu p, does not vanish with the pressure" + hint)


def _unpressed_roll(summary: dict[str, Any], scene: Scene) -> Finding | None:
    """Rolling's: the friction factor's (or sticking's) torque where the strip does not press on
    the roll (the end of the arc it leaves at its exit thickness) against the roll torque."""
    torque, total = summary.get("unpressed_friction_torque", 0.0), summary["roll_torque"]
    share = abs(torque) / abs(total) if total else 0.0
    if not share > UNPRESSED_FRICTION:
        return None
    acts, law = (("sticking friction", "sticking") if scene.friction.sticks else
                 ("the friction factor's m k", "the factor law"))
    return Finding("unpressed_friction",
                   f"{acts} acts where the rolled strip does not press on the rolls (its contact "
                   "pressure is zero there, near the exit): that friction's torque is about "
                   f"{100 * share:.2g} % of the roll torque. The roll gap holds the strip on the "
                   f"rolls there, and {law}, unlike Coulomb's mu p, does not vanish with the "
                   "pressure: Coulomb friction (friction.law = \"coulomb\") gives none there")


def friction_at_strength(summary: dict[str, Any], scene: Scene) -> Finding | None:
    """Rolling: the share of the friction's torque given at a rate-sensitive metal's shear
    strength k (the factor law at m = 1, or Coulomb's cap at k), where the slip regularisation
    d_T splits the slip between the interface and the metal under it: the roll force then moved
    by 0.3 to 1 % when d_T doubled at rate sensitivities of 0.1 to 0.25, 0.02 % at 0.011
    (docs/sanity.md)."""
    share = summary.get("friction_at_strength_share", 0.0)
    if not share > STRENGTH_FRICTION:
        return None
    law = scene.friction
    half = f"friction.d_T_relative = {law.d_T_relative / 2:.3g} (half of this run's)"
    fix = (f"Rerun with {half} to see how far: the answer moves toward its d_T -> 0 limit, "
           "which lay 0.7 to 3.5 % above steel passes' defaults at m = 1. Sticking holds the "
           "strip to the rolls: that limit on a metal that does not harden, in about 10 linear "
           "solves, and m = 1 is solved as it by default there from a rate sensitivity of "
           f"{STICKING_RATE_SENSITIVITY:g} (friction.sticks; docs/rolling.md)"
           if law.law == "factor" else
           "With friction.shear_limit = false (the default on a rate-sensitive metal) the metal "
           "under the surface bounds the friction at its own rate, and d_T moves the roll force "
           f"by 0.1 % or less; or rerun with {half} to see how far")
    return Finding("friction_at_strength",
                   "the friction stress reaches the metal's shear strength k over "
                   f"{100 * share:.2g} % of the friction's torque on the rolls, and the metal is "
                   "rate-sensitive (d ln sigma_p / d ln rate = "
                   f"{scene.rate_sensitivity:.2g} at the "
                   "process strain rate): there the slip regularisation friction.d_T decides how "
                   "the slip splits between the interface and the metal under it, and the roll "
                   "force moved by 0.3 to 1 % when d_T doubled at rate sensitivities of 0.1 to "
                   f"0.25 (0.02 % at 0.011). {fix}")


def _update_applies(scene: Scene) -> bool:
    """Whether the free-surface update can move this scene's surfaces and is off (2D, the
    scene's own geometry, not rolling)."""
    g = scene.geometry
    return not (scene.free_surface.update or g.three_dimensional or g.mesh_file is not None
                or scene.process.kind == "rolling")


def _update_hint(scene: Scene) -> str:
    """Where the free-surface update applies and is off: the surfaces it can move (the stock's
    too before a drawing die)."""
    if not _update_applies(scene):
        return ""
    surfaces = ("the stock's and the product's surfaces streamlines"
                if scene.process.kind == "drawing" else "the product's surface a streamline")
    return (f"; free_surface.update = true makes {surfaces} of the flow (docs/free_surface.md)")


def die_contact(summary: dict[str, Any], scene: Scene) -> Finding | None:
    """A die that the workpiece does not touch at all."""
    fraction = summary["die_contact_fraction"]
    if not (math.isfinite(fraction) and fraction <= 0):
        return None
    return Finding("die_contact", "the workpiece does not touch the die anywhere (no point of "
                   "Gamma3 with u_N > 0): the die carries no load and the process force is not "
                   "that of forming. Check process.velocity (its sign and where process.drive "
                   "applies it) and the die geometry", failure=True)


def rate_window(summary: dict[str, Any], scene: Scene) -> list[Finding]:
    """Every law is linear (viscous) below its rate floor (rate1 of (4.5)), and (4.5) also above
    rate2: the plastic work done there is that of a fluid, not of the nearly rate-independent
    metal the law describes."""
    law, found = scene.material, []
    above = summary.get("dissipation_above_rate2", 0.0)
    below = summary.get("dissipation_below_rate1",
                        summary.get("dissipation_below_rate_floor", 0.0))
    velocity = f"process.velocity = {scene.process.velocity:g}"
    if above > ABOVE_RATE2:
        found.append(Finding("rate_window", f"{100 * above:.3g} % of the plastic work is done "
                             f"at strain rates above material.rate2 = {law.rate2:g}, where the law "
                             "(4.5) turns linear and the flow stress grows in proportion to the "
                             f"rate: at {velocity} the process runs in the law's viscous branch. "
                             "Raise material.rate2 (it is in the scene's time unit) unless the "
                             "material is that rate sensitive, or check process.velocity",
                             cause=True))
    if below > BELOW_FLOOR:
        key = "material.rate1" if hasattr(law, "rate1") else "material.rate_floor"
        found.append(Finding("rate_window", f"{100 * below:.3g} % of the plastic work is done "
                             f"at strain rates below {key} = {law.rate_floor:g}, where the law is "
                             f"linear (a viscous fluid, not a plastic metal): at {velocity} the "
                             f"process runs in the wrong branch of the law. Lower {key} (it is in "
                             "the scene's time unit) or check process.velocity", cause=True))
    return found


def solve_accuracy(summary: dict[str, Any], scene: Scene) -> Finding | None:
    """Linear solves whose estimated error is not small beside the iteration's tolerance."""
    error = summary["solve_error_estimate"]
    if not error > ILL_CONDITIONED * scene.solver.tolerance:
        return None
    return Finding("solve_accuracy", "ill-conditioned linear systems: estimated relative error of "
                   f"a solve {error:.1e}, above {ILL_CONDITIONED:.0%} of solver.tolerance; use "
                   "larger penalty parameters (penalty.d_relative, penalty.d_N_relative, "
                   "friction.d_T_relative)")


def force_balance(summary: dict[str, Any], scene: Scene, converged: bool = True
                  ) -> Finding | None:
    """The x forces on the workpiece must balance (verification.md): a driving force that differs
    from the die's by percents is not the force of this flow, whatever the increment says. An
    iteration that stopped did not get there: its reason, not the tolerance, says what to change."""
    value = summary["force_balance_residual"]
    fix = ("The iteration stopped before they balance: what its reason advises comes first"
           if not converged else
           "Set solver.force_tolerance (e.g. 1e-3) so the iteration goes on until they balance"
           if scene.solver.force_tolerance == 0 else "Lower solver.force_tolerance")
    return _graded("force_balance", value, FORCE_BALANCE,
                   f"the x forces do not balance: |driving + applied - die| is {100 * value:.3g} % "
                   "of the driving force, so the reported forces and stresses are not those of one "
                   f"flow. {fix}" + (", or try solver.method = \"direct\"" if converged else ""))


def _temperature(kelvin: float) -> str:
    return f"{kelvin:.1f} K ({kelvin - KELVIN:.1f} C)"


def heat(summary: dict[str, Any], scene: Scene) -> list[Finding]:
    """[thermal]: its temperatures are kelvin (one below CELSIUS_SLIP was likely meant in Celsius),
    a solid workpiece stays below its solidus, no colder than what enters or surrounds it (no heat
    sink inside), and its energy balances close."""
    thermal = scene.thermal
    if thermal is None or "max_temperature" not in summary:
        return []
    found = [Finding("kelvin_temperature",
                     f"thermal.{key} = {value:g} K is {value - KELVIN:.2f} C: [thermal] "
                     "temperatures are in kelvin whatever units.temperature shows (a temperature "
                     f"meant in Celsius needs + {KELVIN}); colder than {CELSIUS_SLIP:g} K only "
                     "cryogenic forming runs")
             for key, value in thermal.surroundings().items() if value < CELSIUS_SLIP]
    hottest, coldest = summary["max_temperature"], summary["min_temperature"]
    if thermal.solidus is not None:
        finding = _graded("melting", hottest / thermal.solidus, SOLIDUS,
                          f"the workpiece reaches {_temperature(hottest)}, "
                          f"{hottest / thermal.solidus:.3f} of its solidus "
                          f"{_temperature(thermal.solidus)} in kelvin: ")
        if finding is not None:
            tail = ("it melts, and a rigid-plastic solid is not a model of it. The plastic and "
                    "friction heat grow with the velocity (here process.velocity = "
                    f"{scene.process.velocity:g}): lower it, or the inflow temperature"
                    if finding.failure else "close to melting (incipient melting, hot shortness, "
                    "speed cracking): lower process.velocity or the inflow temperature")
            found.append(Finding("melting", finding.message + tail, finding.failure))
    below = thermal.coldest - coldest
    finding = _graded("temperature_undershoot", below, UNDERCOOLED,
                      f"the workpiece's lowest temperature {_temperature(coldest)} lies "
                      f"{below:.3g} K below the coldest temperature entering or around it "
                      f"({_temperature(thermal.coldest)}), which no steady heat flow can give: the "
                      "discrete temperature oscillates (a boundary layer thinner than the mesh); "
                      "refine discretisation.mesh_size")
    found += [finding] if finding is not None else []
    balance = summary.get("energy_balance", {})
    for key, name in (("residual", "heat balance (heat out against heat generated)"),
                      ("global_residual", "energy balance (driving power against heat out and "
                                          "work stored)")):
        value = balance.get(key, math.nan)
        finding = _graded("energy_balance", abs(value), ENERGY_BALANCE,
                          f"the {name} is off by {100 * value:.3g} %: the temperature is not that "
                          "of this flow's heat; refine discretisation.mesh_size (steep thermal "
                          "boundary layers at high Peclet numbers) or lower solver.tolerance")
        found += [finding] if finding is not None else []
    return found


# an entry speed beyond this many times the rolls' is the iteration's, not a strip's: a back
# tension of 150 MPa on the demo strip left it at -7.4e5, a front tension of 155 MPa on the
# aluminium pass at 66.8 (docs/rolling.md)
RUNAWAY_SPEED = 10.0


def bite(summary: dict[str, Any], scene: Scene) -> Finding | None:
    """Rolling: the strip's slip on the rolls must change sign along the arc (the neutral point);
    without one the rolls skid on the strip (too little friction for the bite, or a tension that
    pulls the strip through or holds it back), and no steady rolling exists. The message names the
    slab solution's limit (rolling_slab.bite_limit) for a Coulomb law."""
    if scene.process.kind != "rolling" or math.isfinite(summary.get("neutral_x", math.nan)):
        return None
    g, process, law = scene.geometry, scene.process, scene.friction
    speed = summary.get("entry_speed", math.nan) / process.velocity
    limit = ""
    fix = "Raise the friction, reduce the draft (a smaller bite angle) or lower the tensions"
    if law.law == "coulomb":
        k = scene.reference_flow_stress / math.sqrt(3.0)
        mu = bite_limit(g.roll_radius, g.entry_thickness, g.exit_thickness,
                        process.back_tension / k, process.front_tension / k)
        if math.isfinite(mu):
            limit = (f"; friction.mu = {law.mu:.3g}, and the slab solution needs mu above "
                     f"{mu:.3g} here (about tan(alpha/2) = {math.tan(g.bite_angle / 2):.3g} "
                     "without tensions)")
        else:
            limit = (f"; the slab solution rolls it at no friction coefficient: its tensions "
                     f"(front {process.front_tension:.4g}, back {process.back_tension:.4g}) "
                     "against the strip's yield stress in plane-strain tension, 2k = "
                     f"{2 * k:.4g} at the pass's mean flow stress, are "
                     f"{process.front_tension / (2 * k):.3g} and "
                     f"{process.back_tension / (2 * k):.3g} of it")
            fix = ("Lower the tensions: near the strip's yield stress no friction or draft rolls "
                   "it")
    if 0.0 <= speed <= RUNAWAY_SPEED:
        entry = f"the strip enters at {speed:.3g} times the rolls' speed"
    else:  # no steady strip enters backwards or at ten times the rolls' speed
        entry = (f"the iteration ran away with the strip's speed, which it left at {speed:.3g} "
                 "times the rolls'")
    return Finding("bite", "the rolls do not draw the strip through the bite: its slip on the "
                   f"rolls does not change sign along the arc (no neutral point; {entry}). The "
                   f"bite angle is {g.die_angle:.3g} deg{limit}. {fix}", failure=True,
                   cause=True)


def check_run(summary: dict[str, Any], scene: Scene, converged: bool = True) -> list[Finding]:
    """Every check, a cause before its symptoms; ``converged``: whether the iteration converged
    (the advice differs)."""
    found = [f for f in (bite(summary, scene),) if f is not None]
    found += rate_window(summary, scene)
    found += [f for f in (die_penetration(summary, scene, converged), die_contact(summary, scene))
              if f is not None]
    found += [f for f in (compressibility(summary, scene, found),
                          stock_yield(summary, scene, converged)) if f is not None]
    found += strain_runaway(summary, scene, converged)
    found += drawability(summary, scene, found)
    found += heat(summary, scene)
    found += [f for f in (free_surfaces(summary, scene), unpressed_friction(summary, scene),
                          friction_at_strength(summary, scene), solve_accuracy(summary, scene),
                          force_balance(summary, scene, converged)) if f is not None]
    return found

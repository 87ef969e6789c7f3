"""Physical sanity of a run, checked after every run: what a converged iteration can still get wrong.

Each check reads the run's summary and gives a :class:`Finding`: a warning (the answer may be off; the
run still counts as converged) or a failure (the answer cannot be right: the run counts as not
converged and the command exits with 3). Every message names what was measured, the likely cause and
the fix. Thresholds (docs/sanity.md gives the values measured on correct and broken runs):

| check | warning above | failure above |
|---|---|---|
| die_penetration (inflow into the die / throughput) | 1 % | 5 % |
| relative_divergence, penalty formulation | 0.1 | 0.5 |
| drawing stress / yield stress of the drawn product | 0.9 | 0.99 |
| exit_zone_rate_ratio (product deforming after the die) | | 0.1 |
| free_surface_crossing | 5 % | 20 % |
| die_contact_fraction | | 0 (no contact at all) |
| plastic work at rates above rate2 of (4.5) | 10 % | |
| plastic work at rates below rate1 of (4.5) | 50 % | |
| estimated linear-solve error / solver.tolerance | 1 % | |
| force_balance_residual (x forces of the driving face, the die and Gamma5) | 1 % | 5 % |
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from .scene import D_N_RELATIVE, D_RELATIVE, Scene
from .solvers import ILL_CONDITIONED

PENETRATION = (0.01, 0.05)
COMPRESSIBLE = (0.1, 0.5)
DRAWING_LIMIT = (0.9, 0.99)
EXIT_ZONE_RIGID = 0.1
FREE_SURFACE = (0.05, 0.2)
ABOVE_RATE2 = 0.1
BELOW_RATE1 = 0.5
FORCE_BALANCE = (0.01, 0.05)


@dataclass(frozen=True)
class Finding:
    """One check's verdict: ``failure`` when the answer cannot be right."""

    check: str
    message: str
    failure: bool = False


def _graded(check: str, value: float, levels: tuple[float, float], message: str) -> Finding | None:
    if not value > levels[0]:
        return None
    return Finding(check, message, failure=value > levels[1])


def die_penetration(summary: dict[str, Any], scene: Scene) -> Finding | None:
    penalty = scene.penalty
    return _graded("die_penetration", summary["die_penetration"], PENETRATION,
                   f"{100 * summary['die_penetration']:.3g} % of the throughput flows into the die (u_N > 0 on "
                   f"Gamma3): the contact penalty d_N = {penalty.d_N:.3g} ({penalty.d_N_relative:.3g} times "
                   f"U/sigma0) is too soft for this die pressure, and the workpiece passes through the die "
                   f"instead of being formed by it. Use a smaller penalty.d_N_relative, or leave penalty.d_N "
                   f"out and penalty.augmented at its default (true: augmented contact with a relative d_N of "
                   f"{D_N_RELATIVE:g}, which does not let the workpiece through)")


def compressibility(summary: dict[str, Any], scene: Scene, found: list[Finding]) -> Finding | None:
    if scene.discretisation.formulation != "penalty":
        return None
    value, penalty = summary["relative_divergence"], scene.penalty
    causes = []
    if any(f.check == "die_penetration" for f in found):
        causes.append("the die lets the workpiece through (above), so it is squeezed instead of formed")
    if penalty.d_relative > 0.01:
        causes.append(f"penalty.d = {penalty.d:.3g} is {penalty.d_relative:.3g} times rate0/sigma0, a soft "
                      f"volumetric penalty: use a smaller penalty.d_relative or leave penalty.d out (default "
                      f"{D_RELATIVE:g}; Theorem 3.1: the error falls like O(d))")
    if scene.discretisation.element == "Q1" and scene.discretisation.volumetric_integration == "complete":
        causes.append("Q1 with complete integration of the penalty locks: use reduced integration or Q2")
    if not causes:
        causes.append(f"penalty.d_relative = {penalty.d_relative:.3g}: use a smaller one")
    return _graded("compressibility", value, COMPRESSIBLE,
                   f"the material compresses: ||div u||/||e(u)|| = {value:.2g}; the results are those of a "
                   f"compressible material. Cause: {'; '.join(causes)}")


def drawability(summary: dict[str, Any], scene: Scene) -> list[Finding]:
    """The drawn product must leave the die rigid: its stress below its yield stress in tension (2k =
    2 sigma0/sqrt3 in plane strain, sigma0 for a round bar), and its strain rate near zero after the die."""
    found = []
    ratio = summary["exit_zone_rate_ratio"]
    if math.isfinite(ratio) and ratio > EXIT_ZONE_RIGID:
        product = "drawn strip" if scene.process.kind == "drawing" else "extruded product"
        found.append(Finding("exit_zone", f"the {product} deforms after the die: its mean strain rate over the last "
                             f"exit thickness is {ratio:.3g} times the workpiece's mean (a rigid product: below "
                             f"{EXIT_ZONE_RIGID:g}). It yields under the load that pulls or pushes it: not a steady "
                             "process. Reduce the reduction, the die angle, the friction or the back force",
                             failure=True))
    if scene.process.kind == "drawing":
        stress, ratio = summary["drawing_stress"], summary["product_yield_ratio"]
        finding = _graded("drawability", ratio, DRAWING_LIMIT,
                          f"the drawing stress {stress:.4g} is {ratio:.3f} times the yield stress in tension "
                          f"of the drawn product ({'sigma0, a round bar' if scene.geometry.axisymmetric else '2k, a plane-strain strip'}): ")
        if finding is not None:
            tail = ("it yields after the die, so no steady drawing exists at this reduction and friction (not "
                    "drawable): reduce the reduction or the friction" if finding.failure else
                    "close to the drawing limit, where the product may neck; industrial passes stay below "
                    "about 0.6 to 0.8")
            found.append(Finding(finding.check, finding.message + tail, finding.failure))
    return found


def free_surfaces(summary: dict[str, Any], scene: Scene) -> Finding | None:
    value = summary["free_surface_crossing"]
    return _graded("free_surface_crossing", value, FREE_SURFACE,
                   f"{100 * value:.3g} % of the throughput crosses the free surfaces of the fixed domain (2.6): "
                   "the real free surface lies elsewhere and the forces are those of another shape. Usual "
                   "causes: the product yields after the die, the die leaves a gap the fixed domain ignores, "
                   "or a coarse mesh (the crossing falls like the mesh size: refine discretisation.mesh_size)")


def die_contact(summary: dict[str, Any], scene: Scene) -> Finding | None:
    fraction = summary["die_contact_fraction"]
    if not (math.isfinite(fraction) and fraction <= 0):
        return None
    return Finding("die_contact", "the workpiece does not touch the die anywhere (no point of Gamma3 with "
                   "u_N > 0): the die carries no load and the process force is not that of forming. Check "
                   "process.velocity (its sign and where process.drive applies it) and the die geometry",
                   failure=True)


def rate_window(summary: dict[str, Any], scene: Scene) -> list[Finding]:
    """Law (4.5) is nearly rate independent only between rate1 and rate2; outside it is linear."""
    law, found = scene.material, []
    above, below = summary.get("dissipation_above_rate2", 0.0), summary.get("dissipation_below_rate1", 0.0)
    if above > ABOVE_RATE2:
        found.append(Finding("rate_window", f"{100 * above:.3g} % of the plastic work is done at strain rates "
                             f"above material.rate2 = {law.rate2:g}, where the law (4.5) turns linear and the flow "
                             "stress grows in proportion to the rate: raise material.rate2 unless the material is "
                             "that rate sensitive"))
    if below > BELOW_RATE1:
        found.append(Finding("rate_window", f"{100 * below:.3g} % of the plastic work is done at strain rates "
                             f"below material.rate1 = {law.rate1:g}, where the law (4.5) is linear (a viscous "
                             f"fluid, not a plastic metal): at this velocity ({scene.process.velocity:g}) the "
                             "process runs in the wrong branch of the law. Lower material.rate1 (it is in the "
                             "scene's time unit) or check process.velocity"))
    return found


def solve_accuracy(summary: dict[str, Any], scene: Scene) -> Finding | None:
    error = summary["solve_error_estimate"]
    if not error > ILL_CONDITIONED * scene.solver.tolerance:
        return None
    return Finding("solve_accuracy", f"ill-conditioned linear systems: estimated relative error of a solve "
                   f"{error:.1e}, above {ILL_CONDITIONED:.0%} of solver.tolerance; use larger penalty parameters "
                   "(penalty.d_relative, penalty.d_N_relative, friction.d_T_relative)")


def force_balance(summary: dict[str, Any], scene: Scene) -> Finding | None:
    """The x forces on the workpiece must balance (verification.md): a driving force that differs
    from the die's by percents is not the force of this flow, whatever the increment says."""
    value = summary["force_balance_residual"]
    return _graded("force_balance", value, FORCE_BALANCE,
                   f"the x forces do not balance: |driving + applied - die| is {100 * value:.3g} % of "
                   "the driving force, so the reported forces and stresses are not those of one flow. "
                   "Set solver.force_tolerance (e.g. 1e-3) so the iteration goes on until they balance, "
                   "or try solver.method = \"direct\"")


def check_run(summary: dict[str, Any], scene: Scene) -> list[Finding]:
    """Every check, a cause before its symptoms."""
    found = [f for f in (die_penetration(summary, scene), die_contact(summary, scene)) if f is not None]
    found += [f for f in (compressibility(summary, scene, found),) if f is not None]
    found += drawability(summary, scene)
    found += [f for f in (free_surfaces(summary, scene), solve_accuracy(summary, scene),
                          force_balance(summary, scene)) if f is not None]
    return found + rate_window(summary, scene)

"""Why an iteration stopped and what to try, as the run reports it (SolveResult.reason): the text
apart from the algorithms (secant.py, newton.py), one function (or string) per reason or note,
named for it."""
from __future__ import annotations

import math

from forming_fenicsx.config.scene import Scene
from forming_fenicsx.solvers.records import IterationRecord

# what Newton's method did when it stopped, by SolveResult.cause
NEWTON_STOPPED = {"non_finite": "failed a solve or gave a non-finite iterate",
                  "diverging": "diverged", "stalled": "stalled",
                  "max_iterations": "did not converge in solver.max_iterations"}
ROUNDING = 1e-9  # relative: two products of the same numbers in another order


def recent(increments: list[float], count: int = 6) -> str:
    """The last ``count`` increments, for a message."""
    return ", ".join(f"{value:.2e}" for value in increments[-count:])


def penalties(scene: Scene) -> str:
    """The advice for ill-conditioned linear systems."""
    return (f"the penalties make K stiff (penalty.d = {scene.penalty.d:g}, penalty.d_N = "
            f"{scene.penalty.d_N:g}, friction.d_T = {scene.friction.d_T:g}); use larger ones")


def contact_note(scene: Scene, tolerance: float, method: str) -> str:
    """Why friction may not settle with a stiff contact penalty: an increment delta*U of the
    velocity moves the penalty normal stress u_N/d_N of (3.4), and with it the friction bound, by
    delta*U/d_N; when that exceeds the flow stress the iteration cannot resolve tau_f (measured on
    Example 2). Empty when it does not: rolling's default d_N = 1e-4 U/sigma0 puts it at the flow
    stress to rounding with delta = 1e-4, where the note told a strip that failed the bite to use
    the d_N it had."""
    flow = scene.reference_flow_stress
    noise = tolerance * abs(scene.process.velocity) / scene.penalty.d_N
    if noise <= flow * (1.0 + ROUNDING):
        return ""
    return (f"; with penalty.d_N = {scene.penalty.d_N:g} an increment of delta times the process "
            f"velocity moves the contact normal stress by {noise:.2g}, {noise / flow:.2g} times "
            f"the flow stress, so the friction bound cannot settle: use penalty.d_N >= "
            f"{tolerance * abs(scene.process.velocity) / flow:.2g}"
            + (" or the modified method" if method == "direct" else ""))


def secant_friction_note(scene: Scene, tolerance: float, method: str) -> str:
    """What a secant run with friction adds to a divergence or stall."""
    return ("; at this friction coefficient the solution may not be unique"
            f"{contact_note(scene, tolerance, method)}")


def newton_friction_note(scene: Scene, tolerance: float, method: str) -> str:
    """What a Newton run with friction adds to a divergence or stall."""
    return f"; friction may make the solution non-unique{contact_note(scene, tolerance, method)}"


def linear_solve_failed(outer: int, inner: int, error: Exception) -> str:
    hint = "" if "solver.linear" in str(error) else (
        ". Try a larger penalty parameter (penalty.d, penalty.d_N) or friction.d_T, or MUMPS LU "
        "(solver.petsc_options.pc_type = \"lu\")")
    return (f"linear solve failed at outer {outer}, inner {inner}: {error}; the results are the "
            f"previous iterate{hint}")


def newton_solve_failed(failure: str, error: Exception) -> str:
    """The reason of a run that ends where Newton's linear solve failed (``failure``:
    newton_linear_failure's), with what to try unless the error names the linear solver."""
    hint = "" if "solver.linear" in str(error) else (
        ". Try a secant method or larger penalty parameters")
    return f"{failure}; the results are the previous iterate{hint}"


def stop_requested(stop: str, outer: int, inner: int) -> str:
    return f"{stop} at outer {outer}, inner {inner}; the last completed iterate is written"


def ill_conditioned(solve_error: float, factor: float, delta: float, outer: int, inner: int,
                    scene: Scene) -> str:
    """A solve error of ``factor`` times delta or more: the increment cannot fall below delta."""
    return (f"ill-conditioned linear systems: the estimated relative error of the linear "
            f"solve, {solve_error:.2e} (one step of iterative refinement), is {factor:g} times "
            f"delta {delta:g} or more at outer {outer}, inner {inner}, so the increment cannot "
            f"fall below delta; {penalties(scene)}")


def ill_conditioned_note(solve_error: float, scene: Scene) -> str:
    """What a divergence or stall adds when the linear solves have lost some digits."""
    return (f"; the linear systems are ill-conditioned (estimated solve error {solve_error:.1e}): "
            f"{penalties(scene)}")


def non_finite(outer: int, inner: int) -> str:
    return (f"non-finite iterate (NaN or Inf) at outer {outer}, inner {inner}; the results are the "
            "previous iterate. Try a larger penalty parameter (penalty.d, penalty.d_N)")


def diverging(increments: list[float], outer: int, inner: int, note: str, method: str,
              less_friction: bool) -> str:
    """``less_friction``: whether a smaller friction coefficient is advice to give: not in rolling,
    whose rolls draw the strip by friction (a strip they could not draw in was told both to raise
    the friction and to try less of it, until stop 73)."""
    others = " or ".join(m for m in ("direct", "modified") if m != method)
    friction = ", a smaller friction coefficient" if less_friction else ""
    return (f"diverging: the increment grew for 5 iterations to {increments[-1]:.3e} (outer "
            f"{outer}, inner {inner}; last increments {recent(increments)}){note}. "
            f"Try the {others} method{friction} or larger penalty parameters; see history.csv")


def stalled(window: int, increments: list[float], outer: int, inner: int, note: str) -> str:
    return (f"stalled or oscillating: no smaller increment in the last {window} iterations "
            f"(outer {outer}, inner {inner}; last increments {recent(increments)}){note}; see "
            "history.csv")


FIRST_SOLVE_NON_FINITE = ("the first solve, with the uniform modulus G(reference strain rate), "
                          "gave a non-finite velocity: check the material constants and "
                          "solver.reference_strain_rate")


def balance_note(checks: list[float], tolerance: float) -> str:
    """The last force balance residual, when the run checked one."""
    if not checks:
        return ""
    return (f"; force balance residual {checks[-1]:.3e} above the force tolerance "
            f"{tolerance:g}")


def no_convergence(iterations: int, increment: float, delta: float, balance: str,
                   steps: str = "iterations") -> str:
    return (f"no convergence in {iterations} {steps} (last increment {increment:.3e}, delta "
            f"{delta:g}{balance})")


def slow_convergence(iterations: int, increments: list[float], rho: float, delta: float) -> str:
    """Why a rolling run whose increments met delta did not end (newton.py, _rate_settled)."""
    if rho < 1.0:  # False for NaN: the last steps were not three full frozen ones
        rate = (f"fall by only {rho:.3f} a step, so the answer may lie "
                f"{increments[-1] * rho / (1.0 - rho):.1e} (||du||/||u||) away")
    else:
        rate = "do not fall steadily enough to bound the distance to the answer"
    return (f"not converged in {iterations} Newton steps: the increments met delta = {delta:g} but "
            f"{rate} (last increments {recent(increments)}). Near sticking the friction bound's "
            "derivative makes Newton's operator nearly singular and the steps creep along the "
            "stick zone's slip; raise solver.max_iterations (steel strips rolled at m = 1 took "
            "76, 124 and 245 solves to converge, docs/rolling.md)")


def outer_stalled(outer_increments: list[float]) -> str:
    return (f"the friction (outer) loop stalls or oscillates: outer changes "
            f"{recent(outer_increments)}; at this friction coefficient the solution may not be "
            "unique; see history.csv")


def outer_not_converged(iterations: int, change: float, delta: float, balance: str) -> str:
    if change < delta:
        return (f"the force balance did not converge in {iterations} outer iterations{balance}, "
                f"though the outer change {change:.3e} is below delta")
    return (f"no convergence of the friction (outer) loop in {iterations} iterations (last change "
            f"{change:.3e}); at this friction coefficient the solution may not be unique")


def hardening_hint(scene: Scene) -> str:
    """What a Newton run with a hardening law adds when it does not converge."""
    if not scene.material.hardens:
        return ""
    return ("; with a nearly rate-independent hardening law in plane strain, Newton's per-step "
            "strain update may not settle: try solver.method = \"direct\", a rate factor, or "
            "a hardening curve of finite initial slope (voce; swift with a prestrain)")


def strength_friction_hint(factor_at_strength: bool) -> str:
    """What a rolling run adds when it does not converge with the factor law at the shear strength
    of a rate-sensitive metal (FlowProblem.bound_reaches_strength)."""
    if not factor_at_strength:
        return ""
    return ("; a friction factor within 1 % of 1 puts the interface at the rate-sensitive "
            "metal's own shear strength: the slip splits between the two nearly freely, Newton's "
            "step along that split is nearly singular, and the roll force rises steeply as m "
            "nears 1 (docs/rolling.md#sticking). Sticking, the law's d_T -> 0 limit at m = 1 "
            "(friction.law = \"sticking\"; m = 1 is solved as it by default on a strongly "
            "rate-sensitive metal that does not harden), or m = 0.95 converge in about 10 to 20 "
            "solves")


def newton_trigger(records: list[IterationRecord]) -> str:
    """What the Newton steps measured as they failed, for the message: the increment's rise from
    its least value, and the most Gauss points that switched the flow law's branch and die nodes
    that switched the contact set in one step since then (the non-smooth parts of the operator)."""
    steps = [r for r in records if math.isfinite(r.increment)]
    if len(steps) < 2:
        return ""
    least = min(range(len(steps)), key=lambda k: steps[k].increment)
    after = steps[least:]
    law = max(r.law_switches for r in after)
    contact = max(r.contact_switches for r in after)
    text = (f": its increment rose from {steps[least].increment:.2e} (step {steps[least].inner}) "
            f"to {steps[-1].increment:.2e}")
    if law > 0 or contact > 0:
        text += (f" while up to {law} Gauss points switched the flow law's branch and {contact} "
                 "die nodes the contact set in a step")
    return text


def newton_failed(cause: str, steps: list[IterationRecord]) -> str:
    """How Newton's method failed before the direct method took over."""
    return (f"Newton's method {NEWTON_STOPPED[cause]} at step {steps[-1].inner if steps else 0}"
            f"{newton_trigger(steps)}")


def newton_linear_failure(inner: int, error: Exception, scene: Scene, iterative: bool) -> str:
    """How Newton's method failed when its linear solve (``iterative``: by the Krylov solver) did,
    before the direct method took over."""
    note = ""
    if iterative and getattr(scene.material, "rate_factor", None) == "none":
        note = (" (the tangent of a rate-independent law has almost no stiffness along the flow "
                "direction: MUMPS solves it, the Krylov solver does not)")
    return f"Newton's linear solve failed at step {inner}: {error}{note}"


def after_fallback(reason: str, failed: str) -> str:
    """The direct method's reason, after Newton's method failed."""
    return (f"{reason}, by the direct method (3.13) after {failed} (set solver.method = \"direct\" "
            "to start with it)")

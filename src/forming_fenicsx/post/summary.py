"""The summary numbers of a run, gathered from the post-processing modules. The order of the calls
matters: thermal_scalars settles the temperature (one way), and the numbers computed after it (the
flow stress in the dissipation fractions) see the settled field."""
from __future__ import annotations

from forming_fenicsx.core.roles import ROLES
from forming_fenicsx.fem.forms import FlowProblem
from forming_fenicsx.post.diagnostics import (die_penetration, discrete_divergence,
                                              dissipation_outside_window, divergence_l2,
                                              exit_zone_rate_ratio, free_surface_crossings,
                                              relative_divergence, strain_extremes,
                                              volume_change)
from forming_fenicsx.post.die import (contact_end_x, contact_pressures, die_contact_fraction,
                                      die_profile, die_scalars, die_scalars_3d, die_scalars_of)
from forming_fenicsx.post.forces import (die_separation_force, force_balance,
                                         pressure_free_friction, unpressed_friction_x,
                                         whole_product)
from forming_fenicsx.post.heat import thermal_scalars
from forming_fenicsx.post.integrals import integrate
from forming_fenicsx.post.product import (hardening_scalars, mean_exit_strain, pass_shape,
                                          product_flow_stress, product_half_size, section_areas)
from forming_fenicsx.post.ram_face import mean_hydrostatic_pressure
from forming_fenicsx.post.rolls import roll_scalars


def exit_section(problem: FlowProblem) -> float:
    """The area the drawing force acts on: the model's exit section (the half-thickness per unit
    width, pi R^2, or a 3D model's part of the section, integrated over Gamma1); in 2D of the
    product's half-size at the exit face (the die's exit size, or where a free surface ends)."""
    c = problem.coordinates
    if c.three_dimensional:
        return integrate(problem, 1.0 * problem.ds(ROLES["gamma1_velocity"]))
    return c.section(product_half_size(problem))


def crossing_keys(crossed: dict[str, float]) -> dict[str, float]:
    """free_surface_crossing (both free surfaces) and its part on each, by name."""
    return {"free_surface_crossing": sum(crossed.values()),
            **{f"free_surface_crossing_{name}": value for name, value in crossed.items()}}


def stock_yield_ratio(problem: FlowProblem, back: float | None) -> dict[str, float]:
    """A back tension (drawing's process.applied_force, rolling's process.back_tension) over the
    stock's yield stress in tension at the strain it flows in with (2k in plane strain): empty
    without one."""
    if not back or back <= 0:
        return {}
    tensile = problem.coordinates.tensile_yield_factor
    return {"stock_yield_ratio": back / (tensile * product_flow_stress(problem, False))}


def scalars(problem: FlowProblem) -> dict[str, float]:
    """The summary numbers of a run: process force and pressure, die forces and the x force
    balance, forces on the whole product (whole_product).

    Extrusion: ram force and pressure (force over the Gamma1 height), p_av. Drawing: drawing force
    and stress (Gamma1 force over the exit half-thickness), q_av, contact length and end. Rolling:
    the roll force, torque and power, the strip's speeds, forward slip and neutral point
    (rolls.py), q_av and the contact.
    """
    residual, force, die_normal, die_friction, external = force_balance(problem)
    divergence = divergence_l2(problem)
    three_d = problem.coordinates.three_dimensional
    die_numbers = die_scalars_3d if three_d else die_scalars
    if problem.scene.process.kind == "extrusion":
        height = integrate(problem, 1.0 * problem.ds(ROLES["gamma1_velocity"]))
        process = {"ram_force": force, "ram_pressure": force / height,
                   "mean_hydrostatic_pressure": mean_hydrostatic_pressure(problem)}
        if problem.scene.geometry.die != "square":
            process.update({**die_numbers(problem), **pass_shape(problem)})
    elif problem.rolling:  # one die profile for the neutral point and the contact's end
        profile = die_profile(problem)
        process = {"roll_force": die_separation_force(problem),
                   **roll_scalars(problem, profile), **die_scalars_of(problem, profile),
                   **stock_yield_ratio(problem, problem.scene.process.back_tension),
                   **pass_shape(problem)}
    else:
        stress = force / exit_section(problem)
        strength = problem.coordinates.tensile_yield_factor * product_flow_stress(problem)
        process = {"drawing_force": force, "drawing_stress": stress,
                   "product_yield_ratio": stress / strength,
                   **stock_yield_ratio(problem, problem.scene.process.applied_force),
                   **die_numbers(problem), **pass_shape(problem)}
    if three_d:
        process.update(section_areas(problem))
    return whole_product(problem, {
        **process,
        **hardening_scalars(problem),
        **strain_extremes(problem),
        **thermal_scalars(problem, process),
        "die_force_x": die_normal + die_friction,
        "die_separation_force": die_separation_force(problem),
        **({"die_side_force": die_separation_force(problem, 2)} if three_d else {}),
        "die_normal_force_x": die_normal,
        "die_friction_force_x": die_friction,
        # the factor law's m k where the die is not pressed (extrusion and drawing; sanity.py)
        **({"unpressed_friction_force_x": unpressed_friction_x(problem)}
           if pressure_free_friction(problem) and not problem.rolling else {}),
        "applied_force_x": external,
        "force_balance_residual": residual,
        "divergence_l2": divergence,
        "relative_divergence": relative_divergence(problem, divergence),
        **({"discrete_divergence": discrete_divergence(problem)} if problem.mixed else {}),
        "volume_change": volume_change(problem),
        **crossing_keys(free_surface_crossings(problem)),
        "die_penetration": die_penetration(problem),
        **({} if "die_contact_fraction" in process else
           {"die_contact_fraction": die_contact_fraction(problem)}),
        "exit_zone_rate_ratio": exit_zone_rate_ratio(problem),
        # a hardening law's is the transported strain's (hardening_scalars)
        **({} if problem.strain is not None else {"mean_exit_strain": mean_exit_strain(problem)}),
        **dissipation_outside_window(problem),
    })


def update_scalars(problem: FlowProblem) -> dict[str, float]:
    """The numbers of scalars that the free surface's update reads from a flow that may not be
    its last (app/free_surface.py): the x force balance, the crossings, and where the contact with
    the die ends (none on the square die, as scalars)."""
    process, geometry = problem.scene.process, problem.scene.geometry
    square = process.kind == "extrusion" and geometry.die == "square"
    end = {} if square else {"contact_end_x": contact_end_x(
        problem, die_profile(problem, contact_pressures(problem)))}
    return {**end, "force_balance_residual": force_balance(problem)[0],
            **crossing_keys(free_surface_crossings(problem))}

"""exit_<quantity>.png: a quantity across the product (the hardness or temperature profile)."""
from __future__ import annotations

from pathlib import Path

from forming_fenicsx.core.units import Units, bracketed
from forming_fenicsx.io.figure import Heading, plain_ticks, pyplot, save


def write_exit_profile_plot(profile: dict, path: Path, heading: Heading, label: str,
                            dimension: str, units: Units,
                            reference: tuple[str, float] | None = None) -> Path:
    """exit_<quantity>.png: a quantity across the product against y (the hardness or temperature
    profile; temperatures in units.temperature), with a reference level (``(label, value)``: the
    ideal strain, the inflow temperature); the strain's profile
    (exit_profiles.exit_strain_profile) also shows the strain traced along the streamlines and
    the transported field, and shades the outermost elements, across which the written profile
    takes its mean (docs/hardening.md)."""
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(7, 4.5))
    values, unit = units.shown(dimension, profile["values"])
    strain = "surface_layer" in profile
    if strain:  # a layer at the surface is not resolved
        surface = profile["y"][-1]
        ax.axvspan(surface - profile["surface_layer"], surface, color="0.88",
                   label="the outermost elements: the written value is their mean")
        ax.plot(profile["y"], profile["transported"], "--", color="tab:orange",
                label=f"transported {label} (FE field)")
        ax.plot(profile["y"], profile["streamlines"], "-", color="0.5", linewidth=0.8,
                label=f"{label} along the streamlines")
    ax.plot(profile["y"], values, "b.-",
            label=f"{label}: the written profile (CSV)" if strain else f"FE {label}")
    if reference is not None:
        level = float(units.shown(dimension, reference[1])[0])
        ax.axhline(level, color="k", linestyle="--", label=f"{reference[0]} = {level:.4g}")
    ax.set_xlabel(units.labelled("y, from the axis to the surface of the product", "length"))
    ax.set_ylabel(bracketed(label, unit))
    heading.put(ax, f"{label} across the product")
    if dimension != "temperature":
        ax.set_ylim(bottom=0.0)
    ax.grid(True, alpha=0.3)
    ax.legend()
    plain_ticks(ax)
    fig.tight_layout()
    return save(fig, path)

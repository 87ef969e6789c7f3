"""die.png: the stresses on the die along the die coordinate s over bands marking the parts of the
die, and the die profile at 1:1 below them."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from forming_fenicsx.config.scene import Scene
from forming_fenicsx.core.units import bracketed
from forming_fenicsx.io.figure import Heading, plain_ticks, pyplot, save

DIE_PARTS = {"container wall": "tab:green", "die face": "tab:red", "cone": "tab:purple",
             "land": "tab:brown"}


def die_parts(x: np.ndarray, y: np.ndarray, land_start: float | None = None) -> list[str]:
    """The part of the die each segment between consecutive nodes of Gamma3 lies on, by its slope:
    "die face" (within 10 deg of the normal to the axis, a square die's face), level (within 1 deg
    of the axis: the "container wall" before the first inclined segment, the "land" after it, but
    with the die's ``land_start`` given not before that x: a curved die's tail that meets the land
    tangentially is "cone"), else "cone"."""
    slope = np.degrees(np.arctan2(np.abs(np.diff(y)), np.abs(np.diff(x))))
    middle = 0.5 * (x[1:] + x[:-1])
    parts, reached = [], False
    for angle, at in zip(slope, middle):
        if angle > 80.0:
            parts.append("die face")
        elif angle < 1.0 and not reached:
            parts.append("container wall")
        elif angle < 1.0 and (land_start is None or at > land_start):
            parts.append("land")
        else:
            parts.append("cone")
        reached |= angle >= 1.0
    return parts


def write_die_plot(profile: dict, path: Path, heading: Heading, scene: Scene) -> Path:
    """die.png: the stresses on the die (contact pressure, averaged normal stress and friction
    stress, as present) along the die coordinate s, over bands marking the part of the die
    (die_parts), and below it the die profile y(x) through the nodes of Gamma3 (die.csv's x and y)
    at 1:1, coloured by part; axes with the scene's units (stresses far from 1 in another unit of
    their family, Units.shown), the run's main settings in the title."""
    plt = pyplot()
    units = scene.units
    fig, (ax, shape) = plt.subplots(2, 1, figsize=(8, 7.5), gridspec_kw={"height_ratios": [3, 2]})
    names = {"contact_pressure": ("contact pressure", " -sigma_N"), "averaged_normal_stress":
             ("averaged normal stress", ""), "friction_stress": ("friction stress", " |sigma_T|")}
    shown = [key for key in names if key in profile]
    geometry = scene.geometry
    land_start = (geometry.profile().land_start if hasattr(geometry, "profile")
                  and geometry.mesh_file is None else None)
    parts = die_parts(profile["x"], profile["y"], land_start)
    for index, part in enumerate(parts):
        first = index == parts.index(part)
        label = part if first else None
        ax.axvspan(profile["s"][index], profile["s"][index + 1], color=DIE_PARTS[part], alpha=0.12,
                   lw=0, label=label)
        shape.plot(profile["x"][index:index + 2], profile["y"][index:index + 2], "-",
                   color=DIE_PARTS[part], linewidth=2.5, label=label)
    largest = max(np.nanmax(np.abs(profile[key]), initial=0.0) for key in shown)
    unit = units.shown("stress", [largest])[1]  # one unit for every stress on the axis
    for key in shown:
        ax.plot(profile["s"], units.shown("stress", profile[key], largest)[0], marker=".",
                label="".join(names[key]))
    ax.set_xlabel(units.labelled("s, distance along the die from its entry",
                                 "length"))
    ax.set_ylabel(bracketed("stress on the die", unit))
    heading.put(ax, "stresses on the die")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    shape.plot(profile["x"], profile["y"], "k.", markersize=1.5, label="nodes of Gamma3")
    shape.set_xlabel(units.labelled("x, along the axis", "length"))
    size = "radius" if scene.geometry.axisymmetric else "half-thickness"
    shape.set_ylabel(units.labelled(size, "length"))
    shape.update_datalim([[profile["x"][0], 0.0]])  # from the axis
    shape.autoscale()
    shape.set_aspect("equal", adjustable="datalim")  # 1:1, the limits widened to fill the panel
    shape.set_title("die profile (1:1)", fontsize=9)
    shape.grid(True, alpha=0.3)
    shape.legend(fontsize=8)
    for axes in (ax, shape):
        plain_ticks(axes)
    fig.tight_layout()
    return save(fig, path)

"""rolls.png: the friction hill of flat rolling along the arc of contact, the roll pressure and the
signed friction stress against x with the neutral point marked, and the strip's slip on the roll
below them."""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from forming_fenicsx.config.scene import Scene
from forming_fenicsx.core.units import bracketed
from forming_fenicsx.io.figure import Heading, plain_ticks, pyplot, save


def write_roll_plot(profile: dict, path: Path, heading: Heading, scene: Scene,
                    neutral_x: float) -> Path:
    """rolls.png: the contact pressure and the friction stress along the roll's motion (> 0 drags
    the strip forward) at the nodes of the arc (die.csv) against x, from the bite to the roll gap,
    with the neutral point (where the slip changes sign) marked; below, the slip u - w along the
    roll's motion. Axes in the scene's units."""
    plt = pyplot()
    units = scene.units
    fig, (ax, slip) = plt.subplots(2, 1, figsize=(8, 7), sharex=True,
                                   gridspec_kw={"height_ratios": [3, 2]})
    keys = [("contact_pressure", "roll pressure p", "tab:blue"),
            ("shear_stress", "friction stress along the roll's motion", "tab:green")]
    keys = [k for k in keys if k[0] in profile]
    largest = max(np.nanmax(np.abs(profile[key]), initial=0.0) for key, _, _ in keys)
    unit = units.shown("stress", [largest])[1]
    for key, label, colour in keys:
        ax.plot(profile["x"], units.shown("stress", profile[key], largest)[0], marker=".",
                color=colour, label=label)
    ax.axhline(0.0, color="k", linewidth=0.6)
    g = scene.geometry
    for axes in (ax, slip):
        for x in (g.die_entry, g.die_exit):  # the bite and the roll gap
            axes.axvline(x, color="0.5", linestyle=":", linewidth=1)
        if math.isfinite(neutral_x):
            axes.axvline(neutral_x, color="tab:red", linestyle="--", linewidth=1,
                         label="neutral point" if axes is ax else None)
    ax.set_ylabel(bracketed("stress on the strip", unit))
    heading.put(ax, "roll pressure and friction along the arc of contact")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    velocity = units.label("velocity")
    slip.plot(profile["x"], profile["slip"], ".-", color="tab:purple",
              label="slip (u - w) along the roll's motion")
    slip.axhline(0.0, color="k", linewidth=0.6)
    slip.set_xlabel(units.labelled("x, along the strip (bite and roll gap dotted)", "length"))
    slip.set_ylabel(bracketed("slip", velocity))
    slip.grid(True, alpha=0.3)
    slip.legend(fontsize=8)
    for axes in (ax, slip):
        plain_ticks(axes)
    fig.tight_layout()
    return save(fig, path)

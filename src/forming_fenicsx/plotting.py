"""PNG figures in the manner of the paper's Fig. 3 and 4: velocity vectors and the equivalent strain-rate map."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from .compat import cell_geometry_nodes
from .forms import FlowProblem
from .postprocess import cell_means
from .units import Units

QUAD_OUTLINE = [0, 1, 3, 2]  # dolfinx quadrilateral vertices in tensor order -> polygon order


def _gather_cells(problem: FlowProblem):
    """Cell outlines, cell-mean velocity and equivalent strain rate of every cell, on rank 0."""
    mesh = problem.mesh
    owned = mesh.topology.index_map(mesh.topology.dim).size_local
    nodes = cell_geometry_nodes(mesh)[:owned][:, QUAD_OUTLINE]
    outlines = mesh.geometry.x[nodes][:, :, :2]
    degree = problem.full_degree
    rate = cell_means(problem, problem.equivalent_strain_rate(problem.u), "rate", degree).x.array[:owned]
    ux = cell_means(problem, problem.u[0], "ux", degree).x.array[:owned]
    uy = cell_means(problem, problem.u[1], "uy", degree).x.array[:owned]
    parts = problem.comm.gather((outlines, rate, ux, uy), root=0)
    if problem.comm.rank != 0:
        return None
    return [np.concatenate(p) for p in zip(*parts, strict=True)]


def write_figures(problem: FlowProblem, directory: Path, title: str) -> list[Path]:
    """velocity.png and strain_rate.png (collective; rank 0 draws)."""
    data = _gather_cells(problem)
    if data is None:
        return []
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.collections import PolyCollection
    from matplotlib.colors import LogNorm

    outlines, rate, ux, uy = data
    units = problem.scene.units
    centres = outlines.mean(axis=1)
    extent = np.ptp(outlines.reshape(-1, 2), axis=0)
    size = (10, max(2.5, 10 * extent[1] / extent[0] + 1.0))
    paths = []

    fig, ax = plt.subplots(figsize=size)
    ax.add_collection(PolyCollection(outlines, facecolors="none", edgecolors="0.8", linewidths=0.3))
    stride = max(1, len(centres) // 600)
    ax.quiver(centres[::stride, 0], centres[::stride, 1], ux[::stride], uy[::stride], angles="xy",
              scale_units="xy", scale=(np.abs(ux).max() or 1.0) / (0.6 * np.sqrt(extent.prod() / len(centres) * stride)),
              width=0.002)
    ax.set_title(f"{title}: velocity vectors")
    paths.append(_finish(fig, ax, outlines, directory / "velocity.png", units))

    fig, ax = plt.subplots(figsize=size)
    floor = max(rate.max() * 1e-4, 1e-12)
    cells = PolyCollection(outlines, array=np.maximum(rate, floor), cmap="jet",
                           norm=LogNorm(vmin=floor, vmax=max(rate.max(), 2 * floor)), edgecolors="face")
    ax.add_collection(cells)
    fig.colorbar(cells, ax=ax, label=units.labelled("equivalent strain rate", "strain_rate"))
    ax.set_title(f"{title}: equivalent strain rate")
    paths.append(_finish(fig, ax, outlines, directory / "strain_rate.png", units))
    return paths


def _finish(fig, ax, outlines: np.ndarray, path: Path, units: Units) -> Path:
    import matplotlib.pyplot as plt

    points = outlines.reshape(-1, 2)
    ax.set_xlim(points[:, 0].min(), points[:, 0].max())
    ax.set_ylim(points[:, 1].min(), points[:, 1].max())
    ax.set_aspect("equal")
    ax.set_xlabel(units.labelled("x", "length"))
    ax.set_ylabel(units.labelled("y", "length"))
    fig.tight_layout()
    fig.savefig(path, dpi=130)
    plt.close(fig)
    return path


def write_die_plot(profile: dict, path: Path, title: str, units: Units) -> Path:
    """die.png: contact pressure (and averaged normal stress, friction stress) along the die, and
    below it the die profile y(x) through the nodes of Gamma3 (die.csv's x and y)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (ax, shape) = plt.subplots(2, 1, figsize=(8, 7), gridspec_kw={"height_ratios": [3, 2]})
    labels = {"contact_pressure": "contact pressure -sigma_N", "averaged_normal_stress": "averaged normal stress",
              "friction_stress": "friction stress |sigma_T|"}
    for key, label in labels.items():
        if key in profile:
            ax.plot(profile["s"], profile[key], marker=".", label=label)
    ax.set_xlabel(units.labelled("s, distance along the die from where the workpiece meets it", "length"))
    ax.set_ylabel(units.labelled("stress", "stress"))
    ax.set_title(f"{title}: die stresses")
    ax.grid(True, alpha=0.3)
    ax.legend()
    shape.plot(profile["x"], profile["y"], "k.-", label="die wall (nodes of Gamma3)")
    shape.set_xlabel(units.labelled("x, along the axis", "length"))
    shape.set_ylabel(units.labelled("y, half-thickness or radius", "length"))
    shape.set_ylim(bottom=0.0)
    shape.set_title("die profile")
    shape.grid(True, alpha=0.3)
    shape.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=130)
    plt.close(fig)
    return path


def write_exit_profile_plot(profile: dict, path: Path, title: str, label: str, dimension: str,
                           units: Units, reference: tuple[str, float] | None = None) -> Path:
    """exit_<quantity>.png: a quantity across the product against y (the hardness or temperature
    profile), with a reference level (``(label, value)``: the ideal strain, the inflow
    temperature)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 4.5))
    ax.plot(profile["y"], profile["values"], "b.-", label=f"FE {label}")
    if reference is not None:
        ax.axhline(reference[1], color="k", linestyle="--", label=f"{reference[0]} = {reference[1]:.4g}")
    ax.set_xlabel(units.labelled("y, from the axis to the surface of the product", "length"))
    ax.set_ylabel(units.labelled(label, dimension))
    ax.set_title(f"{title}: {label} across the product")
    if dimension != "temperature":
        ax.set_ylim(bottom=0.0)
    ax.grid(True, alpha=0.3)
    ax.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=130)
    plt.close(fig)
    return path

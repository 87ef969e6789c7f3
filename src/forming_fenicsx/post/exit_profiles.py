"""Profiles across the product: a field at heights of the exit section from the axis to the
surface, and the strain profile (the hardness of the next pass's stock), traced along the
streamlines and averaged over the outermost elements, where it is not resolved."""
from __future__ import annotations

import logging
from typing import Any

import dolfinx.mesh
import numpy as np
from mpi4py import MPI
from ufl.core.expr import Expr

from forming_fenicsx.core.compat import cell_geometry_nodes, colliding_cells
from forming_fenicsx.fem.forms import FlowProblem
from forming_fenicsx.post.product import product_top
from forming_fenicsx.post.sections import values_at
from forming_fenicsx.post.streamlines import streamline_strain

log = logging.getLogger(__name__)
# the strain of the product's outermost LAYER_CELLS elements is written as their mean, by
# Gauss-Legendre at LAYER_POINTS heights (docs/hardening.md measures both choices)
LAYER_CELLS = 2
LAYER_POINTS = 8


def exit_section(problem: FlowProblem, points: int) -> tuple[float, np.ndarray]:
    """The product's section half its half-thickness (radius) before the workpiece's end, x, and
    ``points`` heights on it from the axis to the surface (the workpiece's top there,
    product.product_top; the last a hair inside, more so under a free surface, which the
    isoparametric cells, their nodes on it, follow to about 1e-7 of the size)."""
    g = problem.scene.geometry
    x = g.length - 0.5 * g.thinnest
    inside = 1e-6 if problem.scene.free_surface.update else 1e-9
    return x, np.linspace(0.0, product_top(problem, x) * (1 - inside), points)


def exit_profile(problem: FlowProblem, field: Expr, points: int = 41) -> dict[str, Any] | None:
    """A field across the product on the exit_section (rank 0; None elsewhere; collective)."""
    x, y = exit_section(problem, points)
    values = values_at(problem, field, np.column_stack([np.full(points, x), y]),
                       problem.scene.discretisation.degree)
    return {"y": y, "values": values} if problem.comm.rank == 0 else None


def exit_strain_profile(problem: FlowProblem, points: int = 41,
                        layer_points: int = LAYER_POINTS) -> dict[str, Any] | None:
    """The strain across the product (exit_strain.csv; rank 0, None elsewhere; collective):
    ``values`` along the streamlines (streamlines.streamline_strain), but within the outermost
    LAYER_CELLS elements of the exit_section (``surface_layer`` deep) their mean,

        eps_layer = int eps W dy / int W dy  over R - s < y < R,  W = y (round) or 1 (strip),

    by Gauss-Legendre at ``layer_points`` (the product moves rigidly: the flux-weighted mean). The
    strain's distribution within that layer is not resolved (the die-entry corner's shear, smeared
    over about two elements at any mesh size, docs/hardening.md); its mean is, as the mean of the
    strain flowing out through a stream tube, the rate integrated over it. Beside it
    ``streamlines`` (the traced strain itself), ``transported`` (the transported field) and
    ``surface_mean``. A streamline that does not reach the entry takes the transported field's
    value, with a warning."""
    x, y = exit_section(problem, points)
    surface = y[-1]
    depth = surface_cell_depth(problem.mesh, x, surface, LAYER_CELLS)
    nodes, weights = np.polynomial.legendre.leggauss(layer_points)
    layer = surface - 0.5 * depth * (1 - nodes)
    heights = np.concatenate([y, layer])
    section = np.column_stack([np.full(len(heights), x), heights])
    traced = streamline_strain(problem, section)
    transported = values_at(problem, problem.strain, section, problem.scene.discretisation.degree)
    lost = np.isnan(traced)
    if lost.any() and problem.comm.rank == 0:
        log.warning("warning: %d streamlines through the exit section did not reach the entry: "
                    "exit_strain.csv takes the transported strain there", int(lost.sum()))
    traced[lost] = transported[lost]
    weight = weights * (layer if problem.coordinates.axisymmetric else 1.0)
    mean = float(np.sum(weight * traced[points:]) / np.sum(weight))
    if problem.comm.rank != 0:
        return None
    return {"y": y, "values": np.where(y > surface - depth, mean, traced[:points]),
            "streamlines": traced[:points], "transported": transported[:points],
            "surface_layer": depth, "surface_mean": mean}


def surface_cell_depth(mesh: dolfinx.mesh.Mesh, x: float, y: float, cells: int = 1) -> float:
    """How far below the point (x, y) at the surface the lowest node of the ``cells``-th cell down
    from it lies (collective): the layer in which a profile's values rest on so many elements."""
    query, lowest = y, y
    for _ in range(cells):
        found = colliding_cells(mesh, np.array([[x, query, 0.0]]))[0]
        local = mesh.geometry.x[cell_geometry_nodes(mesh)[found], 1].min() if found >= 0 \
            else np.inf
        lowest = mesh.comm.allreduce(local, op=MPI.MIN)
        query = lowest - 1e-6 * (y - lowest)  # just inside the next cell down
    return float(y - lowest)

"""Scalars of the product: the pass's reduction and central-burst indicator, a 3D product's section
areas, its mean strain (the redundant strain beside the ideal one) and, with a hardening law, its
strains, redundant-work factor and flow stresses."""
from __future__ import annotations

import math

import numpy as np
import ufl
from mpi4py import MPI

from forming_fenicsx.core.compat import bounding_box_tree, colliding_cells
from forming_fenicsx.fem.forms import FlowProblem
from forming_fenicsx.physics.closed_forms import central_burst_indicator
from forming_fenicsx.post.flux import mean_strain_through, throughput
from forming_fenicsx.post.integrals import integrate


def pass_shape(problem: FlowProblem) -> dict[str, float]:
    """The reduction r (of area for a round bar, of thickness for a strip) and the central-burst
    indicator Delta of a profiled die at its semi_angle (closed_forms.central_burst_indicator), or
    a roll gap's h_m/L; none for a user's mesh."""
    g = problem.scene.geometry
    if g.mesh_file is not None:
        return {}
    reduction = 1 - g.area_ratio
    if problem.rolling:  # the roll gap's shape h_m/L (mean thickness over contact length)
        return {"reduction": reduction, "gap_shape_factor":
                0.5 * (g.entry_thickness + g.exit_thickness) / g.cone_length}
    if g.shape == "rectangle":  # the indicator is a 2D or round product's
        return {"reduction": reduction}
    symmetry = "axisymmetric" if g.round else g.symmetry
    return {"reduction": reduction,
            "central_burst_indicator": central_burst_indicator(reduction, g.semi_angle,
                                                               symmetry)}


def section_areas(problem: FlowProblem) -> dict[str, float]:
    """A 3D product's entry and exit section areas, the whole product's: the model's end faces
    (the boundary at its smallest and largest x) integrated, times CoordinateSystem.whole."""
    x = ufl.SpatialCoordinate(problem.mesh)
    ends = problem.comm.allgather((problem.mesh.geometry.x[:, 0].min(),
                                   problem.mesh.geometry.x[:, 0].max()))
    low, high = min(e[0] for e in ends), max(e[1] for e in ends)
    tolerance = 1e-9 * (high - low)
    areas = {}
    for key, inside in (("entry_section_area", ufl.lt(x[0], low + tolerance)),
                        ("exit_section_area", ufl.gt(x[0], high - tolerance))):
        areas[key] = problem.coordinates.whole * integrate(
            problem, ufl.conditional(inside, 1.0, 0.0) * problem.ds)
    return areas


def product_half_size(problem: FlowProblem) -> float:
    """A 2D product's half-size (radius) at the workpiece's downstream end: the top of its end
    face (the die's exit size on the scene's domain, where the free surface ends after an
    update, app/free_surface.py)."""
    x = problem.mesh.geometry.x
    end = problem.comm.allreduce(x[:, 0].max(), op=MPI.MAX)
    at_end = x[:, 0] >= end - 1e-12 * abs(end)
    return problem.comm.allreduce(x[at_end, 1].max(initial=0.0), op=MPI.MAX)


def product_top(problem: FlowProblem, x: float) -> float:
    """The 2D workpiece's top at x (the product's half-size or radius there): the highest point of
    the line x = const in a cell, found on three ever finer rows of points about the half-size at
    the end (product_half_size), which it is unless lower by more than 1e-8 of it (the same on
    every rank). Under a free surface the product need not be level to the last digit: the
    least-squares surface of the annealed rod lay 3.4e-6 of its radius lower half an exit
    thickness before the end than at it."""
    half = product_half_size(problem)
    tree = bounding_box_tree(problem.mesh)
    low, high = 0.5 * half, 1.5 * half
    for _ in range(3):
        ys = np.linspace(low, high, 1001)
        points = np.column_stack([np.full(len(ys), x), ys, np.zeros(len(ys))])
        local = (colliding_cells(problem.mesh, points, tree) >= 0).astype(np.int32)
        inside = np.zeros_like(local)
        problem.comm.Allreduce(local, inside, op=MPI.MAX)
        last = int(np.flatnonzero(inside).max(initial=0))
        low, high = ys[last], ys[min(last + 1, len(ys) - 1)]
    return half if low >= half * (1 - 1e-8) else float(low)


def product_flow_stress(problem: FlowProblem, leaving: bool = True) -> float:
    """The drawn product's flow stress at the process strain rate: at its mean exit strain for a
    hardening law (``leaving`` False: the stock's, at the strain it flows in with, the law's
    initial strain or its profile's section mean), the scene's reference flow stress otherwise.
    The stock's is not read from the iterate's entry section: a stopped iterate carried 4e27
    there (the steel wire at 0.943 of its stock's yield stress, Debian 13), and NaN before."""
    scene = problem.scene
    if problem.strain is None:
        return scene.reference_flow_stress
    strain = mean_strain_through(problem) if leaving else scene.inflow_strain
    return float(scene.material.flow_stress([scene.reference_strain_rate], strain)[0])


def hardening_scalars(problem: FlowProblem) -> dict[str, float]:
    """With a hardening law: the mean entry and exit strains, the ideal strain ln(A0/A1)
    (2/sqrt3 ln(h0/h1) in plane strain), the redundant-work factor (exit strain gained over the
    ideal), and the mean flow stress Ybar = P / (Q (eps_exit - eps_in)): the plastic work rate
    P = int sigma rate over the throughput Q and the strain gained, as the ideal-work formulas
    use it."""
    if problem.strain is None:
        return {}
    g = problem.scene.geometry
    exit_strain, entry_strain = mean_strain_through(problem), mean_strain_through(problem, False)
    gained = exit_strain - entry_strain
    ideal = g.ideal_strain
    rate = problem.equivalent_strain_rate(problem.u)
    work = integrate(problem, problem.flow_stress(problem.u) * rate * problem.dx)
    return {"mean_entry_strain": entry_strain, "mean_exit_strain": exit_strain,
            "ideal_strain": ideal, "redundant_work_factor": gained / ideal,
            "mean_flow_stress": work / (throughput(problem) * gained) if gained > 0 else math.nan,
            "product_flow_stress": product_flow_stress(problem)}


def mean_exit_strain(problem: FlowProblem) -> float:
    """The flux-weighted mean equivalent strain of the product: with u.grad(eps) = rate along the
    streamlines and div u = 0, div(eps u) = rate, so int_exit eps u.n = int rate dx over the
    workpiece (eps = 0 entering, no flow through the die and free surfaces) and the mean is
    int rate dx / Q, Q the throughput. Compare the homogeneous strain ln(A0/A1) (round) or
    (2/sqrt3) ln(h0/h1) (strip): the excess is the redundant strain."""
    through = throughput(problem)
    rate = problem.equivalent_strain_rate(problem.u)
    return integrate(problem, rate * problem.dx) / through if through else math.nan

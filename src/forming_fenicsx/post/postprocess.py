"""Forces, pressures and fields of a converged (or last) iterate.

Global forces are consistent reactions (the residual of (3.12) at the Gamma1 dofs) and boundary
integrals of the penalty and friction tractions; pressures are element or nodal means of the
penalty pressure sigma_H = div(u)/d of (3.4).
"""
from __future__ import annotations

import logging
import math
from typing import Any

import dolfinx.fem
import dolfinx.fem.petsc
import numpy as np
import ufl
from mpi4py import MPI
from petsc4py import PETSc

from forming_fenicsx.physics import contact, friction
from forming_fenicsx.physics.closed_forms import central_burst_indicator
from forming_fenicsx.core.compat import cell_geometry_nodes, colliding_cells, function_space, geometry_degree
from forming_fenicsx.post.contact_zone import facet_integrals, zone_scalars
from forming_fenicsx.fem.forms import FlowProblem
from forming_fenicsx.mesh.geometry import die_coordinate
from forming_fenicsx.core.roles import ROLES
from forming_fenicsx.fem.projection import LumpedProjector, cell_means

log = logging.getLogger(__name__)
# The strain of the product's outermost LAYER_CELLS elements is written as their mean, by
# Gauss-Legendre at LAYER_POINTS heights (docs/hardening.md: on the steel wire the strain deviates
# from the finest mesh's by up to 0.035 within 1.2 elements of the surface, 0.002 to 0.004 at 1.7,
# below 0.002 at 2.3; the mean on 4, 8, 16, 32 heights within 1.5e-3)
LAYER_CELLS = 2
LAYER_POINTS = 8


def _integrate(problem: FlowProblem, integrand) -> float:
    local = dolfinx.fem.assemble_scalar(dolfinx.fem.form(integrand))
    return problem.comm.allreduce(local)


def reaction(problem: FlowProblem, role: str = "gamma1_velocity") -> float:
    """Force the constraint on ``role`` exerts on the workpiece along its component."""
    component = next(c.component for c in problem.constraints if c.role == role)
    return reaction_on(problem, role, component)


def reaction_on(problem: FlowProblem, role: str, component: int) -> float:
    """Force along x (0) or y (1) that the velocity prescribed on ``role`` exerts on the workpiece: the
    residual summed over that component's dofs there (the whole body's when axisymmetric)."""
    residual = problem.residual.vector()
    dofs = problem.boundary_dofs(role, component)
    owned = problem.V.dofmap.index_map.size_local * problem.V.dofmap.index_map_bs
    value = residual.getArray(readonly=True)[dofs[dofs < owned]].sum()
    residual.destroy()
    return problem.comm.allreduce(value)


def die_forces_x(problem: FlowProblem) -> tuple[float, float]:
    """x-forces the workpiece exerts on the die: normal (contact penalty) and friction parts."""
    if not problem.has_contact:
        return 0.0, 0.0
    n, ds = problem.n, problem.ds_contact
    normal = _integrate(problem, problem.contact_pressure(problem.u) * n[0] * ds)
    if not problem.has_friction:
        return normal, 0.0
    traction = friction.friction_traction(problem.friction_coefficient(), problem.u, n)
    return normal, _integrate(problem, -traction[0] * ds)


def die_separation_force(problem: FlowProblem) -> float:
    """The force that pushes the die apart: the y-traction of the workpiece on the die (contact pressure
    p n_y plus the friction stress's y part) integrated over Gamma3 with the coordinate system's
    separation weight: per unit width on one die half in plane strain; for a round die, the force
    across a diametral plane, 2 int y t_y ds."""
    if not problem.has_contact:
        return 0.0
    n, c = problem.n, problem.coordinates
    traction_y = problem.contact_pressure(problem.u) * n[1]
    if problem.has_friction:
        traction_y -= friction.friction_traction(problem.friction_coefficient(), problem.u, n)[1]
    plain = problem.ds.measure(ROLES["gamma3_contact"])
    return _integrate(problem, traction_y * c.separation_weight * plain)


def applied_force_x(problem: FlowProblem) -> float:
    """x-force of F_N on Gamma5 (2.7) acting on the workpiece."""
    if not problem.has_force:
        return 0.0
    return problem.scene.process.applied_force * _integrate(problem, problem.n[0] * problem.ds(ROLES["gamma5_force"]))


def mean_hydrostatic_pressure(problem: FlowProblem) -> float:
    """The paper's p_av: -sigma_H averaged over the ram face Gamma1, sigma_H taken as element means.

    The elements along Gamma1 lie in the rigid zone at the ram, where sigma_H is close to the
    ram pressure; the mean uses the volumetric term's own quadrature.
    """
    pressure = cell_means(problem.mesh, -problem.hydrostatic_stress(), "pressure", problem.volumetric_degree)
    ds = problem.ds(ROLES["gamma1_velocity"])
    return _integrate(problem, pressure * ds) / _integrate(problem, 1.0 * ds)


def in_contact(problem: FlowProblem):
    """1 where the workpiece presses on the die (sigma_N < 0), else 0."""
    return ufl.conditional(ufl.gt(problem.contact_pressure(problem.u), 0.0), 1.0, 0.0)


def die_pressure(problem: FlowProblem):
    """Contact pressure -sigma_N on Gamma3: the contact's (lambda + u_N/d_N)^+ (contact.py), or -n.sigma.n of
    the stress."""
    if problem.scene.output.die_pressure == "stress":
        n = problem.n
        return -ufl.dot(n, ufl.dot(problem.coordinates.in_plane(problem.stress()), n))
    return problem.contact_pressure(problem.u)


def die_profile(problem: FlowProblem) -> dict[str, np.ndarray] | None:
    """Nodal values along Gamma3 on rank 0 (None elsewhere), ordered by the die coordinate s:
    contact pressure, averaged normal stress (when friction uses it) and friction stress |sigma_T|."""
    space = function_space(problem.mesh, "P", 1)
    ds = problem.ds_contact
    sources = {"contact_pressure": die_pressure(problem)}
    if problem.normal_stress_average is not None:
        sources["averaged_normal_stress"] = problem.normal_stress_average.value
    if problem.has_friction:
        slip = friction.tangential(problem.u, problem.n)
        sources["friction_stress"] = problem.friction_coefficient() * ufl.sqrt(ufl.dot(slip, slip))
    owned = space.dofmap.index_map.size_local
    dofs = dolfinx.fem.locate_dofs_topological(space, problem.mesh.topology.dim - 1,
                                               problem.role_facets("gamma3_contact"))
    dofs = dofs[dofs < owned]
    points = space.tabulate_dof_coordinates()[dofs]
    columns = {"x": points[:, 0], "y": points[:, 1]}
    for name, expr in sources.items():
        target = dolfinx.fem.Function(space)
        columns[name] = LumpedProjector(expr, target, problem.full_degree, ds).project().x.array[dofs]
    gathered = problem.comm.gather(columns, root=0)
    if problem.comm.rank != 0:
        return None
    profile = {key: np.concatenate([part[key] for part in gathered]) for key in columns}
    profile["s"] = die_coordinate(problem.scene, profile["x"], profile["y"])
    order = np.argsort(profile["s"])
    return {key: profile[key][order] for key in ["s", *columns]}


def die_scalars(problem: FlowProblem) -> dict[str, float]:
    """q_av over the contact zone's part in the die from its entry to the land (the paper's mean
    die pressure; over all of Gamma3 for a user's mesh), the contact length (contact_zone.py:
    the facets inside the zone count whole, however finely the die is described), and the x
    where the workpiece leaves the die (last node of Gamma3 with positive contact pressure)."""
    g, x = problem.scene.geometry, ufl.SpatialCoordinate(problem.mesh)
    start = g.die_entry + problem.scene.output.die_entry_trim * math.cos(math.radians(g.die_angle))
    cone = 1.0 if g.mesh_file else ufl.conditional(
        ufl.And(ufl.ge(x[0], start), ufl.le(x[0], g.die_entry + g.cone_length)), 1.0, 0.0)
    facets = facet_integrals(problem, die_pressure(problem), in_contact(problem), cone)
    zone = zone_scalars(facets) if facets is not None else None
    profile = die_profile(problem)
    end = None
    if profile is not None:
        pressed = profile["contact_pressure"] > 1e-9 * max(profile["contact_pressure"].max(), 1e-300)
        end = float(profile["x"][pressed].max()) if pressed.any() else float("nan")
    zone = problem.comm.bcast(zone, root=0)
    return {"mean_die_pressure": zone["mean_die_pressure"], "contact_length": zone["contact_length"],
            "contact_end_x": problem.comm.bcast(end, root=0),
            "die_contact_fraction": zone["die_contact_fraction"]}


def pass_shape(problem: FlowProblem) -> dict[str, float]:
    """The reduction r (of area for a round bar, of thickness for a strip) and the central-burst
    indicator Delta of a profiled die at its semi_angle (closed_forms.central_burst_indicator); none
    for a user's mesh."""
    g = problem.scene.geometry
    if g.mesh_file is not None:
        return {}
    ratio = g.exit_thickness / g.entry_thickness
    reduction = 1 - (ratio**2 if g.axisymmetric else ratio)
    return {"reduction": reduction,
            "central_burst_indicator": central_burst_indicator(reduction, g.semi_angle, g.symmetry)}


def _flux_weight(problem: FlowProblem, leaving: bool):
    """|u.n| where the flow leaves (or enters) the workpiece at more than 30 degrees to the
    boundary, else 0 (die walls and free surfaces, which the flow follows, carry none)."""
    flux = ufl.dot(problem.u, problem.n) if leaving else -ufl.dot(problem.u, problem.n)
    return ufl.conditional(ufl.gt(flux, 0.5 * ufl.sqrt(ufl.dot(problem.u, problem.u))), flux, 0.0)


def mean_through(problem: FlowProblem, field, leaving: bool = True) -> float:
    """The flux-weighted mean of a field leaving (or entering) the workpiece,
    int f |u.n| / int |u.n| over the outflow (inflow): the mean of the product (of the stock)."""
    weight = _flux_weight(problem, leaving)
    return _integrate(problem, field * weight * problem.ds) / _integrate(problem, weight * problem.ds)


def mean_strain_through(problem: FlowProblem, leaving: bool = True) -> float:
    """The mean equivalent strain of the product (or of the stock, ``leaving`` False)."""
    return mean_through(problem, problem.strain, leaving)


def product_flow_stress(problem: FlowProblem) -> float:
    """The drawn product's flow stress at the process strain rate: at its mean exit strain for a
    hardening law, the scene's reference flow stress otherwise."""
    scene = problem.scene
    if problem.strain is None:
        return scene.reference_flow_stress
    return float(scene.material.flow_stress([scene.reference_strain_rate],
                                            mean_strain_through(problem))[0])


def hardening_scalars(problem: FlowProblem) -> dict[str, float]:
    """With a hardening law: the mean entry and exit strains, the ideal strain ln(A0/A1) (2/sqrt3 ln(h0/h1) in
    plane strain), the redundant-work factor (exit strain gained over the ideal), and the mean flow
    stress Ybar = P / (Q (eps_exit - eps_in)): the plastic work rate P = int sigma rate over the
    throughput Q and the strain gained, as the ideal-work formulas use it."""
    if problem.strain is None:
        return {}
    g = problem.scene.geometry
    exit_strain, entry_strain = mean_strain_through(problem), mean_strain_through(problem, False)
    gained = exit_strain - entry_strain
    ratio = g.entry_thickness / g.exit_thickness
    ideal = 2 * math.log(ratio) if g.axisymmetric else 2 / math.sqrt(3) * math.log(ratio)
    rate = problem.equivalent_strain_rate(problem.u)
    work = _integrate(problem, problem.flow_stress(problem.u) * rate * problem.dx)
    return {"mean_entry_strain": entry_strain, "mean_exit_strain": exit_strain, "ideal_strain": ideal,
            "redundant_work_factor": gained / ideal,
            "mean_flow_stress": work / (throughput(problem) * gained) if gained > 0 else math.nan,
            "product_flow_stress": product_flow_stress(problem)}


def exit_section(problem: FlowProblem, points: int) -> tuple[float, np.ndarray]:
    """The product's section half an exit thickness before the workpiece's end, x, and ``points``
    heights on it from the axis to the surface (the last a hair inside)."""
    g = problem.scene.geometry
    return g.length - 0.5 * g.thinnest, np.linspace(0.0, g.thinnest * (1 - 1e-9), points)


def exit_profile(problem: FlowProblem, field, points: int = 41) -> dict[str, Any] | None:
    """A field across the product on the exit_section (rank 0; None elsewhere; collective)."""
    from forming_fenicsx.post.sections import values_at

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
    from forming_fenicsx.post.sections import values_at
    from forming_fenicsx.post.streamlines import streamline_strain

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


def surface_cell_depth(mesh, x: float, y: float, cells: int = 1) -> float:
    """How far below the point (x, y) at the surface the lowest node of the ``cells``-th cell down
    from it lies (collective): the layer in which a profile's values rest on so many elements."""
    query, lowest = y, y
    for _ in range(cells):
        found = colliding_cells(mesh, np.array([[x, query, 0.0]]))[0]
        local = mesh.geometry.x[cell_geometry_nodes(mesh)[found], 1].min() if found >= 0 else np.inf
        lowest = mesh.comm.allreduce(local, op=MPI.MIN)
        query = lowest - 1e-6 * (y - lowest)  # just inside the next cell down
    return float(y - lowest)


def thermal_scalars(problem: FlowProblem, numbers: dict[str, float]) -> dict[str, Any]:
    """With [thermal]: the temperature taken from the converged flow (one way), the product's mean
    (flux-weighted), lowest and highest exit temperature (across the exit section), the workpiece's
    lowest and highest (nodal values), and the energy
    balance (TemperatureField.energy_balance) against the work of the driving force, the ram or
    drawing force (``numbers``) times the process velocity (plus the applied force's on Gamma5)."""
    field = problem.field("temperature")
    if field is None:
        return {}
    field.settle(problem.u)
    force = numbers["ram_force"] if "ram_force" in numbers else numbers["drawing_force"]
    power = force * problem.scene.process.velocity
    if problem.has_force:
        power += _integrate(problem, problem.scene.process.applied_force
                            * ufl.dot(problem.u, problem.n) * problem.ds(ROLES["gamma5_force"]))
    balance = field.energy_balance(power)
    profile = exit_profile(problem, field.T)
    extremes = problem.comm.bcast(
        (float(profile["values"].min()), float(profile["values"].max())) if profile else None)
    nodal = field.T.x.array
    return {"mean_exit_temperature": mean_through(problem, field.T), "min_exit_temperature": extremes[0],
            "max_exit_temperature": extremes[1],
            "min_temperature": problem.comm.allreduce(float(nodal.min()), op=MPI.MIN),
            "max_temperature": problem.comm.allreduce(float(nodal.max()), op=MPI.MAX),
            "energy_balance": balance, "energy_balance_residual": balance["global_residual"]}


def free_surface_crossing(problem: FlowProblem) -> float:
    """Volume crossing the free strip surfaces (Gamma2, Gamma4 facets whose normal is mostly along y),
    in or out, relative to the flux through Gamma1: zero for a steady state whose free surfaces are
    streamlines, so it measures what the fixed-domain model (2.6) lets cross them."""
    surface = ufl.conditional(ufl.gt(abs(problem.n[1]), 0.5), 1.0, 0.0)
    out = sum(_integrate(problem, abs(ufl.dot(problem.u, problem.n)) * surface * problem.ds(ROLES[role]))
              for role in ("gamma2_free", "gamma4_free") if role in problem.roles)
    through = throughput(problem)
    return out / through if through else math.nan


def throughput(problem: FlowProblem) -> float:
    """|flux through Gamma1|: the volume the model forms per unit time (per unit width of the half
    model in plane strain)."""
    return abs(_integrate(problem, ufl.dot(problem.u, problem.n) * problem.ds(ROLES["gamma1_velocity"])))


def die_penetration(problem: FlowProblem) -> float:
    """Volume flowing into the die (u_N > 0 on Gamma3) over the throughput: the penalty (3.4) lets the
    workpiece into the die at u_N = d_N sigma_N, which must stay a small fraction of the flow."""
    if not problem.has_contact:
        return 0.0
    inflow = _integrate(problem, ufl.max_value(contact.normal_velocity(problem.u, problem.n), 0.0)
                        * problem.ds_contact)
    through = throughput(problem)
    return inflow / through if through else math.nan


def die_contact_fraction(problem: FlowProblem) -> float:
    """The contact length over the length of Gamma3 (contact_zone.py; NaN without a die)."""
    if not problem.has_contact:
        return math.nan
    facets = facet_integrals(problem, problem.contact_pressure(problem.u), in_contact(problem), 1.0)
    zone = zone_scalars(facets) if facets is not None else None
    zone = problem.comm.bcast(zone, root=0)
    return zone["die_contact_fraction"]


def exit_zone_rate_ratio(problem: FlowProblem) -> float:
    """Mean equivalent strain rate over the last exit thickness of the workpiece (x within one full exit
    thickness of its downstream end) over its mean over the whole workpiece: near zero when the product
    leaves the die rigid, of order one when it yields after the die."""
    x = ufl.SpatialCoordinate(problem.mesh)[0]
    end = problem.comm.allreduce(problem.mesh.geometry.x[:, 0].max(), op=MPI.MAX)
    zone = ufl.conditional(ufl.gt(x, end - problem.scene.geometry.exit_thickness), 1.0, 0.0)
    rate = problem.equivalent_strain_rate(problem.u)
    mean = _integrate(problem, rate * problem.dx) / _integrate(problem, 1.0 * problem.dx)
    zone_mean = _integrate(problem, rate * zone * problem.dx) / _integrate(problem, zone * problem.dx)
    return zone_mean / mean if mean > 0 else math.nan


def mean_exit_strain(problem: FlowProblem) -> float:
    """The flux-weighted mean equivalent strain of the product: with u.grad(eps) = rate along the
    streamlines and div u = 0, div(eps u) = rate, so int_exit eps u.n = int rate dx over the
    workpiece (eps = 0 entering, no flow through the die and free surfaces) and the mean is
    int rate dx / Q, Q the throughput. Compare the homogeneous strain ln(A0/A1) (round) or
    (2/sqrt3) ln(h0/h1) (strip): the excess is the redundant strain."""
    through = throughput(problem)
    return _integrate(problem, problem.equivalent_strain_rate(problem.u) * problem.dx) / through \
        if through else math.nan


def dissipation_outside_window(problem: FlowProblem) -> dict[str, float]:
    """The fractions of the plastic work rate int sigma_p rate dissipated where the law is linear
    (viscous) instead of nearly rate-independent: below rate1 and above rate2 for the law (4.5),
    below the rate floor for the others."""
    law = problem.scene.material
    rate = problem.equivalent_strain_rate(problem.u)
    power = problem.flow_stress(problem.u) * rate
    total = _integrate(problem, power * problem.dx)
    if total <= 0:
        return {}
    tests = (("above_rate2", ufl.gt(rate, law.rate2)), ("below_rate1", ufl.lt(rate, law.rate1))) \
        if hasattr(law, "rate2") else (("below_rate_floor", ufl.lt(rate, law.rate_floor)),)
    return {f"dissipation_{name}": _integrate(problem, ufl.conditional(test, power, 0.0)
                                              * problem.dx) / total for name, test in tests}


def force_balance(problem: FlowProblem) -> tuple[float, float, float, float, float]:
    """(relative residual, Gamma1 force, die normal x-force, die friction x-force, applied x-force) of the
    x force balance Gamma1 force + applied force = die force (verification.md), at the current state."""
    force = reaction(problem)
    die_normal, die_friction = die_forces_x(problem)
    external = applied_force_x(problem)
    die = die_normal + die_friction
    return (abs(force + external - die) / max(abs(force), abs(die), 1e-300), force, die_normal, die_friction,
            external)


def relative_divergence(problem: FlowProblem, divergence: float) -> float:
    """||div u|| / ||e(u)|| (L2 norms over the strip), given ||div u||: the volume change the penalty 1/d
    leaves, per unit of deformation rate; Theorem 3.1 drives it to zero like O(d)."""
    e = problem.strain_rate(problem.u)
    deformation = _integrate(problem, ufl.inner(e, e) * problem.dx)
    if deformation == 0:  # no deformation at all (e.g. a first solve that failed)
        return math.nan
    return float(divergence / np.sqrt(deformation))


def discrete_divergence(problem: FlowProblem) -> float:
    """|(q, div u)| over the pressure basis functions q (Euclidean norm): the incompressibility the mixed
    formulation imposes exactly (zero up to the linear solve), while ||div u|| itself is not zero."""
    q = ufl.TestFunction(problem.pressure.function_space)
    vector = dolfinx.fem.petsc.assemble_vector(dolfinx.fem.form(q * problem.divergence(problem.u) * problem.dx))
    vector.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
    value = vector.norm()
    vector.destroy()
    return value


# forces on the whole product (the model's times CoordinateSystem.whole and the strip's width)
PRODUCT_FORCES = ("ram_force", "drawing_force", "die_force_x", "die_normal_force_x",
                  "die_friction_force_x", "applied_force_x")
# the energy balance's ratios; its other terms are powers, scaled as the forces
BALANCE_RATIOS = ("residual", "global_residual")


def whole_product(problem: FlowProblem, numbers: dict[str, Any]) -> dict[str, Any]:
    """The model's forces and powers made the whole product's: times 2 for the plane-strain half
    model (per unit width), and times geometry.width when the scene gives it (then in force
    units). The die separation force acts on each die half, which the half model holds whole: it
    takes the width only."""
    width = problem.scene.geometry.width or 1.0
    factor = problem.coordinates.whole * width
    scaled = {key: value * factor if key in PRODUCT_FORCES else value
              for key, value in numbers.items()}
    if "die_separation_force" in scaled:
        scaled["die_separation_force"] *= width
    if "energy_balance" in scaled:
        scaled["energy_balance"] = {key: value if key in BALANCE_RATIOS else value * factor
                                    for key, value in scaled["energy_balance"].items()}
    return scaled


def scalars(problem: FlowProblem) -> dict[str, float]:
    """The summary numbers of a run: process force and pressure, die forces and the x force balance,
    forces on the whole product (whole_product).

    Extrusion: ram force and pressure (force over the Gamma1 height), p_av. Drawing: drawing force
    and stress (Gamma1 force over the exit half-thickness), q_av, contact length and end.
    """
    residual, force, die_normal, die_friction, external = force_balance(problem)
    divergence = float(np.sqrt(_integrate(problem, problem.divergence(problem.u) ** 2 * problem.dx_vol)))
    if problem.scene.process.kind == "extrusion":
        height = _integrate(problem, 1.0 * problem.ds(ROLES["gamma1_velocity"]))
        process = {"ram_force": force, "ram_pressure": force / height,
                   "mean_hydrostatic_pressure": mean_hydrostatic_pressure(problem)}
        if problem.scene.geometry.die != "square":
            process.update({**die_scalars(problem), **pass_shape(problem)})
    else:
        stress = force / problem.coordinates.section(problem.scene.geometry.thinnest)
        strength = problem.coordinates.tensile_yield_factor * product_flow_stress(problem)
        process = {"drawing_force": force, "drawing_stress": stress, "product_yield_ratio": stress / strength,
                   **die_scalars(problem), **pass_shape(problem)}
    return whole_product(problem, {
        **process,
        **hardening_scalars(problem),
        **thermal_scalars(problem, process),
        "die_force_x": die_normal + die_friction,
        "die_separation_force": die_separation_force(problem),
        "die_normal_force_x": die_normal,
        "die_friction_force_x": die_friction,
        "applied_force_x": external,
        "force_balance_residual": residual,
        "divergence_l2": divergence,
        "relative_divergence": relative_divergence(problem, divergence),
        **({"discrete_divergence": discrete_divergence(problem)} if problem.mixed else {}),
        "free_surface_crossing": free_surface_crossing(problem),
        "die_penetration": die_penetration(problem),
        **({} if "die_contact_fraction" in process else
           {"die_contact_fraction": die_contact_fraction(problem)}),
        "exit_zone_rate_ratio": exit_zone_rate_ratio(problem),
        # a hardening law's is the transported strain's (hardening_scalars)
        **({} if problem.strain is not None else {"mean_exit_strain": mean_exit_strain(problem)}),
        **dissipation_outside_window(problem),
    })


def nodal_velocity(problem: FlowProblem) -> dolfinx.fem.Function:
    """The velocity on Lagrange elements of the geometry degree (interpolated when the element
    differs): the form XDMF, ParaView and the flow lines read."""
    degree = geometry_degree(problem.mesh)
    if problem.scene.discretisation.degree == degree:
        return problem.u
    space = function_space(problem.mesh, "P", degree, (2,))
    velocity = dolfinx.fem.Function(space, name="velocity")
    velocity.interpolate(problem.u)
    return velocity


NON_NEGATIVE_FIELDS = ("equivalent_strain_rate", "secant_viscosity", "equivalent_strain", "flow_stress")
# the floor of a non-negative field relative to its largest value: far above the rounding (1e-15
# relative) with which dolfinx's XDMF writer evaluates the nodal function at the nodes, so the file
# holds no negative value, and far below anything a figure or ParaView shows
FLOOR = 1e-12


def output_fields(problem: FlowProblem) -> list[dolfinx.fem.Function]:
    """Velocity, equivalent strain rate, hydrostatic pressure and secant viscosity at the mesh nodes
    (and, with a hardening law, the equivalent strain and the flow stress).

    Scalars are nodal means (lumped projections) on Lagrange elements of the geometry degree, the
    form XDMF and ParaView read. Q2's basis functions change sign, so the nodal mean
    (f, phi_i)/(1, phi_i) of a non-negative f can be negative where f varies steeply (-4e-3 of the
    equivalent strain rate was seen): the non-negative fields (NON_NEGATIVE_FIELDS) are clipped,
    max(value, FLOOR max|value|), node by node (the projection is not positivity-preserving; the
    clip is). Without the floor, the writer's rounding left -3e-12 of a largest 2e3 in the file.
    """
    space = function_space(problem.mesh, "P", geometry_degree(problem.mesh))
    sources = {
        "equivalent_strain_rate": (problem.equivalent_strain_rate(problem.u), problem.full_degree),
        "hydrostatic_pressure": (problem.hydrostatic_stress(), problem.volumetric_degree),
        "secant_viscosity": (problem.secant_coefficient(), problem.full_degree),
    }
    if problem.strain is not None:  # a hardening law: its strain and flow stress
        sources["equivalent_strain"] = (problem.strain, problem.full_degree)
        sources["flow_stress"] = (problem.flow_stress(problem.u), problem.full_degree)
    fields = [nodal_velocity(problem)]
    if problem.field("temperature") is not None:  # [thermal]: the temperature, as solved
        fields.append(problem.field("temperature").T)
    for name, (expr, quadrature) in sources.items():
        target = LumpedProjector(expr, dolfinx.fem.Function(space, name=name), quadrature).project()
        if name in NON_NEGATIVE_FIELDS:
            largest = problem.comm.allreduce(np.abs(target.x.array).max(initial=0.0), op=MPI.MAX)
            np.maximum(target.x.array, FLOOR * largest, out=target.x.array)
        fields.append(target)
    return fields


def ram_face_pressure_model(law, d: float, ram_pressure: float) -> float:
    """p_av on Gamma1 predicted from the ram pressure, for the zone at the ram that the penalty compresses.

    Beside the ram the container holds u_y ~ 0, so the penalty's volumetric rate e = d sigma_H is a
    uniaxial-strain compression of equivalent rate 2/3 |e| and s_xx = 4/9 G e. Below rate1 of (4.5)
    G = sigma_p(rate1)/rate1 and p_ram = p_av (1 + 4/9 G d); above it the zone yields and
    p_ram = p_av + 2/3 sigma_p(2/3 d p_av). As d -> 0, p_av -> p_ram.
    """
    stiff = law.secant(np.array([law.rate1]))[0]
    p_av = ram_pressure / (1 + 4 / 9 * stiff * d)
    if 2 / 3 * d * p_av < law.rate1:
        return p_av
    p_av = ram_pressure
    for _ in range(50):  # fixed point; sigma_p barely depends on the rate here
        p_av = ram_pressure - 2 / 3 * law.flow_stress(np.array([2 / 3 * d * p_av]))[0]
    return p_av

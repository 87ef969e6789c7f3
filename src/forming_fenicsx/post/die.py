"""The die: the contact pressure on Gamma3 (the penalty's sigma_N of (3.4), or the stress's), the
stresses at its nodes (in 2D a profile along the die coordinate s, in 3D a table of x, y, z), and
the contact zone's scalars (contact_zone.py)."""
from __future__ import annotations

import math

import dolfinx.fem
import numpy as np
import ufl
from mpi4py import MPI
from ufl.core.expr import Expr

from forming_fenicsx.fem.forms import FlowProblem
from forming_fenicsx.mesh.geometry import die_coordinate
from forming_fenicsx.post import rolls
from forming_fenicsx.post.contact_zone import facet_integrals, zone_scalars
from forming_fenicsx.post.die_nodes import PRESSED, on_die_nodes
from forming_fenicsx.post.integrals import integrate


def in_contact(problem: FlowProblem) -> Expr:
    """1 where the workpiece presses on the die (sigma_N < 0), else 0."""
    return ufl.conditional(ufl.gt(problem.contact_pressure(problem.u), 0.0), 1.0, 0.0)


def die_pressure(problem: FlowProblem) -> Expr:
    """Contact pressure -sigma_N on Gamma3: the contact's (lambda + u_N/d_N)^+ (contact.py), or
    -n.sigma.n of the stress."""
    if problem.scene.output.die_pressure == "stress":
        n = problem.n
        return -ufl.dot(n, ufl.dot(problem.coordinates.in_plane(problem.stress()), n))
    return problem.contact_pressure(problem.u)


def die_stresses(problem: FlowProblem) -> dict[str, dolfinx.fem.Function]:
    """The stresses on Gamma3 at its nodes (P1, lumped projections over Gamma3): contact
    pressure, averaged normal stress (when friction uses it) and friction stress |sigma_T|; on a
    roll also the friction stress and the slip along the roll's motion (signed, rolls.py).

    |sigma_T| is the length of the projected friction traction, each component projected: where
    a sticking wall's traction changes sign from node to node (a plug pushed into a sticking
    container: 0.1 to 0.3 MPa of wall shear, oscillating by 55 MPa), the projection of the
    length would show the oscillation and not the stress (docs/free_surface.md)."""
    found = contact_pressures(problem)
    if problem.normal_stress_average is not None:
        found["averaged_normal_stress"] = on_die_nodes(
            problem, problem.normal_stress_average.value, "averaged_normal_stress")
    if problem.has_friction:
        traction = problem.friction_traction()
        parts = [on_die_nodes(problem, traction[i]) for i in range(problem.mesh.geometry.dim)]
        length = dolfinx.fem.Function(parts[0].function_space, name="friction_stress")
        length.x.array[:] = np.sqrt(sum(part.x.array ** 2 for part in parts))
        found["friction_stress"] = length
    if problem.rolling:  # signed along the roll's motion: the friction hill and the neutral point
        found["shear_stress"] = on_die_nodes(problem, rolls.shear_along(problem), "shear_stress")
        found["slip"] = on_die_nodes(problem, rolls.slip_along(problem), "slip")
    return found


def contact_pressures(problem: FlowProblem) -> dict[str, dolfinx.fem.Function]:
    """The contact pressure alone at the nodes of Gamma3 (die_stresses' first entry): all that
    contact_end_x reads, for a flow that is not post-processed in full."""
    return {"contact_pressure": on_die_nodes(problem, die_pressure(problem), "contact_pressure")}


def die_profile(problem: FlowProblem, stresses: dict[str, dolfinx.fem.Function] | None = None
                ) -> dict[str, np.ndarray] | None:
    """The nodes of Gamma3 with die_stresses there (``stresses`` when given), on rank 0 (None
    elsewhere; collective): in 2D ordered by the die coordinate s (its first column); in 3D x,
    y, z ordered by x, then around the section from the plane z = 0 to the plane y = 0
    (descending atan2(y, z))."""
    stresses = die_stresses(problem) if stresses is None else stresses
    space = next(iter(stresses.values())).function_space
    owned = space.dofmap.index_map.size_local
    dofs = dolfinx.fem.locate_dofs_topological(space, problem.mesh.topology.dim - 1,
                                               problem.role_facets("gamma3_contact"))
    dofs = dofs[dofs < owned]
    points = space.tabulate_dof_coordinates()[dofs]
    columns = {axis: points[:, i] for i, axis in enumerate("xyz"[:problem.mesh.geometry.dim])}
    columns.update({name: stress.x.array[dofs] for name, stress in stresses.items()})
    gathered = problem.comm.gather(columns, root=0)
    if problem.comm.rank != 0:
        return None
    profile = {key: np.concatenate([part[key] for part in gathered]) for key in columns}
    if "z" in profile:
        order = np.lexsort((-np.arctan2(profile["y"], profile["z"]), profile["x"]))
        return {key: profile[key][order] for key in columns}
    profile["s"] = die_coordinate(problem.scene, profile["x"], profile["y"])
    order = np.argsort(profile["s"])
    return {key: profile[key][order] for key in ["s", *columns]}


def _zone(problem: FlowProblem, pressure: Expr, cone: Expr | float) -> dict[str, float]:
    """contact_zone.zone_scalars of ``pressure`` where the workpiece is in contact, ``cone``
    marking the die's part from its entry to the land, on every rank (collective)."""
    facets = facet_integrals(problem, pressure, in_contact(problem), cone)
    zone = zone_scalars(facets) if facets is not None else None
    return problem.comm.bcast(zone, root=0)


def die_scalars(problem: FlowProblem) -> dict[str, float]:
    """die_scalars_of the die profile (die_profile; collective)."""
    return die_scalars_of(problem, die_profile(problem))


def die_scalars_of(problem: FlowProblem, profile: dict[str, np.ndarray] | None
                   ) -> dict[str, float]:
    """q_av over the contact zone's part in the die from its entry to the land (the paper's mean
    die pressure; over all of Gamma3 for a user's mesh), the contact length (contact_zone.py:
    the facets inside the zone count whole, however finely the die is described), and the x
    where the workpiece leaves the die (last node of Gamma3 with positive contact pressure, from
    ``profile``: die_profile's, on rank 0; None on the other ranks). Collective."""
    g, x = problem.scene.geometry, ufl.SpatialCoordinate(problem.mesh)
    cone: Expr | float = 1.0  # a user's mesh: all of Gamma3 (it has no die angle nor entry)
    if not g.mesh_file:
        start = g.die_entry + problem.scene.output.die_entry_trim * math.cos(
            math.radians(g.die_angle))
        cone = ufl.conditional(
            ufl.And(ufl.ge(x[0], start), ufl.le(x[0], g.die_entry + g.cone_length)), 1.0, 0.0)
    zone = _zone(problem, die_pressure(problem), cone)
    return {"mean_die_pressure": zone["mean_die_pressure"],
            "contact_length": zone["contact_length"],
            "contact_end_x": contact_end_x(problem, profile),
            "die_contact_fraction": zone["die_contact_fraction"]}


def contact_end_x(problem: FlowProblem, profile: dict[str, np.ndarray] | None) -> float:
    """The x of the last node of Gamma3 with positive contact pressure in ``profile``
    (die_profile's, on rank 0; None on the other ranks), on every rank. Collective."""
    end = None
    if profile is not None:
        pressure = profile["contact_pressure"]
        pressed = pressure > PRESSED * max(pressure.max(), 1e-300)
        end = float(profile["x"][pressed].max()) if pressed.any() else float("nan")
    return problem.comm.bcast(end, root=0)


def die_scalars_3d(problem: FlowProblem) -> dict[str, float]:
    """A 3D die's q_av (the contact pressure over the part of the faces in contact from the die
    entry to the land, area-weighted; over all of Gamma3 for a user's mesh), the product's contact
    area (the model's times CoordinateSystem.whole), the largest x in contact and the fraction of
    the die's area in contact (quadrature points in contact: the straight faces do not make the
    contact flicker, contact_zone.py)."""
    g, x = problem.scene.geometry, ufl.SpatialCoordinate(problem.mesh)
    cone = 1.0 if g.mesh_file else ufl.conditional(
        ufl.And(ufl.ge(x[0], g.die_entry), ufl.le(x[0], g.die_entry + g.cone_length)), 1.0, 0.0)
    touching, ds = in_contact(problem), problem.ds_contact
    area = integrate(problem, touching * cone * ds)
    force = integrate(problem, die_pressure(problem) * touching * cone * ds)
    contact = integrate(problem, touching * ds)
    pressure = on_die_nodes(problem, die_pressure(problem))
    space = pressure.function_space
    facets = problem.role_facets("gamma3_contact")
    dofs = dolfinx.fem.locate_dofs_topological(space, problem.mesh.topology.dim - 1, facets)
    pressed = dofs[pressure.x.array[dofs] > 0]
    end = space.tabulate_dof_coordinates()[pressed, 0].max(initial=-math.inf)
    return {"mean_die_pressure": force / area if area > 0 else 0.0,
            "contact_area": contact * problem.coordinates.whole,
            "contact_end_x": problem.comm.allreduce(float(end), op=MPI.MAX),
            "die_contact_fraction": contact / integrate(problem, 1.0 * ds)}


def die_contact_fraction(problem: FlowProblem) -> float:
    """The contact length over the length of Gamma3 (contact_zone.py; NaN without a die)."""
    if not problem.has_contact:
        return math.nan
    return _zone(problem, problem.contact_pressure(problem.u), 1.0)["die_contact_fraction"]

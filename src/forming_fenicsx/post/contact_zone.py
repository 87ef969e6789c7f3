"""The die's contact zone, facet by facet: its length and the mean die pressure over it.

The penalty contact pressure (lambda + u_N/d_N)^+ is read at the quadrature points of the Gamma3
facets. Where the die wall turns at a facet's end (a CSV polyline, a user's mesh), the continuous
velocity cannot be tangent to both facets, so u_N changes sign within each facet and the pressure
is zero at some of its quadrature points although the facet and its neighbours press on the die
(the contact "flickers"), and counting only the quadrature points makes the zone short and its
mean pressure high (docs/outputs.md). Here the facets inside a zone count whole, and so do its end
facets when the zone flickers (whole_facets); a die whose contact points do not flicker (a
straight wall) gets the quadrature points' measure.
"""
from __future__ import annotations

import dolfinx.fem
import dolfinx.fem.petsc
import numpy as np
import ufl
from petsc4py import PETSc

from forming_fenicsx.core.compat import function_space
from forming_fenicsx.mesh.geometry import die_coordinate

# a facet in contact at quadrature points of all but this fraction of its length is wholly in
# contact
FULL = 1e-9
# a gap in the contact zone up to this fraction of its span is bridged (bridged_gaps)
BRIDGED = 0.1
# the facet integrals gathered per Gamma3 facet
COLUMNS = ("length", "contact", "area", "area_contact", "cone", "cone_contact", "cone_pressure",
           "cone_contact_pressure")


def facet_integrals(problem, pressure, touching, cone) -> dict[str, np.ndarray] | None:
    """Per Gamma3 facet (rank 0, sorted by the die coordinate s of the facet's midpoint; None on
    the other ranks): its length and its length in contact (``touching``, an indicator at the
    quadrature points), along the die; with the coordinate system's weight (the die's surface
    when axisymmetric) its area and area in contact, and over its part in the cone (``cone``, an
    indicator) its area, its area in contact, the integral of ``pressure`` and that of
    ``pressure`` where in contact."""
    mesh = problem.mesh
    space = function_space(mesh, "DP", 0)
    test = ufl.TestFunction(space)
    plain = problem.ds.measure(problem.roles["gamma3_contact"])
    weighted = problem.ds_contact
    integrands = {"length": 1.0 * test * plain, "contact": touching * test * plain,
                  "area": 1.0 * test * weighted, "area_contact": touching * test * weighted,
                  "cone": cone * test * weighted, "cone_contact": touching * cone * test * weighted,
                  "cone_pressure": pressure * cone * test * weighted,
                  "cone_contact_pressure": pressure * touching * cone * test * weighted}
    owned = space.dofmap.index_map.size_local
    values = {}
    for name, form in integrands.items():
        vector = dolfinx.fem.petsc.assemble_vector(dolfinx.fem.form(form))
        vector.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        values[name] = vector.array[:owned].copy()
        vector.destroy()
    cells = np.flatnonzero(values["length"] > 0)
    midpoints = _facet_midpoints(problem, cells)
    part = {name: values[name][cells] for name in COLUMNS}
    part["x"], part["y"] = midpoints[:, 0], midpoints[:, 1]
    gathered = problem.comm.gather(part, root=0)
    if problem.comm.rank != 0:
        return None
    joined = {key: np.concatenate([p[key] for p in gathered]) for key in part}
    s = die_coordinate(problem.scene, joined["x"], joined["y"])
    order = np.argsort(s)
    return {"s": s[order], **{key: joined[key][order] for key in COLUMNS}}


def _facet_midpoints(problem, cells: np.ndarray) -> np.ndarray:
    """The midpoint of the Gamma3 facet of each cell (the mean of the facets' when a cell has
    several)."""
    mesh = problem.mesh
    tdim = mesh.topology.dim
    facets = problem.role_facets("gamma3_contact")
    mesh.topology.create_connectivity(tdim - 1, tdim)
    to_cell = mesh.topology.connectivity(tdim - 1, tdim)
    owner = np.array([to_cell.links(f)[0] for f in facets], dtype=np.int64)
    midpoints = dolfinx.mesh.compute_midpoints(mesh, tdim - 1, np.asarray(facets, dtype=np.int32))
    result = np.zeros((len(cells), 2))
    for row, cell in enumerate(cells):
        result[row] = midpoints[owner == cell, :2].mean(axis=0)
    return result


def bridged_gaps(length: np.ndarray, touching: np.ndarray) -> np.ndarray:
    """Facets out of contact between facets in contact on both sides, in runs no longer along the
    die than BRIDGED times the zone's span (its first to its last facet in contact): where the
    elements are much shorter than a polyline die's segments, the workpiece bears on the segments'
    ends and lifts off whole facets between them (an adapted mesh on a CSV die: runs of one to
    three facets under 0.2 mm segments; docs/outputs.md)."""
    bridged = np.zeros(len(touching), dtype=bool)
    where = np.flatnonzero(touching)
    if len(where) < 2:
        return bridged
    span = length[where[0]:where[-1] + 1].sum()
    gaps = np.flatnonzero(np.diff(where) > 1)
    for first, last in zip(where[gaps] + 1, where[gaps + 1], strict=True):
        if length[first:last].sum() <= BRIDGED * span:
            bridged[first:last] = True
    return bridged


def whole_facets(length: np.ndarray, contact: np.ndarray) -> np.ndarray:
    """The facets counted whole: those in contact at some quadrature point, or in a bridged gap
    (bridged_gaps), whose neighbours along the die both are (inside the zone), and the zone's end
    facets whose neighbour inside it is in contact at some of its points only (a zone whose points
    flicker does not tell where it ends within a facet; next to a facet wholly in contact, the
    points do)."""
    touching = contact > 0
    zone = touching | bridged_gaps(length, touching)
    partial = touching & (contact < (1 - FULL) * length)
    before = np.concatenate([[False], zone[:-1]])
    after = np.concatenate([zone[1:], [False]])
    partial_before = np.concatenate([[False], partial[:-1]])
    partial_after = np.concatenate([partial[1:], [False]])
    inside = zone & before & after
    ends = touching & ((before & ~after & partial_before) | (after & ~before & partial_after))
    return inside | ends


def zone_scalars(facets: dict[str, np.ndarray]) -> dict[str, float]:
    """The contact length (along the die), the fraction of the die's area in contact, and the
    mean die pressure q_av over the contact zone's part in the cone (area-weighted; zero without
    contact there), whole_facets counted whole."""
    inside = whole_facets(facets["length"], facets["contact"])
    contact = np.where(inside, facets["length"], facets["contact"])
    area = np.where(inside, facets["area"], facets["area_contact"]).sum()
    cone = np.where(inside, facets["cone"], facets["cone_contact"]).sum()
    force = np.where(inside, facets["cone_pressure"], facets["cone_contact_pressure"]).sum()
    return {"contact_length": float(contact.sum()),
            "die_contact_fraction": float(area / facets["area"].sum()),
            "mean_die_pressure": float(force / cone) if cone > 0 else 0.0}

"""What a 3D run's tables and figures show, sampled on boundary facets (facet_samples.py): the die
faces with their stresses, the symmetry planes with the velocity and the strain rate, and the
exit section with a field (the hardening run's strain)."""
from __future__ import annotations

import dolfinx.fem
import dolfinx.mesh
import numpy as np
from mpi4py import MPI

from forming_fenicsx.core.compat import geometry_degree
from forming_fenicsx.fem.forms import FlowProblem
from forming_fenicsx.fem.projection import cell_means
from forming_fenicsx.post.facet_samples import FacetSamples, coincident, sample_facets
from forming_fenicsx.post.output_fields import nodal_velocity

# the symmetry planes of a 3D model and the coordinates (x and the other one) of each
PLANES = {"gamma7_symmetry": (0, 1), "gamma6_symmetry": (0, 2)}


def role_samples(problem: FlowProblem, role: str, functions: list[dolfinx.fem.Function]
                 ) -> FacetSamples | None:
    """The functions on the facets of a boundary role, at their nodes' grid (geometry degree);
    on rank 0 (collective)."""
    return sample_facets(functions, problem.role_facets(role), geometry_degree(problem.mesh))


def die_faces(problem: FlowProblem, stresses: dict[str, dolfinx.fem.Function]
              ) -> FacetSamples | None:
    """The die's stresses (post/die.py: die_stresses, in that order) over the facets of Gamma3;
    on rank 0 (collective)."""
    return role_samples(problem, "gamma3_contact", list(stresses.values()))


def symmetry_planes(problem: FlowProblem) -> dict[str, FacetSamples] | None:
    """The nodal velocity (3 columns) and the cell-mean equivalent strain rate (1) over each
    symmetry plane of the model (PLANES), by role; on rank 0 (collective)."""
    rate = cell_means(problem.mesh, problem.equivalent_strain_rate(problem.u), "rate",
                      problem.full_degree)
    velocity = nodal_velocity(problem)
    planes = {role: role_samples(problem, role, [velocity, rate])
              for role in PLANES if role in problem.roles}
    return planes if problem.comm.rank == 0 else None


def exit_face(problem: FlowProblem, function: dolfinx.fem.Function) -> FacetSamples | None:
    """A function over the workpiece's downstream end face (the boundary facets at its largest
    x), at the face's nodes; on rank 0 (collective)."""
    mesh = problem.mesh
    end = problem.comm.allreduce(float(mesh.geometry.x[:, 0].max()), op=MPI.MAX)
    tolerance = 1e-9 * max(end - problem.comm.allreduce(float(mesh.geometry.x[:, 0].min()),
                                                        op=MPI.MIN), 1e-300)
    facets = dolfinx.mesh.locate_entities_boundary(
        mesh, mesh.topology.dim - 1, lambda x: np.abs(x[0] - end) < tolerance)
    return sample_facets([function], facets, geometry_degree(mesh))


def exit_section_values(problem: FlowProblem, function: dolfinx.fem.Function
                        ) -> dict[str, object] | None:
    """A scalar function at the nodes of the exit section (exit_face), each once, ordered by y
    and then z: {"y", "z", "values"} and the exit face's ``samples`` (for its map), on rank 0
    (None elsewhere; collective)."""
    samples = exit_face(problem, function)
    if samples is None:
        return None
    points, values = samples.points.reshape(-1, 3)[:, 1:], samples.values.reshape(-1)
    first, _ = coincident(points)
    points, values = points[first], values[first]
    # the push-forward's rounding off the symmetry planes (-4e-17) set to zero, the order by the
    # rounded coordinates
    scale = np.abs(points).max()
    points[np.abs(points) < 1e-12 * scale] = 0.0
    keys = np.round(points / scale, 9)
    order = np.lexsort((keys[:, 1], keys[:, 0]))
    return {"y": points[order, 0], "z": points[order, 1], "values": values[order],
            "samples": samples}


def strain_undershoot(section: dict[str, object] | None, entry: float, comm: MPI.Comm) -> str:
    """The nodes of the exit section (exit_section_values' ``section``, rank 0) where the
    transported strain lies below the stock's entry strain ``entry``: no strain falls along a
    streamline, so these are the transport's undershoot (SUPG at the die edge's corner streamline,
    docs/strain_transport.md), not strains. They are set to NaN in the section's values and its
    samples (exit_strain.csv and .png leave them out). Returns the warning that says so ("" when
    there are none), on every rank (collective)."""
    found = (0, np.nan)
    if section is not None:
        floor = entry - 1e-6 * max(1.0, abs(entry))
        below = section["values"] < floor
        found = (int(np.count_nonzero(below)),
                 float(section["values"][below].min()) if below.any() else np.nan)
        section["values"][below] = np.nan
        section["samples"].values[section["samples"].values < floor] = np.nan
    count, least = comm.bcast(found, root=0)
    return "" if not count else (
        f"the transported strain lies below the stock's entry strain ({entry:g}) at {count} "
        f"node(s) of the exit section (least {least:.4g}): the transport's undershoot where the "
        "die's edges shear the bar's corner (docs/strain_transport.md), not a strain; "
        "exit_strain.csv and .png leave them out (NaN)")

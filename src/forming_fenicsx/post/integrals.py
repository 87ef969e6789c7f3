"""The integral of a form over the workpiece, every rank's part summed: the one reduction that the
forces, means and ratios of a run are made of."""
from __future__ import annotations

import dolfinx.fem
import ufl

from forming_fenicsx.fem.forms import FlowProblem


def integrate(problem: FlowProblem, integrand: ufl.Form) -> float:
    """The scalar form ``integrand`` (its measure included) assembled and summed over the ranks."""
    local = dolfinx.fem.assemble_scalar(dolfinx.fem.form(integrand))
    return problem.comm.allreduce(local)

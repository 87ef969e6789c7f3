"""The die's stresses at the nodes of Gamma3 (P1), and the share of the largest contact pressure
above which a node presses on the die: the one reading that die.csv, the contact's end and the
unpressed friction share."""
from __future__ import annotations

import dolfinx.fem
from ufl.core.expr import Expr

from forming_fenicsx.core.compat import function_space
from forming_fenicsx.fem.forms import FlowProblem
from forming_fenicsx.fem.projection import LumpedProjector

# a node presses on the die where its contact pressure exceeds this share of the largest
PRESSED = 1e-9


def on_die_nodes(problem: FlowProblem, expr: Expr, name: str = "f") -> dolfinx.fem.Function:
    """A quantity on Gamma3 at the nodes of P1: its lumped projection over Gamma3 (zero at the
    nodes elsewhere)."""
    target = dolfinx.fem.Function(function_space(problem.mesh, "P", 1), name=name)
    return LumpedProjector(expr, target, problem.full_degree, problem.ds_contact).project()

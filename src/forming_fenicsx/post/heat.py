"""The heat of a run with [thermal]: the product's exit temperatures, the workpiece's extremes and
the energy balance against the work of the driving force."""
from __future__ import annotations

from typing import Any

import ufl
from mpi4py import MPI

from forming_fenicsx.core.roles import ROLES
from forming_fenicsx.fem.forms import FlowProblem
from forming_fenicsx.post.exit_profiles import exit_profile
from forming_fenicsx.post.flux import mean_through
from forming_fenicsx.post.integrals import integrate


def thermal_scalars(problem: FlowProblem, numbers: dict[str, float]) -> dict[str, Any]:
    """With [thermal]: the temperature taken from the converged flow (one way), the product's mean
    (flux-weighted), lowest and highest exit temperature (across the exit section), the
    workpiece's lowest and highest (nodal values), and the energy balance
    (TemperatureField.energy_balance) against the work of the driving force, the ram or drawing
    force (``numbers``) times the process velocity (plus the applied force's on Gamma5), or the
    rolls' and the tensions' power."""
    field = problem.field("temperature")
    if field is None:
        return {}
    field.settle(problem.u)
    if problem.rolling:  # the rolls' power and the tensions' (rolls.power_balance)
        power = numbers["roll_power"] + numbers["power_balance"]["tension_power"]
    else:
        force = numbers["ram_force"] if "ram_force" in numbers else numbers["drawing_force"]
        power = force * problem.scene.process.velocity
        if problem.has_force:
            power += integrate(problem, problem.scene.process.applied_force
                               * ufl.dot(problem.u, problem.n) * problem.ds(ROLES["gamma5_force"]))
    balance = field.energy_balance(power)
    profile = exit_profile(problem, field.T)
    extremes = problem.comm.bcast(
        (float(profile["values"].min()), float(profile["values"].max())) if profile else None)
    nodal = field.T.x.array
    return {"mean_exit_temperature": mean_through(problem, field.T),
            "min_exit_temperature": extremes[0], "max_exit_temperature": extremes[1],
            "min_temperature": problem.comm.allreduce(float(nodal.min()), op=MPI.MIN),
            "max_temperature": problem.comm.allreduce(float(nodal.max()), op=MPI.MAX),
            "energy_balance": balance, "energy_balance_residual": balance["global_residual"]}

"""Frozen coefficients: fields the flow's forms read at a state the iteration updates on its own
schedule (the outer loop of the modified method (3.33), every iterate of the direct method (3.13),
every Newton step). The friction bound tau_f is one; a strain or temperature field joins the same
way.

Protocol: ``freeze(u)`` takes the coefficient from the velocity u (a relaxed or accelerated step
for a coupled field); ``settle(u)`` takes it at u itself; ``change(u)`` is the relative change
freezing at u would make (the outer loop has converged when every change is below delta);
``snapshot()`` and ``restore(saved)`` keep and bring back its values (an iteration that restarts
from an earlier iterate, newton.py's fallback, restores what its coefficients were then);
``start_at(u)`` sets it for an iteration started from a velocity near the answer (a restart, the
last flow of a free-surface update), where a cold start's schedule would only lose solves.
``coupled``: a field of its own that the flow law reads (strain, temperature: an iteration
converges only once it settles), not the friction bound; ``tangent``: Newton's step can carry its
derivative. The coupled fields live in forming_fenicsx.coupled and join a flow problem through
FlowProblem.couple.
"""
from __future__ import annotations

from typing import Protocol

import dolfinx.fem

from forming_fenicsx.core.compat import petsc_vec


class FrozenCoefficient(Protocol):
    name: str
    coupled: bool  # a field of its own (strain, temperature), not the friction bound
    tangent: bool  # Newton's step can carry its derivative (velocity_derivative, transport_solve)

    def freeze(self, u: dolfinx.fem.Function) -> None: ...

    def change(self, u: dolfinx.fem.Function) -> float: ...

    def settle(self, u: dolfinx.fem.Function) -> None: ...

    def snapshot(self) -> object: ...

    def restore(self, saved: object) -> None: ...

    def start_at(self, u: dolfinx.fem.Function) -> None: ...


class FrozenVelocity:
    """A coefficient that is a function of a frozen velocity ``state`` (u_{0,m} of (3.33) for the
    friction bound), with the fields derived from it (``derived``: objects with update(), e.g. the
    averaged normal stress) recomputed on each freeze."""

    coupled = False
    tangent = False

    def __init__(self, name: str, space, derived: list | None = None):
        self.name = name
        self.state = dolfinx.fem.Function(space)
        self.derived = derived or []

    def freeze(self, u: dolfinx.fem.Function) -> None:
        petsc_vec(u).copy(petsc_vec(self.state))
        self.state.x.scatter_forward()
        for field in self.derived:
            field.update()

    def settle(self, u: dolfinx.fem.Function) -> None:
        self.freeze(u)

    def start_at(self, u: dolfinx.fem.Function) -> None:
        """Nothing: the iteration freezes the state at its first iterate, whatever the start."""

    def snapshot(self) -> object:
        return self.state.x.array.copy()

    def restore(self, saved: object) -> None:
        self.state.x.array[:] = saved
        for field in self.derived:
            field.update()

    def change(self, u: dolfinx.fem.Function) -> float:
        """||u - state|| / ||u||."""
        difference = petsc_vec(u).copy()
        difference.axpy(-1.0, petsc_vec(self.state))
        norm = petsc_vec(u).norm()
        value = difference.norm() / norm if norm > 0 else 0.0
        difference.destroy()
        return value

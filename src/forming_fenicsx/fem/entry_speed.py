"""Rolling's entry speed, which the flow decides: the entry face Gamma1 is free along x (it carries
the back tension), and the strip is held along x only by the friction with the rolls.

Friction's bound tau_f is frozen from an earlier iterate (forms.FlowProblem.friction_bound), so the
first solve, from a uniform modulus, would have no friction and a free x-translation. That solve
holds Gamma1's x-velocity at a guess v_0 by the penalty traction -k (u_x - v_0) with k = 1/d_N,
the contact's stiffness, without the tensions (``released`` 0 scales them: a front tension could
pull the strip off the rolls in that viscous first solve, and leave no friction to hold it). With
Coulomb friction the hold lasts two solves: the first freeze takes the friction bound mu sigma_N
from the viscous solve's contact pressure, and the iterate solved with it is held too (released
after the viscous solve alone, strips near the bite limit stopped: docs/rolling.md). The factor
law's bound m k does not come from that pressure: its hold ends at the first freeze. Once
released (k = 0, the tensions on), every iterate solves the problem with the entry speed free. A
held iterate never counts as converged (``change`` is 1).
"""
from __future__ import annotations

import dolfinx.fem
from petsc4py import PETSc


class EntrySpeed:
    """The hold of Gamma1's x-velocity at ``guess`` with the stiffness ``stiffness`` for the
    first ``held_solves`` solves (a frozen coefficient of the flow problem, frozen.py)."""

    name = "entry speed hold"
    coupled = False
    tangent = False

    def __init__(self, mesh, guess: float, stiffness: float, ds_entry, held_solves: int):
        self.stiffness = dolfinx.fem.Constant(mesh, PETSc.ScalarType(stiffness))
        self.released = dolfinx.fem.Constant(mesh, PETSc.ScalarType(0.0))
        self.guess = dolfinx.fem.Constant(mesh, PETSc.ScalarType(guess))
        self.ds = ds_entry
        self.held_solves = held_solves
        self.freezes = 0  # since the hold began

    @property
    def held(self) -> bool:
        return float(self.stiffness.value) > 0

    def form(self, u, v):
        """int_G1 k u_x v_x: the hold's part of the bilinear form."""
        return self.stiffness * u[0] * v[0] * self.ds

    def load(self, v):
        """int_G1 k v_0 v_x: the hold's part of the right-hand side."""
        return self.stiffness * self.guess * v[0] * self.ds

    def energy(self, u):
        """int_G1 k/2 (u_x - v_0)^2: the hold's part of Newton's energy."""
        return 0.5 * self.stiffness * (u[0] - self.guess) ** 2 * self.ds

    def freeze(self, u: dolfinx.fem.Function) -> None:
        self.freezes += 1
        if self.freezes >= self.held_solves:
            self.settle(u)

    def settle(self, u: dolfinx.fem.Function) -> None:
        self.stiffness.value, self.released.value = 0.0, 1.0

    def start_at(self, u: dolfinx.fem.Function) -> None:
        """Nothing: the hold's schedule is a cold start's (rolling refuses the free-surface
        update; a --restart holds the entry speed as the first run did)."""

    def change(self, u: dolfinx.fem.Function) -> float:
        return 1.0 if self.held else 0.0

    def snapshot(self) -> object:
        return float(self.stiffness.value), float(self.released.value), self.freezes

    def restore(self, saved: object) -> None:
        self.stiffness.value, self.released.value, self.freezes = saved

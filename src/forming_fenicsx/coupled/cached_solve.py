"""The linear solve of a coupled field for a velocity, kept: an iteration freezes, settles and
measures the change of a field (frozen.py) several times at the same velocity, and one solve serves
them all."""
from __future__ import annotations

import dolfinx.fem
import numpy as np
from mpi4py import MPI

from forming_fenicsx.core.errors import LinearSolveError
from forming_fenicsx.fem.linear_problem import LinearProblem


class CachedSolve:
    """``problem`` solved into its ``u`` with ``velocity`` (the Function its forms read) set to the
    velocity asked for; ``inputs``: the other Functions its forms read (the heat source's frozen
    temperature), whose change also needs a new solve. A velocity that is zero everywhere (before
    the first flow solve) carries nothing: the solution is then ``kept``'s values. ``name`` names
    the field in a failed solve's message."""

    def __init__(self, problem: LinearProblem, velocity: dolfinx.fem.Function,
                 kept: dolfinx.fem.Function, name: str,
                 inputs: tuple[dolfinx.fem.Function, ...] = ()):
        self.problem, self.velocity, self.kept, self.name = problem, velocity, kept, name
        self.inputs = inputs
        self.solves = 0
        self._solved_for: tuple[np.ndarray, ...] | None = None

    def solve(self, u: dolfinx.fem.Function) -> dolfinx.fem.Function:
        """The solution for the velocity u (collective): the last one, without solving, when u and
        the inputs equal those it was solved for, even if a Constant the forms read has changed
        since."""
        comm = self.velocity.function_space.mesh.comm
        arrays = (u.x.array, *(f.x.array for f in self.inputs))
        if self._unchanged(comm, arrays):
            return self.problem.u
        if comm.allreduce(float(np.abs(u.x.array).max(initial=0.0)), op=MPI.MAX) == 0:
            self.problem.u.x.array[:] = self.kept.x.array
            return self.problem.u
        self.velocity.x.array[:] = u.x.array
        self.velocity.x.scatter_forward()
        try:
            self.problem.solve()
        except LinearSolveError as error:
            raise LinearSolveError(f"the {self.name} solve failed: {error}") from None
        self.solves += 1
        self._solved_for = tuple(array.copy() for array in arrays)
        return self.problem.u

    def forget(self) -> None:
        """Solve at the next call whatever the velocity (the field's values were restored)."""
        self._solved_for = None

    def _unchanged(self, comm: MPI.Comm, arrays: tuple[np.ndarray, ...]) -> bool:
        """Whether every array equals its kept copy on every rank (decided together: a velocity
        changed on one rank's entries only must be solved for on all, or the ranks part ways in
        the solve)."""
        same = self._solved_for is not None and all(
            np.array_equal(a, b) for a, b in zip(self._solved_for, arrays, strict=True))
        return bool(comm.allreduce(same, op=MPI.LAND))

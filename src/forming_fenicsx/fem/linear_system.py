"""One linear system a(s, w) = L(w) of a scalar field coupled to the flow (the transported strain,
the temperature): assembled with its Dirichlet conditions and solved by a PETSc KSP under a named
option prefix (MUMPS LU unless the options say otherwise; an iterative solve that fails falls back
to it)."""
from __future__ import annotations

import dolfinx.fem
import dolfinx.fem.petsc
import numpy as np
from mpi4py import MPI
from petsc4py import PETSc

from forming_fenicsx.core.compat import petsc_vec
from forming_fenicsx.core.petsc_options import PrefixedOptions

DIRECT = {"ksp_type": "preonly", "pc_type": "lu", "pc_factor_mat_solver_type": "mumps"}


class LinearSystem:
    """The compiled forms a and L, their matrix, vector and KSP (prefix ``prefix``_). The options
    are held until the first solve has set the KSP up: a preconditioner's sub-solvers (block
    Jacobi's ``sub_``) and MUMPS read theirs only then."""

    def __init__(self, a: dolfinx.fem.Form, L: dolfinx.fem.Form, comm: MPI.Comm, prefix: str,
                 bcs: list | None = None, options: dict | None = None):
        self.a, self.L, self.bcs = a, L, bcs or []
        self.matrix = dolfinx.fem.petsc.create_matrix(a)
        self.rhs = dolfinx.fem.petsc.create_vector(L)
        self.ksp = PETSc.KSP().create(comm)
        self.ksp.setOperators(self.matrix)
        self._options: PrefixedOptions | None = PrefixedOptions(prefix, {**DIRECT, **(options or {})})
        self.ksp.setOptionsPrefix(self._options.prefix)
        self.ksp.setFromOptions()

    def solve(self, target: dolfinx.fem.Function, name: str) -> None:
        """Assemble at the coefficients' current values and solve into ``target`` (collective); a
        failed solve raises RuntimeError naming ``name``."""
        self.matrix.zeroEntries()
        dolfinx.fem.petsc.assemble_matrix(self.matrix, self.a, bcs=self.bcs)
        self.matrix.assemble()
        with self.rhs.localForm() as local:
            local.set(0.0)
        dolfinx.fem.petsc.assemble_vector(self.rhs, self.L)
        dolfinx.fem.petsc.apply_lifting(self.rhs, [self.a], bcs=[self.bcs])
        self.rhs.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        dolfinx.fem.petsc.set_bc(self.rhs, self.bcs)
        self.solve_vector(self.rhs, petsc_vec(target), name)
        target.x.scatter_forward()

    def solve_vector(self, b: PETSc.Vec, x: PETSc.Vec, name: str) -> None:
        """x = a^-1 b with the matrix last assembled; an iterative solve that fails (the same
        reason on every rank) is repeated by MUMPS LU, which the KSP keeps from then on."""
        self.ksp.solve(b, x)
        self._release_options()
        if self.ksp.getConvergedReason() < 0 and self.ksp.getType() != "preonly":
            self.ksp.setType("preonly")
            self.ksp.getPC().setType("lu")
            self.ksp.getPC().setFactorSolverType("mumps")
            self.ksp.solve(b, x)
        if self.ksp.getConvergedReason() < 0:
            raise RuntimeError(f"the {name} solve failed: KSP reason {self.ksp.getConvergedReason()}")

    def _release_options(self) -> None:
        if self._options is not None:
            self._options.release()
            self._options = None

    def destroy(self) -> None:
        self._release_options()
        for item in (self.ksp, self.matrix, self.rhs):
            item.destroy()


def unchanged(comm: MPI.Comm, kept: tuple[np.ndarray, ...] | None, *arrays: np.ndarray) -> bool:
    """Whether every array equals the kept copy on every rank (decided together: a field changed
    on one rank's entries only must be solved for on all, or the ranks part ways in the solve)."""
    same = kept is not None and all(np.array_equal(a, b) for a, b in zip(kept, arrays, strict=True))
    return bool(comm.allreduce(same, op=MPI.LAND))

"""Two-level p-multigrid for the velocity block of the iterative solver (fem/saddle_point.py): the
Q2 velocity smoothed on its own level (a symmetric SOR sweep, by default), the error left to the Q1
velocity on the same mesh, whose operator P^T A P (P the Q1 -> Q2 interpolation) GAMG V-cycles
solve with the rigid-body near-null space: algebraic multigrid does well on the Q1 operator, not on
the Q2 block itself (27-node hexahedra; measured in docs/iterative_solver.md).

The fine level is the fieldsplit's velocity block of the scaled augmented system, S A S, in the
order of its index set: the interpolation into it is S^-1 P with its rows so ordered (the Galerkin
coarse operator (S^-1 P)^T S A S (S^-1 P) = P^T A P is the unscaled one). The coarse operator is
computed here before each solve, from the whole scaled system and the interpolation into its
velocity rows (the fieldsplit extracts its block only inside the solve), so that GAMG finds the
near-null space on it at its set-up.
"""
from __future__ import annotations

from collections.abc import Callable

import dolfinx.fem
import numpy as np
from petsc4py import PETSc

from forming_fenicsx.core.compat import function_space, interpolation_matrix

# the symmetric SOR sweeps (local to each rank) before and after the coarse correction
# (docs/iterative_solver.md, "the Q2 smoother": one sweep took the time of two Chebyshev steps with
# Jacobi, with iterations that grew 1.1 times from 3147 to 276819 unknowns instead of 1.2, and 0.6
# times as many at a viscosity contrast of 2e6)
SMOOTHING_STEPS = 1
# the GAMG V-cycles on the Q1 level per application (docs/iterative_solver.md: 2 took 19 % less
# solve time than 1)
COARSE_CYCLES = 2


def moved_rows(matrix: PETSc.Mat, rows: np.ndarray, count: int) -> PETSc.Mat:
    """A matrix of ``count`` local rows whose local row rows[i] is ``matrix``'s local row i (the
    others empty), with ``matrix``'s columns."""
    indptr, indices, values = matrix.getValuesCSR()
    lengths = np.diff(indptr)
    moved = np.zeros(count, dtype=np.int64)
    moved[rows] = lengths
    offsets = np.concatenate([[0], np.cumsum(moved)])
    position = np.arange(len(indices)) + np.repeat(offsets[rows] - indptr[:-1], lengths)
    new_indices = np.empty(len(indices), dtype=PETSc.IntType)
    new_values = np.empty(len(values))
    new_indices[position] = indices
    new_values[position] = values
    return PETSc.Mat().createAIJ(
        ((count, PETSc.DECIDE), matrix.getSizes()[1]),
        csr=(offsets.astype(PETSc.IntType), new_indices, new_values), comm=matrix.getComm())


def orthonormal_null_space(arrays: list[np.ndarray], like: PETSc.Vec) -> PETSc.NullSpace:
    """The span of ``arrays`` (local parts of vectors of ``like``'s layout), Gram-Schmidt
    orthonormalised, as a PETSc null space."""
    vectors = []
    for values in arrays:
        vector = like.duplicate()
        vector.array[:] = values
        for previous in vectors:
            vector.axpy(-vector.dot(previous), previous)
        vector.normalize()
        vectors.append(vector)
    space = PETSc.NullSpace().create(vectors=vectors, comm=like.getComm())
    for vector in vectors:  # the null space holds them
        vector.destroy()
    return space


class PMultigrid:
    """The Q1 level under the fieldsplit's velocity block: ``velocity`` the collapsed velocity
    space, ``system_index`` the global index in the system of each of its owned dofs (unrolled),
    ``block`` the fieldsplit's index set of those (sorted), ``rows`` the system's local rows
    (start, end), ``modes`` the rigid-body motions of a space's owned dofs in an order
    (saddle_point.rigid_body_modes)."""

    def __init__(self, velocity: dolfinx.fem.FunctionSpace, system_index: np.ndarray,
                 block: PETSc.IS, rows: tuple[int, int],
                 modes: Callable[[dolfinx.fem.FunctionSpace, np.ndarray], list[np.ndarray]]
                 ) -> None:
        mesh = velocity.mesh
        self.space = coarse = function_space(mesh, "P", 1, (mesh.geometry.dim,))  # Q1
        interpolation = interpolation_matrix(coarse, velocity)
        start, end = rows
        self._system = moved_rows(interpolation, system_index - start, end - start)  # P
        interpolation.destroy()
        self._scaled = self._system.copy()  # S^-1 P
        self._block = block
        first, last = self._system.getOwnershipRangeColumn()
        self._columns = PETSc.IS().createStride(last - first, first, 1, comm=mesh.comm)
        like = self._system.createVecRight()
        owned = coarse.dofmap.index_map.size_local * coarse.dofmap.index_map_bs
        self._modes = orthonormal_null_space(modes(coarse, np.arange(owned)), like)
        like.destroy()
        self._dim = mesh.geometry.dim
        self.interpolation: PETSc.Mat | None = None  # S^-1 P in the fieldsplit's velocity rows
        self.coarse: PETSc.Mat | None = None  # P^T A P

    def install(self, pc: PETSc.PC) -> None:
        """Make the velocity block's PCMG (``pc``, not yet set up) two levels with this
        interpolation and coarse operator (after the first update): SMOOTHING_STEPS symmetric SOR
        sweeps before and after on Q2, COARSE_CYCLES GAMG V-cycles on Q1, unless the
        options under the levels' prefixes (``fieldsplit_u_mg_levels_``,
        ``fieldsplit_u_mg_coarse_``) say otherwise (set here, not among the defaults: GAMG, itself
        a PCMG, would read them)."""
        pc.setMGLevels(2)
        pc.setMGInterpolation(1, self.interpolation)
        smoother = pc.getMGSmoother(1)
        smoother.setType(PETSc.KSP.Type.RICHARDSON)
        smoother.getPC().setType(PETSc.PC.Type.SOR)
        smoother.setTolerances(max_it=SMOOTHING_STEPS)
        smoother.setFromOptions()
        coarse = pc.getMGCoarseSolve()
        coarse.setOperators(self.coarse, self.coarse)
        coarse.setType(PETSc.KSP.Type.RICHARDSON)
        coarse.setTolerances(max_it=COARSE_CYCLES)
        coarse.setNormType(PETSc.KSP.NormType.NONE)  # no residual norms: the cycles alone
        coarse.getPC().setType(PETSc.PC.Type.GAMG)
        coarse.setFromOptions()

    def update(self, A: PETSc.Mat, scale: PETSc.Vec) -> None:
        """The interpolation S^-1 P and the coarse operator P^T A P for the scaled system ``A``
        (S: ``scale``), in the objects the PCMG holds."""
        inverse = scale.copy()
        inverse.reciprocal()
        self._system.copy(self._scaled, structure=PETSc.Mat.Structure.SAME_NONZERO_PATTERN)
        self._scaled.diagonalScale(L=inverse)
        inverse.destroy()
        first = self.coarse is None
        self.coarse = A.PtAP(self._scaled, result=self.coarse)
        self.interpolation = self._scaled.createSubMatrix(self._block, self._columns,
                                                          submat=self.interpolation)
        if first:
            self.coarse.setBlockSize(self._dim)
            self.coarse.setNearNullSpace(self._modes)

    def destroy(self) -> None:
        for item in (self._system, self._scaled, self._columns, self._modes, self.interpolation,
                     self.coarse):
            if item is not None:
                item.destroy()

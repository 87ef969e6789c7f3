"""The iterative solver of the mixed formulation's saddle point (solver.linear = "iterative"): an
augmented Lagrangian, a symmetric scaling, and FGMRES with a fieldsplit Schur preconditioner and a
two-level p-multigrid (Q2 -> Q1, p_multigrid.py) on the velocity block.

The system

    [A  B^T] [u]   [f]          A: the velocity block (secant b(w; u, v) of (3.5), or Newton's
    [B   0 ] [p] = [g],         operator), B: -(q, div u), g: the Dirichlet data's lifting,

is solved as the augmented system (augmented Lagrangian, Benzi and Olshanskii 2006)

    [A + gamma B^T D^-1 B   B^T] [u]   [f + gamma B^T D^-1 g]
    [B                       0 ] [p] = [g                   ],

whose solution is the same (B u = g), with D = diag(M_eta), M_eta = int (1/eta) p q the pressure
mass weighted by the secant viscosity eta = G/3: the term stiffens the velocity block's volumetric
modes (the deviatoric viscous form has none) and makes -(1 + gamma) D^-1 a Schur complement
preconditioner. The system is solved scaled symmetrically, S K S y = S b, x = S y, with
S = diag(A_ii^-1/2) on the velocities and ((1 + gamma)/D_ii)^1/2 on the pressures: the Krylov's
residual then weighs every row alike (unscaled, the rows of the rigid zones, whose eta is up to the
rate window's 1e6 times larger, decide it, and the pressure of the plastic zone is left far less
accurate than the residual says). PETSc fieldsplit
(Schur, upper factorisation) under the solver's options prefix: multigrid on the velocity block
(one application of the two-level p-multigrid of p_multigrid.py per outer iteration, Q2 smoothed
and Q1 solved by GAMG cycles), the Schur preconditioner (-1 on the scaled pressures), FGMRES
outside. ``fieldsplit_u_pc_type = "gamg"`` in
solver.petsc_options puts GAMG on the Q2 block itself instead (with the rigid-body near-null
space), the preconditioner before the p-multigrid.
"""
from __future__ import annotations

from typing import Any

import dolfinx.fem
import dolfinx.fem.petsc
import numpy as np
import ufl
from petsc4py import PETSc

from forming_fenicsx.fem.p_multigrid import PMultigrid, orthonormal_null_space

# the augmentation's weight (docs/iterative_solver.md, "the Q2 smoother and gamma": with one
# multigrid application per outer iteration, 3 needed the fewest iterations at 92k and 277k
# unknowns and grew least with the mesh; the larger gamma, the more the velocity block's multigrid
# grew, while with that block solved exactly the outer iterations stayed flat)
GAMMA = 3.0
# the options under the KSP's prefix (a scene's solver.petsc_options override any)
OPTIONS: dict[str, Any] = {
    "ksp_type": "fgmres", "ksp_gmres_restart": 200, "ksp_max_it": 1000,
    "ksp_initial_guess_nonzero": True, "ksp_converged_use_initial_residual_norm": True,
    "pc_type": "fieldsplit", "pc_fieldsplit_type": "schur",
    "pc_fieldsplit_schur_fact_type": "upper", "pc_fieldsplit_schur_precondition": "user",
    # the velocity block: one application of its preconditioner per outer iteration (a Krylov
    # solve inside each, GMRES to 1e-2, took twice the time: docs/iterative_solver.md)
    "fieldsplit_u_ksp_type": "preonly",
    # "mg": the velocity block's p-multigrid (p_multigrid.py; its levels' options under
    # fieldsplit_u_mg_levels_ and fieldsplit_u_mg_coarse_); "gamg": GAMG on the Q2 block, with
    # this graph threshold
    "fieldsplit_u_pc_type": "mg", "fieldsplit_u_pc_gamg_threshold": 0.02,
    "fieldsplit_p_ksp_type": "preonly", "fieldsplit_p_pc_type": "jacobi"}


def owned_subspace(space: dolfinx.fem.FunctionSpace, index: int,
                   collapsed: tuple[dolfinx.fem.FunctionSpace, Any] | None = None
                   ) -> tuple[np.ndarray, Any]:
    """The global indices (in ``space``, sorted) of the owned dofs of sub-space ``index``, and that
    sub-space collapsed with the map of its owned dofs into them. ``collapsed``: the sub-space
    already collapsed, with its map into ``space`` (dolfinx 0.5's collapse took 70 % of a
    277k-unknown problem's set-up)."""
    sub, parent = space.sub(index).collapse() if collapsed is None else collapsed
    parent = np.asarray(parent)
    owned = sub.dofmap.index_map.size_local * sub.dofmap.index_map_bs
    offset = space.dofmap.index_map.local_range[0] * space.dofmap.index_map_bs
    local = parent[:owned]
    order = np.argsort(local)
    return local[order] + offset, (sub, order)


def rigid_body_modes(velocity: dolfinx.fem.FunctionSpace, order: np.ndarray) -> list[np.ndarray]:
    """The rigid motions (translations and rotations: 3 in 2D, 6 in 3D) on the owned velocity dofs
    in ``order``: multigrid's near-null space of the velocity block."""
    dim = velocity.mesh.geometry.dim
    owned = velocity.dofmap.index_map.size_local
    points = velocity.tabulate_dof_coordinates()[:owned]
    coordinates = np.repeat(points, dim, axis=0)[order]
    component = np.tile(np.arange(dim), owned)[order]
    rotations = [(0, 1)] if dim == 2 else [(0, 1), (1, 2), (2, 0)]
    modes = []
    for k in range(dim + len(rotations)):
        values = np.zeros(len(order))
        if k < dim:
            values[component == k] = 1.0
        else:
            i, j = rotations[k - dim]
            values[component == i] = -coordinates[component == i, j]
            values[component == j] = coordinates[component == j, i]
        modes.append(values)
    return modes


class AugmentedSaddlePoint:
    """The augmentation and fieldsplit of one mixed system on ``space`` (velocity x pressure), the
    pressure weight 1/eta = 3/G from the UFL coefficient ``secant`` (G of a(w; u, v)); ``collapsed``
    the velocity and pressure spaces with their maps into ``space``, if already collapsed."""

    def __init__(self, space: dolfinx.fem.FunctionSpace, secant, dx: ufl.Measure,
                 gamma: float = GAMMA, collapsed: list[tuple[Any, Any]] | None = None):
        comm = space.mesh.comm
        self.gamma = gamma
        collapsed = collapsed or [None, None]
        velocity_dofs, (velocity, order) = owned_subspace(space, 0, collapsed[0])
        pressure_dofs, (pressure, self._pressure_order) = owned_subspace(space, 1, collapsed[1])
        self.velocity = PETSc.IS().createGeneral(velocity_dofs.astype(PETSc.IntType), comm=comm)
        self.velocity.setBlockSize(space.mesh.geometry.dim)
        self.pressure = PETSc.IS().createGeneral(pressure_dofs.astype(PETSc.IntType), comm=comm)
        start, end = space.dofmap.index_map.local_range
        bs = space.dofmap.index_map_bs
        self.rows = PETSc.IS().createStride((end - start) * bs, start * bs, 1, comm=comm)
        self._modes = rigid_body_modes(velocity, order)
        # what the p-multigrid needs: the velocity space, each owned dof's index in the system
        system_index = np.empty_like(velocity_dofs)
        system_index[order] = velocity_dofs
        self._velocity_space = velocity, system_index, (start * bs, end * bs)
        self.multigrid: PMultigrid | None = None  # the velocity block's (with pc_type "mg")
        self.modes: PETSc.NullSpace | None = None  # in the scaled unknowns (scale)
        self._ksp: PETSc.KSP | None = None
        self._scale: PETSc.Vec | None = None  # S
        # M_eta on the pressure space alone (its cells' blocks; on the mixed space the matrix would
        # have the whole system's pattern, and cost as much to assemble as the flow's)
        p, q = ufl.TrialFunction(pressure), ufl.TestFunction(pressure)
        self._weight = dolfinx.fem.form(3.0 / secant * p * q * dx)
        self._weight_matrix = dolfinx.fem.petsc.create_matrix(self._weight)
        self._weight_diagonal = self._weight_matrix.createVecLeft()
        # the Schur preconditioner -D/(1 + gamma) scaled by S^2 (scale): -1 on the pressure dofs
        sizes = (len(pressure_dofs), PETSc.DECIDE)
        self.schur = PETSc.Mat().createAIJ((sizes, sizes), nnz=1, comm=comm)
        self._inverse = self.schur.createVecLeft()  # D^-1
        self._inverse.set(-1.0)
        self.schur.setDiagonal(self._inverse)
        self.schur.assemble()
        self._B: PETSc.Mat | None = None  # the pressure rows of the system (constant)
        self._scaled: PETSc.Mat | None = None  # D^-1 B
        self._product: PETSc.Mat | None = None  # B^T D^-1 B
        self.velocity_iterations = 0  # the velocity block's Krylov iterations, all solves

    def augment_matrix(self, A: PETSc.Mat) -> None:
        """A += gamma B^T D^-1 B (in A's sparsity: B couples the velocity dofs of one cell), with D
        at the coefficients' current values."""
        M = self._weight_matrix
        M.zeroEntries()
        dolfinx.fem.petsc.assemble_matrix(M, self._weight)
        M.assemble()
        M.getDiagonal(self._weight_diagonal)
        # the pressure space's owned dofs in the order of the system's (the index set's)
        self._inverse.array[:] = 1.0 / self._weight_diagonal.array[self._pressure_order]
        if self._B is None:  # -(q, div u) does not change with the state
            self._B = A.createSubMatrix(self.pressure, self.rows)
        if self._scaled is None:
            self._scaled = self._B.copy()
        else:
            self._B.copy(self._scaled, structure=PETSc.Mat.Structure.SAME_NONZERO_PATTERN)
        self._scaled.diagonalScale(L=self._inverse)
        # the same matrices and pattern at every call: the product's symbolic phase is kept
        self._product = self._B.transposeMatMult(self._scaled, result=self._product)
        A.axpy(self.gamma, self._product, structure=PETSc.Mat.Structure.SUBSET_NONZERO_PATTERN)

    def augment_vector(self, b: PETSc.Vec) -> None:
        """b += gamma B^T D^-1 g, g the pressure rows of b (after augment_matrix)."""
        g = b.getSubVector(self.pressure)
        weighted = g.copy()
        b.restoreSubVector(self.pressure, g)
        weighted.pointwiseMult(weighted, self._inverse)
        extra = self._B.createVecRight()
        self._B.multTranspose(weighted, extra)
        b.axpy(self.gamma, extra)
        for item in (weighted, extra):
            item.destroy()

    def scale(self, A: PETSc.Mat, b: PETSc.Vec, x: PETSc.Vec) -> None:
        """A <- S A S, b <- S b and the initial guess x <- S^-1 x (after augment_matrix and
        augment_vector; unscale undoes it), and the near-null space's modes in the scaled
        unknowns, S^-1 r, orthonormal."""
        if self._scale is None:
            self._scale = b.duplicate()
        scale = self._scale
        A.getDiagonal(scale)
        velocity = scale.getSubVector(self.velocity)
        velocity.sqrtabs()
        velocity.reciprocal()
        self._set_modes(velocity)
        scale.restoreSubVector(self.velocity, velocity)
        pressure = scale.getSubVector(self.pressure)
        self._inverse.copy(pressure)
        pressure.scale(1.0 + self.gamma)
        pressure.sqrtabs()
        scale.restoreSubVector(self.pressure, pressure)
        A.diagonalScale(scale, scale)
        b.pointwiseMult(b, scale)
        x.pointwiseDivide(x, scale)

    def _set_modes(self, velocity_scale: PETSc.Vec) -> None:
        """The near-null space of the scaled velocity block, S^-1 r for the rigid motions r,
        orthonormal: a new one each time (PETSc locks a null space's vectors), composed with the
        velocity field and set on the fieldsplit's velocity matrix once it exists."""
        modes = orthonormal_null_space([values / velocity_scale.array for values in self._modes],
                                       velocity_scale)
        self.velocity.compose("nearnullspace", modes)
        if self._ksp is not None:
            self._ksp.getPC().getFieldSplitSubKSP()[0].getOperators()[1].setNearNullSpace(modes)
        if self.modes is not None:
            self.modes.destroy()
        self.modes = modes

    def unscale(self, A: PETSc.Mat, b: PETSc.Vec, x: PETSc.Vec) -> None:
        """A <- S^-1 A S^-1, b <- S^-1 b, and the solution x = S y of the scaled system."""
        x.pointwiseMult(x, self._scale)
        b.pointwiseDivide(b, self._scale)
        inverse = self._scale.copy()
        inverse.reciprocal()
        A.diagonalScale(inverse, inverse)
        inverse.destroy()

    def configure(self, ksp: PETSc.KSP) -> None:
        """The fieldsplit's two fields and its Schur preconditioner, and the velocity block's
        p-multigrid if its pc_type is "mg", once (after augment_matrix); the p-multigrid's operators
        at every solve (after scale)."""
        if self._ksp is None:
            self._set_up(ksp)
        elif self.multigrid is not None:
            self.multigrid.update(ksp.getOperators()[0], self._scale)

    def _set_up(self, ksp: PETSc.KSP) -> None:
        pc = ksp.getPC()
        pc.setFieldSplitIS(("u", self.velocity), ("p", self.pressure))
        options = PETSc.Options(ksp.getOptionsPrefix())
        if options.getString("pc_fieldsplit_schur_precondition", "user") == "user":
            # -D/(1 + gamma), unless solver.petsc_options chose another (e.g. "selfp")
            pc.setFieldSplitSchurPreType(PETSc.PC.SchurPreType.USER, self.schur)
        ksp.setUp()  # the fieldsplit's, not yet its blocks' preconditioners
        block = pc.getFieldSplitSubKSP()[0]
        block.setMonitor(self._count)
        self._ksp = ksp
        if block.getPC().getType() == PETSc.PC.Type.MG:
            velocity, system_index, rows = self._velocity_space
            self.multigrid = PMultigrid(velocity, system_index, self.velocity, rows,
                                        rigid_body_modes)
            self.multigrid.update(ksp.getOperators()[0], self._scale)
            self.multigrid.install(block.getPC())

    def _count(self, ksp: PETSc.KSP, iteration: int, residual: float) -> None:
        if iteration > 0:
            self.velocity_iterations += 1

    def destroy(self) -> None:
        for item in (self._weight_matrix, self._weight_diagonal, self.schur, self._inverse,
                     self._B, self._scaled, self._product, self.modes, self._scale, self.velocity,
                     self.pressure, self.rows, self.multigrid):
            if item is not None:
                item.destroy()

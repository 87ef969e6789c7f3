"""TangentGMRES (fem/tangent_gmres.py): J du = F with J = A + corrections, right-preconditioned
with A's factors, and what it leaves in du when GMRES stops short."""
from mpi4py import MPI
from petsc4py import PETSc

from forming_fenicsx.fem.tangent_gmres import TangentGMRES

SIZE = 40


def _matrix(entries) -> PETSc.Mat:
    """A SIZE x SIZE AIJ matrix on COMM_WORLD with entries(i) -> {column: value} in row i."""
    matrix = PETSc.Mat().createAIJ([SIZE, SIZE], nnz=5, comm=MPI.COMM_WORLD)
    start, end = matrix.getOwnershipRange()
    for i in range(start, end):
        for j, value in entries(i).items():
            if 0 <= j < SIZE:
                matrix.setValue(i, j, value)
    matrix.assemble()
    return matrix


class _Skew:
    """A nonsymmetric correction y += C x: GMRES preconditioned with A's factors needs more than
    5 iterations on A + C."""

    name = "skew"

    def __init__(self):
        self.C = _matrix(lambda i: {i - 1: -1.0, i + 2: 0.5})
        self._product = self.C.createVecs()[1]

    def assemble(self) -> None:
        pass

    def add_to(self, x: PETSc.Vec, y: PETSc.Vec) -> None:
        self.C.mult(x, self._product)
        y.axpy(1.0, self._product)


def _residual(A: PETSc.Mat, C: PETSc.Mat, F: PETSc.Vec, du: PETSc.Vec) -> float:
    """||F - (A + C) du||."""
    r, product = F.copy(), F.duplicate()
    A.mult(du, product)
    r.axpy(-1.0, product)
    C.mult(du, product)
    r.axpy(-1.0, product)
    return r.norm()


def _solve(keep: bool, iterations: int):
    """A^-1 F, then TangentGMRES with at most ``iterations``: whether it converged, the start
    A^-1 F, du, and ||F - J x|| at the start and at du."""
    A = _matrix(lambda i: {i - 1: -1.0, i: 2.5, i + 1: -1.0})
    factors = PETSc.KSP().create(MPI.COMM_WORLD)
    factors.setOperators(A)
    factors.setType("preonly")
    factors.getPC().setType("lu")
    factors.getPC().setFactorSolverType("mumps")
    options = PETSc.Options()
    options["newton_tangent_ksp_max_it"] = iterations
    try:
        tangent = TangentGMRES(A, factors)
    finally:  # the option must not reach another test's solver
        del options["newton_tangent_ksp_max_it"]
    F = A.createVecs()[1]
    start, end = F.getOwnershipRange()
    for i in range(start, end):
        F.setValue(i, 1.0 + 0.1 * i)
    F.assemble()
    du = F.duplicate()
    factors.solve(F, du)
    first = du.copy()
    skew = _Skew()
    converged = tangent.solve(F, du, [skew], keep)
    found = (converged, first, du, _residual(A, skew.C, F, first), _residual(A, skew.C, F, du))
    tangent.destroy()
    return found


def test_a_converged_solve_meets_the_tolerance():
    converged, _, _, start, end = _solve(keep=False, iterations=200)
    assert converged
    assert end < 1e-3 * start


def test_a_short_solve_keeps_its_iterate_or_the_start():
    """Stopped after 5 iterations: with keep, du is GMRES's iterate, whose residual is 0.45 of the
    start's (A^-1 F, the frozen step); without, du is the start, bit for bit."""
    converged, first, du, start, end = _solve(keep=True, iterations=5)
    assert not converged
    assert end < 0.6 * start
    converged, first, du, start, end = _solve(keep=False, iterations=5)
    assert not converged
    assert (du - first).norm() == 0.0 and end == start

"""Newton's step with the derivatives of the frozen coefficients: J du = F by GMRES.

Newton's operator A (newton_forms.py) differentiates the residual F(u; c) at frozen coefficients c
(the friction bound, a transported strain). Where c = c(u), the derivative of F(u; c(u)) is

    J = A + sum_k dF/dc_k dc_k/du,

each term applied matrix-free by its owner (``Correction``: the strain's -B D^-1 C in
coupled/strain_tangent.py, the friction bound's in friction_tangent.py). J du = F is solved by GMRES
right-preconditioned with A's factors, starting from A^-1 F: each iteration is a pair of triangular
solves with A's factors and the corrections' own products, so no matrix is factorised beyond
Newton's.
"""
from __future__ import annotations

from collections.abc import Sequence
from typing import Callable, Protocol

from petsc4py import PETSc

# relative residual of J du = F: 1e-6 took 11 to 18 iterations a step, 1e-2 more Newton steps
# (docs/hardening.md)
GMRES_TOLERANCE = 1e-3
GMRES_ITERATIONS = 30


class Correction(Protocol):
    """A term dF/dc dc/du of Newton's derivative: ``assemble()`` at the current u, then
    ``add_to(x, y)``: y += (dF/dc dc/du) x."""

    name: str

    def assemble(self) -> None: ...

    def add_to(self, x: PETSc.Vec, y: PETSc.Vec) -> None: ...


class TangentGMRES:
    """GMRES on J = A + the corrections, right-preconditioned with A's factors (the KSP
    ``factors``); the options prefix ``newton_tangent_`` can change the Krylov method."""

    def __init__(self, A: PETSc.Mat, factors: PETSc.KSP):
        self._A = A
        self.corrections: Sequence[Correction] = ()
        self._start = A.createVecs()[1]
        self._shell = PETSc.Mat().createPython(A.getSizes(), _Shell(self.mult), comm=A.getComm())
        self._shell.setUp()
        self._ksp = PETSc.KSP().create(A.getComm())
        self._ksp.setOperators(self._shell)
        self._ksp.setType("gmres")
        self._ksp.setPCSide(PETSc.PC.Side.RIGHT)
        self._ksp.getPC().setType("python")
        self._ksp.getPC().setPythonContext(_Shell(factors.solve))
        self._ksp.setTolerances(rtol=GMRES_TOLERANCE, max_it=GMRES_ITERATIONS)
        self._ksp.setInitialGuessNonzero(True)
        self._ksp.setOptionsPrefix("newton_tangent_")
        self._ksp.setFromOptions()
        self.iterations = 0

    def mult(self, x: PETSc.Vec, y: PETSc.Vec) -> None:
        """y = J x = A x + the corrections' products, with A and each as last assembled."""
        self._A.mult(x, y)
        for correction in self.corrections:
            correction.add_to(x, y)

    def solve(self, F: PETSc.Vec, du: PETSc.Vec, corrections: Sequence[Correction],
              keep: bool = False) -> bool:
        """J du = F by GMRES from du (A^-1 F on entry, A and its factors at the current u), each
        correction assembled first; True when it converged. Otherwise du is GMRES's last iterate
        when ``keep`` (its residual ||F - J du|| is at most the start's: GMRES minimises it over
        a space holding the start), else left as it came."""
        self.corrections = corrections
        for correction in corrections:
            correction.assemble()
        du.copy(self._start)
        self._ksp.solve(F, du)
        converged = self._ksp.getConvergedReason() > 0
        self.iterations = self._ksp.getIterationNumber()
        if not converged and not keep:
            self._start.copy(du)
        return converged

    def restore_start(self, du: PETSc.Vec) -> None:
        """du <- the last solve's start, A^-1 F (the frozen step)."""
        self._start.copy(du)

    def destroy(self) -> None:
        for item in (self._ksp, self._shell, self._start):
            item.destroy()


class _Shell:
    """A PETSc Python context (shell matrix or preconditioner) applying ``action(x, y)``."""

    def __init__(self, action: Callable[[PETSc.Vec, PETSc.Vec], None]):
        self._action = action

    def mult(self, _, x: PETSc.Vec, y: PETSc.Vec) -> None:
        self._action(x, y)

    def apply(self, _, x: PETSc.Vec, y: PETSc.Vec) -> None:
        self._action(x, y)

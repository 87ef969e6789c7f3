"""Anderson acceleration of a fixed point x = g(x) over distributed vectors (Walker & Ni, SIAM J.
Numer. Anal. 49 (2011) 1715), for the coefficients coupled to the flow through the
frozen-coefficient loop (frozen.py): the temperature (thermal.py).

With the residuals f_k = g(x_k) - x_k and the last ``depth`` differences
dF = [f_k - f_{k-1}, ...], dG = [g(x_k) - g(x_{k-1}), ...], the next iterate is

    x_{k+1} = x_k + beta f_k - (dX + beta dF) gamma,   gamma = argmin || f_k - dF gamma ||_2,

(dX the differences of the iterates; beta = 1 gives g(x_k) - dG gamma),

a secant (multisecant) update that damps the modes the plain iteration x_{k+1} = g(x_k) amplifies.
``depth`` = 0 is the plain iteration. The inner products are over the owned entries, summed over the
ranks, so every rank takes the same gamma.
"""
from __future__ import annotations

import numpy as np
from mpi4py import MPI


class AndersonMixing:
    """The next iterate from x_k and g(x_k) (``step``), keeping the last ``depth`` differences."""

    def __init__(self, comm: MPI.Comm, owned: int, depth: int = 4, damping: float = 1.0):
        self.comm, self.owned, self.depth, self.damping = comm, owned, depth, damping
        self._previous: tuple[np.ndarray, np.ndarray] | None = None  # (f_{k-1}, x_{k-1}) owned
        self._dF: list[np.ndarray] = []
        self._dX: list[np.ndarray] = []

    def step(self, x: np.ndarray, g: np.ndarray) -> np.ndarray:
        """x_{k+1} from x_k and g(x_k) (local arrays whose first ``owned`` entries are owned; the
        returned array has the owned entries set, the ghosts to be updated by the caller)."""
        x_owned = x[:self.owned].copy()
        f = g[:self.owned] - x_owned
        if self._previous is not None and self.depth > 0:
            self._dF.append(f - self._previous[0])
            self._dX.append(x_owned - self._previous[1])
            del self._dF[:-self.depth], self._dX[:-self.depth]
        self._previous = (f, x_owned)
        result = x + self.damping * (g - x)
        if not self._dF:
            return result
        dF = np.column_stack(self._dF)
        gram = self.comm.allreduce(dF.T @ dF)
        rhs = self.comm.allreduce(dF.T @ f)
        # the least-squares problem through its normal equations, truncated where the differences
        # are nearly dependent (singular values of the Gram matrix below 1e-10 of the largest,
        # those of the differences below 1e-5)
        gamma = np.linalg.lstsq(gram, rhs, rcond=1e-10)[0]
        result[:self.owned] -= (np.column_stack(self._dX) + self.damping * dF) @ gamma
        return result

"""Anderson acceleration (anderson.py) of linear fixed-point maps x = A x + b, A = Q diag(lambda)
Q^T with a fixed random orthogonal Q, on 12 unknowns split across the ranks: each rank owns a block
(the ``owned`` argument) and holds one ghost entry after it, as a dolfinx vector does. A contraction
converges in fewer steps than the plain iteration; a map with an eigenvalue below -1, on which the
plain iteration diverges, converges; the iterates are those of one rank.
"""
from __future__ import annotations

import numpy as np
import pytest
from mpi4py import MPI

from forming_fenicsx.core.anderson import AndersonMixing

SIZE = 12
CONTRACTION = np.linspace(0.1, 0.9, SIZE)  # plain iteration: error ~ 0.9^k
EXPANDING = np.append(np.linspace(-0.5, 0.5, SIZE - 1), -1.5)  # plain iteration: ~ 1.5^k


def linear_map(eigenvalues: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A, b and the fixed point (I - A)^-1 b (the same on every rank: a seeded generator)."""
    q, _ = np.linalg.qr(np.random.default_rng(3).standard_normal((SIZE, SIZE)))
    a = q @ np.diag(eigenvalues) @ q.T
    b = np.linspace(1.0, 2.0, SIZE)
    return a, b, np.linalg.solve(np.eye(SIZE) - a, b)


def iterate(eigenvalues: np.ndarray, depth: int, steps: int, comm: MPI.Comm = MPI.COMM_WORLD,
            ghosts: bool = True) -> np.ndarray:
    """The global iterates x_0 = 0, ..., x_steps (rows) of the mixing of depth ``depth``: each
    rank owns a block of entries and (with ``ghosts``) holds a copy of the entry after it."""
    a, b, _ = linear_map(eigenvalues)
    bounds = np.linspace(0, SIZE, comm.size + 1).astype(int)
    owned = np.arange(bounds[comm.rank], bounds[comm.rank + 1])
    local = np.append(owned, owned[-1] + 1 if owned[-1] + 1 < SIZE else 0) if ghosts else owned
    mixing = AndersonMixing(comm, len(owned), depth)
    x_global = np.zeros(SIZE)
    history = [x_global]
    for _ in range(steps):
        x = x_global[local].copy()
        step = mixing.step(x, (a @ x_global + b)[local])
        x_global = np.concatenate(comm.allgather(step[:len(owned)]))  # the ghosts updated
        history.append(x_global)
    return np.array(history)


def errors(eigenvalues: np.ndarray, depth: int, steps: int) -> np.ndarray:
    """||x_k - x*|| / ||x*|| for k = 0 ... steps."""
    exact = linear_map(eigenvalues)[2]
    difference = iterate(eigenvalues, depth, steps) - exact
    return np.linalg.norm(difference, axis=1) / np.linalg.norm(exact)


def steps_to(values: np.ndarray, tolerance: float) -> int:
    """The first step at which the error is below ``tolerance`` (len(values) if none)."""
    below = np.flatnonzero(values < tolerance)
    return int(below[0]) if below.size else len(values)


def test_contraction_converges_faster():
    """Eigenvalues 0.1 ... 0.9: the plain iteration needs more than 150 steps to reach 1e-8
    (error ~ 0.9^k; measured 159), depth 4 fewer than a third of them (measured 37)."""
    plain, anderson = errors(CONTRACTION, 0, 200), errors(CONTRACTION, 4, 200)
    assert steps_to(plain, 1e-8) > 150
    assert steps_to(anderson, 1e-8) < steps_to(plain, 1e-8) / 3


def test_eigenvalue_below_minus_one():
    """An eigenvalue -1.5: the plain iteration diverges (error above 1e3 after 30 steps), depth 4
    converges to 1e-8 within 30 steps (measured 19)."""
    assert errors(EXPANDING, 0, 30)[-1] > 1e3
    assert steps_to(errors(EXPANDING, 4, 40), 1e-8) <= 30


@pytest.mark.parametrize("eigenvalues", [CONTRACTION, EXPANDING])
def test_iterates_independent_of_ranks(eigenvalues):
    """The iterates with the vector split across the ranks, ghosts held, equal those of one rank
    holding the whole vector and no ghost, to 1e-12 (the inner products skip the ghosts)."""
    distributed = iterate(eigenvalues, 4, 20)
    single = iterate(eigenvalues, 4, 20, MPI.COMM_SELF, ghosts=False)
    assert np.abs(distributed - single).max() < 1e-12 * np.abs(single).max()


def test_depth_zero_is_plain_iteration():
    """depth 0 is x_{k+1} = A x_k + b, and damping 0.5 the mean of x_k and A x_k + b."""
    a, b, _ = linear_map(CONTRACTION)
    plain = iterate(CONTRACTION, 0, 3)
    assert np.abs(plain[2] - (a @ plain[1] + b)).max() < 1e-14
    mixing = AndersonMixing(MPI.COMM_SELF, SIZE, depth=0, damping=0.5)
    x = np.ones(SIZE)
    assert np.abs(mixing.step(x, a @ x + b) - 0.5 * (x + a @ x + b)).max() < 1e-14

"""Every difference between the supported dolfinx releases (0.5 on Debian 12, 0.9 on Debian 13).

Nothing outside this module looks at ``dolfinx.__version__``.
"""
from __future__ import annotations

import numpy as np
import dolfinx
import dolfinx.fem
from petsc4py import PETSc

DOLFINX_VERSION = tuple(int(p) for p in dolfinx.__version__.split(".")[:2])
LEGACY = DOLFINX_VERSION < (0, 7)


def function_space(mesh, family: str, degree: int, shape: tuple[int, ...] = ()):
    """A Lagrange ("P") or discontinuous Lagrange ("DP") space, scalar or vector valued."""
    if LEGACY:
        legacy_family = {"P": "CG", "DP": "DG"}[family]
        if shape:
            return dolfinx.fem.VectorFunctionSpace(mesh, (legacy_family, degree), dim=shape[0])
        return dolfinx.fem.FunctionSpace(mesh, (legacy_family, degree))
    name = {"P": "Lagrange", "DP": "DG"}[family]
    return dolfinx.fem.functionspace(mesh, (name, degree, shape) if shape else (name, degree))


def petsc_vec(u: dolfinx.fem.Function) -> PETSc.Vec:
    """The PETSc vector that wraps a Function's degrees of freedom."""
    return u.vector if LEGACY else u.x.petsc_vec


def cell_geometry_nodes(mesh) -> np.ndarray:
    """Geometry node indices of every local cell, shape (cells, nodes per cell)."""
    dofmap = mesh.geometry.dofmap
    if LEGACY:
        ncells = mesh.topology.index_map(mesh.topology.dim).size_local + \
            mesh.topology.index_map(mesh.topology.dim).num_ghosts
        return dofmap.array.reshape(ncells, -1)
    return np.asarray(dofmap)


def geometry_degree(mesh) -> int:
    """Polynomial degree of the coordinate map."""
    return mesh.geometry.cmap.degree

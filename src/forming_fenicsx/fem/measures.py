"""Integration measures of a flow problem: Gauss rules by element and integration, weighted by the
coordinate system (coordinates.py), and the facet normal."""
from __future__ import annotations

import ufl

from forming_fenicsx.physics.coordinates import CoordinateSystem
from forming_fenicsx.core.roles import ROLES

ONE_POINT_DEGREE = 1  # Gauss rules up to this degree have a single point on quadrilaterals


def quadrature_degree(element_degree: int, reduced: bool) -> int:
    """Gauss degree of complete ((k+1)^2 points) or reduced (k^2 points) integration for Q_k."""
    points = element_degree if reduced else element_degree + 1
    return 2 * points - 1


class Measures:
    """dx (complete Gauss rule of Q_k), dx_vol (the volumetric penalty's rule: reduced or complete),
    ds (boundary, tagged by roles) and the facet normal n; every measure carries the coordinate
    system's weight. ``apart_degree``: the volumetric rule when it is a one-point rule beside the
    complete one, whose integrals forms.split_form compiles apart."""

    def __init__(self, mesh, facet_tags, coordinates: CoordinateSystem, element_degree: int,
                 reduced_volumetric: bool):
        self.full_degree = quadrature_degree(element_degree, reduced=False)
        self.volumetric_degree = quadrature_degree(element_degree, reduced_volumetric)
        self.dx = coordinates.measure(
            ufl.dx(domain=mesh, metadata={"quadrature_degree": self.full_degree}))
        self.dx_vol = coordinates.measure(
            ufl.dx(domain=mesh, metadata={"quadrature_degree": self.volumetric_degree}))
        self.apart_degree = (self.volumetric_degree if self.volumetric_degree != self.full_degree
                             and self.volumetric_degree <= ONE_POINT_DEGREE else None)
        self.ds = coordinates.measure(ufl.Measure("ds", domain=mesh, subdomain_data=facet_tags,
                                                  metadata={"quadrature_degree": self.full_degree}))
        self.n = ufl.FacetNormal(mesh)

    def on(self, role: str):
        """ds restricted to a boundary role."""
        return self.ds(ROLES[role])

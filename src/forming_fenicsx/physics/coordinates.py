"""The coordinate system of a scene: plane strain, axisymmetric or three-dimensional, in one object.

x is the flow direction (the axis of an axisymmetric model), y the half-thickness (the radius), and
the symmetry line y = 0 (in 3D also the plane z = 0, z across the width). Every form takes its
strain rate, divergence, equivalent rate, identity and measure weight from here, so that no other
module knows which of them it is.

Plane strain: e(u) = sym(grad u) (2x2; the out-of-plane rate is zero and counts in the deviator),
integrals per unit width of the half model (``whole`` makes them the strip's).
Axisymmetric: e(u) = [[du_x/dx, sym, 0], [sym, du_y/dy, 0], [0, 0, u_y/y]] with the hoop rate
u_y/y, integrals over the whole body: the measure carries the weight 2 pi y.
3D (the paper's k = 3): e(u) = sym(grad u) (3x3), integrals over the model, a half or a quarter of
the product by its symmetry planes (``whole`` makes them the product's).
"""
from __future__ import annotations

import math

import ufl

SYMMETRIES = ("plane_strain", "axisymmetric", "3d")


def tensile_yield_factor(symmetry: str) -> float:
    """Yield stress in tension of a drawn product over the flow stress: 2/sqrt(3) in plane strain
    (2k), 1 for a round or a 3D bar (uniaxial tension)."""
    return 2.0 / math.sqrt(3.0) if symmetry == "plane_strain" else 1.0


class WeightedMeasure:
    """A UFL measure whose integrands are multiplied by a weight: ``f * measure`` is int f w dx.

    ``measure(tag)`` restricts it as ufl.Measure does; with no weight it is the plain measure."""

    def __init__(self, measure: ufl.Measure, weight=None):
        self.measure, self.weight = measure, weight

    def __rmul__(self, integrand):
        if self.weight is None:
            return integrand * self.measure
        return (ufl.as_ufl(integrand) * self.weight) * self.measure

    def __call__(self, *args, **kwargs) -> WeightedMeasure:
        return WeightedMeasure(self.measure(*args, **kwargs), self.weight)


class CoordinateSystem:
    """Kinematics and measure weight of plane strain or an axisymmetric body (section 2 of the
    paper, with the hoop components of a body of revolution)."""

    def __init__(self, mesh, symmetry: str = "plane_strain", planes: int = 1):
        """``planes``: the symmetry planes that cut the model from the product (y = 0 of a strip's
        half model; y = 0 and z = 0 of a 3D quarter), which ``whole`` undoes."""
        if symmetry not in SYMMETRIES:
            raise ValueError(f"symmetry must be one of {', '.join(SYMMETRIES)}; got {symmetry!r}")
        self.symmetry = symmetry
        self.axisymmetric = symmetry == "axisymmetric"
        self.three_dimensional = symmetry == "3d"
        self.planes = planes
        self.radius = ufl.SpatialCoordinate(mesh)[1]
        self.dim = 2 if symmetry == "plane_strain" else 3  # of the strain-rate tensor

    # -- kinematics ------------------------------------------------------------------------------
    def strain_rate(self, u):
        """(2.3): the symmetric velocity gradient (2x2 or 3x3), with the hoop rate u_y/y when
        axisymmetric."""
        e = ufl.sym(ufl.grad(u))
        if not self.axisymmetric:
            return e
        return ufl.as_matrix([[e[0, 0], e[0, 1], 0], [e[1, 0], e[1, 1], 0],
                              [0, 0, u[1] / self.radius]])

    def divergence(self, u):
        """div u = tr e(u) (volume change rate; with u_y/y when axisymmetric)."""
        return ufl.tr(self.strain_rate(u))

    @property
    def identity(self):
        return ufl.Identity(self.dim)

    def deviatoric(self, e):
        """e' = e - tr(e)/3 I of the strain-rate tensor as held (in plane strain the zz part of the
        3-D deviator, -tr(e)/3, is left out of the 2x2 tensor but counts in deviatoric_product)."""
        return e - ufl.tr(e) / 3.0 * self.identity

    @staticmethod
    def deviatoric_product(e1, e2):
        """e1':e2' of the 3-D deviators: inner(e1, e2) - tr(e1) tr(e2)/3 (exact in both systems)."""
        return ufl.inner(e1, e2) - ufl.tr(e1) * ufl.tr(e2) / 3.0

    def equivalent_strain_rate(self, u):
        """sqrt(2/3 e':e') of section 2."""
        e = self.strain_rate(u)
        return ufl.sqrt(2.0 / 3.0 * self.deviatoric_product(e, e))

    def in_plane(self, tensor):
        """The block of a stress or rate tensor that acts on a boundary of the model: the (x, y)
        block when axisymmetric, else all of it."""
        if not self.axisymmetric:
            return tensor
        return ufl.as_matrix([[tensor[i, j] for j in range(2)] for i in range(2)])

    # -- measures --------------------------------------------------------------------------------
    @property
    def weight(self):
        """Weight of the measure: 1 (per unit width), or 2 pi y (the whole body of revolution)."""
        return 2.0 * math.pi * self.radius if self.axisymmetric else None

    def measure(self, measure: ufl.Measure) -> WeightedMeasure:
        return WeightedMeasure(measure, self.weight)

    @property
    def whole(self) -> float:
        """The product's integrals over the model's: 2 per symmetry plane (the plane-strain half
        model, per unit width: 2; a 3D quarter: 4), 1 when axisymmetric (the weight 2 pi y already
        makes them the whole body's)."""
        return 1.0 if self.axisymmetric else 2.0**self.planes

    def section(self, half_thickness: float) -> float:
        """Area the process force acts on at a section of the given half-thickness (radius) of a
        2D model: the half thickness per unit width, or pi R^2 (a 3D model integrates its
        section)."""
        if self.three_dimensional:
            raise ValueError("a 3D section's area is integrated over it, not computed from a size")
        return math.pi * half_thickness**2 if self.axisymmetric else half_thickness

    @property
    def tensile_yield_factor(self) -> float:
        return tensile_yield_factor(self.symmetry)

    @property
    def separation_weight(self):
        """Weight on the y-traction on the die whose integral is the die separation force: the
        force on one die half (per unit width in plane strain; the model's share of it in 3D:
        ``whole``/2 of them make a die half, the y > 0 one), or (axisymmetric) the force that splits
        a die into two halves across a diametral plane, int_0^pi sin(theta) dtheta y t_y = 2 y t_y
        per unit arc length."""
        if self.axisymmetric:
            return 2.0 * self.radius
        return 0.5 * self.whole if self.three_dimensional else 1.0

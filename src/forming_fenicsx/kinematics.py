"""Strain-rate measures of section 2 in plane strain (the out-of-plane deviatoric part counts)."""
from __future__ import annotations

import ufl


def strain_rate(u):
    """(2.3): the symmetric velocity gradient."""
    return ufl.sym(ufl.grad(u))


def deviatoric(e):
    """In-plane part of the plane-strain deviator e - tr(e)/3 I."""
    return e - ufl.tr(e) / 3.0 * ufl.Identity(2)


def deviatoric_product(e1, e2):
    """e1':e2' with the plane-strain deviator of the 3-D tensor (zz component zero before deviation)."""
    return ufl.inner(e1, e2) - ufl.tr(e1) * ufl.tr(e2) / 3.0


def equivalent_strain_rate(u):
    """The equivalent strain rate sqrt(2/3 e':e') of section 2."""
    e = strain_rate(u)
    return ufl.sqrt(2.0 / 3.0 * deviatoric_product(e, e))

"""Finite-strain axisymmetric model of a thick hemispherical dome pressed by a flat plate:
the mesh (:mod:`.mesh`), the equilibrium of one load (:mod:`.equilibrium`) and the
force-travel path (:mod:`.path`); and of a layer on a rigid base pressed by a sphere
(:mod:`.layer_mesh`, solved by :mod:`magdesign.mechanics.finite_layer`); the module
docstrings say how each works."""

from magdesign.mechanics._axisymmetric.equilibrium import (
    LEVENBERG_MAX,
    _element_derivatives,
    _excess,
    _factor,
    _first_order,
    contact_radius,
    derivatives,
    implicit,
    plate_force,
    potential,
    state_tangent,
)
from magdesign.mechanics._axisymmetric.mesh import Mesh
from magdesign.mechanics._axisymmetric.path import first_crossings, follow_travels

__all__ = [
    "LEVENBERG_MAX",
    "Mesh",
    "_element_derivatives",
    "_excess",
    "_factor",
    "_first_order",
    "contact_radius",
    "derivatives",
    "first_crossings",
    "follow_travels",
    "implicit",
    "plate_force",
    "potential",
    "state_tangent",
]

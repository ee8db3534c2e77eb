"""Unilateral contact with rigid obstacles, penalty or Nitsche, with lagged Coulomb friction."""
from ..choices import CONTACT_METHODS as METHODS
from .item import FACET_DEGREE, Contact, ZoneInfo
from .obstacles import Circle, ContactError, Cylinder, Obstacle, Plane, Profile, Sphere
from .surface import Surface
from .swept import Extruded, Revolved

__all__ = ["FACET_DEGREE", "METHODS", "Circle", "Contact", "ContactError", "Cylinder", "Extruded", "Obstacle",
           "Plane", "Profile", "Revolved", "Sphere", "Surface", "ZoneInfo"]

"""What a problem file may hold: its sections, the items, obstacles and probes with their keys'
types, the ranges of the values, and the checks of one table against its schema (problem.py reads
the file with them). Light: the standard library and the project's checks only."""
from __future__ import annotations

import math

from .checks import choice, number, text
from .choices import CONTACT_METHODS, FRICTION_LAWS, MODELS, PREDICTORS, UPDATES


class ProblemError(ValueError):
    """A problem file that cannot be used; the message names the key and the fix."""


BUILDERS = {"rectangle": ("L", "H", "size"), "annulus_sector": ("r_in", "r_out", "size"),
            "plate_section": ("R", "t", "z_support", "size"), "quarter_disc": ("R", "size", "size_contact",
                                                                            "contact_zone"),
            "box": ("Lx", "Ly", "Lz", "size"), "tube_sector": ("r_in", "r_out", "length", "size"),
            "sphere_octant": ("R", "size")}
#: the builders' optional sizes (the 3D builders' refinement near the contact, the tube's angle)
BUILDER_OPTIONS = {"tube_sector": ("angle", "size_contact", "contact_zone", "growth"),
                   "sphere_octant": ("size_contact", "contact_zone", "growth")}
#: the builders of 3D meshes (for the body kind "solid")
BUILDERS_3D = ("box", "tube_sector", "sphere_octant")
ITEMS = {"fixed": {"boundary": str, "component": int},
         "displacement": {"boundary": str, "value": "vector|number", "component": int},
         "pressure": {"boundary": str, "p": float},
         "traction": {"boundary": str, "vector": "vector"},
         "body_force": {"vector": "vector"},
         "point_load": {"point": "vector", "vector": "vector"},
         "contact": {"boundary": str, "obstacle": dict, "method": str, "gamma0": float, "theta": int,
                     "mu": float, "relag": bool, "friction": str, "gamma0_t": float, "max_passes": int,
                     "relag_tol": float}}
REQUIRED = ("boundary", "p", "vector", "point", "obstacle", "value")
_SWEPT = {"points": "points", "file": str, "curve": str, "radius": float, "spacing": float}
OBSTACLES = {"plane": {"point": "vector", "normal": "vector", "motion": "vector"},
             "circle": {"centre": "vector", "radius": float, "motion": "vector"},
             "profile": {"points": "points", "radius": float, "motion": "vector"},
             "gmsh_profile": {"file": str, "curve": str, "radius": float, "spacing": float, "motion": "vector"},
             "sphere": {"centre": "vector", "radius": float, "motion": "vector"},
             "cylinder": {"point": "vector", "axis": "vector", "radius": float, "motion": "vector"},
             "extruded": {**_SWEPT, "u": "vector", "v": "vector", "origin": "vector", "motion": "vector"},
             "revolved": {**_SWEPT, "axis": "vector", "origin": "vector", "motion": "vector"},
             "surface": {"file": str, "surface": str, "size": float, "flip": bool, "motion": "vector"}}
#: the keys an obstacle must have (extruded and revolved: points, or file and curve, besides)
OBSTACLE_REQUIRED = {"plane": ("point", "normal"), "circle": ("centre", "radius"), "profile": ("points", "radius"),
                     "gmsh_profile": ("file", "curve", "radius"), "sphere": ("centre", "radius"),
                     "cylinder": ("point", "axis", "radius"), "extruded": ("radius",), "revolved": ("radius",),
                     "surface": ("file", "surface")}
#: the obstacles of 2D bodies and of 3D ones (plane: both)
OBSTACLES_2D, OBSTACLES_3D = ("circle", "profile", "gmsh_profile"), ("sphere", "cylinder", "extruded", "revolved",
                                                                               "surface")
PROBES = {"node": {"name": str, "point": "vector", "component": int, "column": str},
          "contact_force": {"item": str, "column": str, "component": int, "scale": float},
          "contact_length": {"item": str, "column": str, "scale": float},
          "contact_area": {"item": str, "column": str, "scale": float},
          "contact_radius": {"item": str, "column": str, "origin": "vector", "direction": "vector",
                             "axis": "vector", "scale": float},
          "contact_peak": {"item": str, "column": str, "scale": float},
          "reaction": {"boundary": str, "name": str},
          "max_plastic_strain": {}}
SECTIONS = {"mesh", "body", "items", "steps", "newton", "probes"}
LAWS = ("elastic", "j2", "chen")


def _positive(key, value):
    return number(key, value, gt=0)


#: the values a key may take, wherever it stands (its type is checked first): the message or None
RANGES = {
    "kind": lambda k, v: choice(k, v, MODELS), "update": lambda k, v: choice(k, v, UPDATES),
    "degree": lambda k, v: choice(k, v, (1, 2)), "order": lambda k, v: choice(k, v, (1, 2)),
    "law": lambda k, v: choice(k, v, LAWS), "component": lambda k, v: choice(k, v, (0, 1, 2), " (0: x, 1: y, 2: z in 3D)"),
    "thickness": _positive, "gamma0": _positive, "gamma0_t": _positive, "radius": _positive,
    "spacing": _positive, "relag_tol": _positive,
    "mu": lambda k, v: number(k, v, ge=0, what=" (the friction coefficient)"),
    "theta": lambda k, v: choice(k, v, (1, 0, -1), " (Nitsche's variant)"),
    "method": lambda k, v: choice(k, v, CONTACT_METHODS), "friction": lambda k, v: choice(k, v, FRICTION_LAWS),
    "max_passes": lambda k, v: number(k, v, ge=1, whole=True),
    "n": lambda k, v: number(k, v, ge=1, le=1_000_000, whole=True, what=" of increments"),
    "predictor": lambda k, v: choice(k, v, tuple(PREDICTORS)),
    "max_cutbacks": lambda k, v: number(k, v, ge=0, le=30, whole=True),
    **{k: (lambda k, v: text(k, v)) for k in ("name", "boundary", "column", "item", "curve", "file", "surface")},
}
WANT = {float: "a finite number", int: "a whole number", str: "a string", bool: "true or false", dict: "a table",
        list: "a list of item names", "vector": "finite numbers [x, y] ([x, y, z] in 3D)", "points": "a list of [x, y] points",
        "vector|number": "a finite number or [x, y] ([x, y, z] in 3D)", "names": "a list of names",
        "table": "rows [strain, stress]: [[0, sigma_y], ...]"}


def _real(v) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)


def _typed(kind, value) -> bool:
    """Whether ``value`` is of the kind ``kind`` of a spec (a type or a word of WANT)."""
    if kind is float:
        return _real(value)
    if kind is int:
        return isinstance(value, int) and not isinstance(value, bool)
    if kind in (str, bool, dict):
        return isinstance(value, kind)
    if kind in (list, "names"):
        return isinstance(value, list) and all(isinstance(v, str) for v in value)
    if kind in ("vector", "vector|number"):
        return (isinstance(value, list) and len(value) in (2, 3) and all(_real(v) for v in value)) or (
            kind == "vector|number" and _real(value))
    return isinstance(value, list) and len(value) >= (2 if kind == "points" else 1) and all(   # points, table
        isinstance(p, list) and len(p) == 2 and all(_real(v) for v in p) for p in value)


def _check(where: str, table: dict, spec: dict, required=()) -> dict:
    """Keys of ``table`` against ``spec`` (key -> type), then against RANGES; returns the table."""
    if not isinstance(table, dict):
        raise ProblemError(f"{where}: expected a table of keys, got {table!r}")
    for key, value in table.items():
        if key not in spec:
            raise ProblemError(f"{where}: unknown key {key!r}; the keys are {', '.join(spec) or 'none'}")
        if not _typed(spec[key], value):
            raise ProblemError(f"{where}: {key} = {value!r}: give {WANT[spec[key]]}")
        why = RANGES[key](key, value) if key in RANGES else None
        if why is not None:
            raise ProblemError(f"{where}: {why}")
    for key in required:
        if key not in table:
            raise ProblemError(f"{where}: {key} is missing: add it")
    return table

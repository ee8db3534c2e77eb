"""Checks of the user's input that need nothing heavy (the standard library only).

The API's constructors and the problem files (problem.py) share them, so a value is refused with the
same words from Python and from a TOML file, and a problem file is refused before dolfinx is imported:

* :func:`number`, :func:`choice`, :func:`flag`, :func:`text`: the message for one value that is not
  what it must be (a finite number in a range, a whole number, one of some names, True or False, a
  string), or None; the caller raises its own error type with it (``ContactError``, ``BodyError``,
  ...), so each message is one line that names the value and what to give instead;
* :func:`newton_error`: the fields of ``NewtonSettings`` (:class:`SettingsError`);
* :func:`mesh_size_error`: the number of cells a built-in mesh would have, estimated from its
  geometry and size before Gmsh runs, against :data:`MAX_CELLS`;
* :func:`check_job`: the parts of a ``Job`` (lists of items, steps, probes, writers).
"""
from __future__ import annotations

import math
import numbers

from .choices import CONVERGENCE_SCALES, LINE_SEARCHES, LINEAR_SOLVERS

MAX_CELLS = 5_000_000   #: the most cells a built-in mesh may have (beyond it Gmsh runs out of memory)


class SettingsError(ValueError):
    """Newton settings that cannot be used (a tolerance, a name, a PETSc option); the message names
    the value and the fix."""


class SolverOptionError(SettingsError):
    """PETSc options that PETSc refuses (an unknown type, a value of the wrong kind), or that are not
    options at all."""


# -- one value ------------------------------------------------------------------------------------
def is_number(value) -> bool:
    """A real number (Python's or NumPy's, a 0-d array too), not a bool and not a string."""
    if getattr(value, "shape", None) == () and getattr(getattr(value, "dtype", None), "kind", "?") in "iuf":
        return True                                       # a NumPy 0-d array of numbers
    return isinstance(value, numbers.Real) and not isinstance(value, bool) and type(value).__name__ != "bool_"


def is_whole(value) -> bool:
    """A whole number (Python's or NumPy's int), not a bool."""
    return isinstance(value, numbers.Integral) and is_number(value)


def _bounds(gt, ge, lt, le) -> str:
    parts = [f"> {gt:g}" if gt is not None else "", f">= {ge:g}" if ge is not None else "",
             f"< {lt:g}" if lt is not None else "", f"<= {le:g}" if le is not None else ""]
    return " and ".join(p for p in parts if p)


def number(name: str, value, *, gt=None, ge=None, lt=None, le=None, whole: bool = False,
           what: str = "") -> str | None:
    """Why ``value`` is not a finite number (``whole``: a whole number) within the bounds, or None.
    ``what`` (e.g. " (the friction coefficient)") ends the message."""
    ok = is_whole(value) if whole else (is_number(value) and math.isfinite(value))
    if ok:
        ok = ((gt is None or value > gt) and (ge is None or value >= ge) and (lt is None or value < lt)
              and (le is None or value <= le))
    if ok:
        return None
    bounds = _bounds(gt, ge, lt, le)
    kind = "a whole number" if whole else "a finite number"
    return f"{name} = {value!r}: give {kind}{' ' + bounds if bounds else ''}{what}"


def choice(name: str, value, choices, what: str = "") -> str | None:
    """Why ``value`` is not one of ``choices`` (compared by kind and value: True is not 1, nor "1"),
    or None."""
    def same(a, b):
        return a == b if is_whole(a) and is_whole(b) else (type(a) is type(b) and a == b)
    if any(same(value, c) for c in choices):
        return None
    return f"{name} = {value!r}: choose one of {', '.join(repr(c) for c in choices)}{what}"


def flag(name: str, value) -> str | None:
    """Why ``value`` is not True or False (NumPy's bool too), or None."""
    if isinstance(value, bool) or type(value).__name__ == "bool_":
        return None
    return f"{name} = {value!r}: give True or False"


def text(name: str, value, what: str = "a name (a non-empty string)") -> str | None:
    """Why ``value`` is not a non-empty string, or None; ``what`` is what to give."""
    if isinstance(value, str) and value.strip():
        return None
    return f"{name} = {value!r}: give {what}"


def first(*messages) -> str | None:
    """The first message that is not None (the checks in the order the arguments come)."""
    return next((m for m in messages if m is not None), None)


def meridian_error(origin, direction, axis) -> str | None:
    """Why ``origin``, ``direction``, ``axis`` do not give a meridian's half-plane (the axis through
    ``origin`` along ``axis``, on the side of ``direction``), or None."""
    def vector(value):
        flat = list(value) if isinstance(value, (list, tuple)) or getattr(value, "ndim", 0) == 1 else []
        ok = len(flat) == 3 and all(is_number(v) and math.isfinite(v) for v in flat)
        return [float(v) for v in flat] if ok else None
    o, d, a = vector(origin), vector(direction), vector(axis)
    for name, value, given, what in (("origin", origin, o, "a point on the axis"),
                                     ("axis", axis, a, "the axis's direction"),
                                     ("direction", direction, d, "towards the meridian's side of the axis")):
        if given is None or (name != "origin" and not any(given)):
            zero = "" if name == "origin" else ", not all zero"
            return f"{name} = {value!r}: give 3 finite numbers{zero} ({what})"
    cross = [d[1] * a[2] - d[2] * a[1], d[2] * a[0] - d[0] * a[2], d[0] * a[1] - d[1] * a[0]]
    if math.hypot(*cross) <= 1e-9 * math.hypot(*d) * math.hypot(*a):
        return (f"direction = {direction!r} is parallel to axis = {axis!r}: give a direction across the "
                "axis (towards the meridian's side of it)")
    return None


# -- Newton's settings ----------------------------------------------------------------------------
def _tolerance(name: str, value) -> str | None:
    return number(name, value, ge=0, what=" (0 turns this test off)")


NEWTON_CHECKS = {
    "rtol": _tolerance, "atol": _tolerance, "stol": _tolerance,
    "max_it": lambda n, v: number(n, v, ge=1, whole=True, what=" of Newton iterations per attempt"),
    "divergence": lambda n, v: number(n, v, gt=0, what=" (a factor on the first residual)"),
    "backtracks": lambda n, v: number(n, v, ge=0, whole=True),
    "free_its": lambda n, v: number(n, v, ge=0, whole=True),
    "line_search": lambda n, v: None if choice(n, v, LINE_SEARCHES) is None else (
        f"{n} = {v!r}: choose 'residual', 'energy' or 'none' (True, False; None: chosen from the items)"),
    "energy_eta": lambda n, v: number(n, v, gt=0, le=1),
    "scale": lambda n, v: choice(n, v, CONVERGENCE_SCALES),
    "petsc_options": lambda n, v: petsc_options_error(v),
    "linear_solver": lambda n, v: choice(n, v, LINEAR_SOLVERS),
    "monitor": lambda n, v: None,
}


def newton_error(fields: dict) -> str | None:
    """Why the ``NewtonSettings`` fields ``fields`` (name -> value, any subset) cannot be used, or
    None: tolerances finite and >= 0 with rtol or atol > 0, max_it a whole number >= 1, the names
    known, the PETSc options a table of names and values."""
    bad = newton_field_error(fields)
    return None if bad is None else bad[1]


def newton_field_error(fields: dict, unknown: bool = True) -> tuple[str, str] | None:
    """(the field, why) for the first of ``fields`` that cannot be used (:func:`newton_error`);
    ``unknown``: a name that is not a field is refused (a problem file's key), else passed over."""
    for name, value in fields.items():
        if name not in NEWTON_CHECKS:
            if not unknown:
                continue
            return name, f"unknown setting {name!r}; the settings are {', '.join(NEWTON_CHECKS)}"
        why = NEWTON_CHECKS[name](name, value)
        if why:
            return name, why
    if fields.get("rtol", 1.0) == 0 and fields.get("atol", 1.0) == 0:
        return "rtol", "rtol = 0 and atol = 0: the residual test can never pass; give rtol > 0 or atol > 0"
    return None


def petsc_options_error(options) -> str | None:
    """Why ``options`` is not a dict of option names (without the prefix) to values (a string, a
    finite number, True/False, or None for an option without value), or None."""
    if not isinstance(options, dict):
        return f"petsc_options = {options!r}: give a dict of option names to values, e.g. {{'pc_type': 'lu'}}"
    for key, value in options.items():
        if not isinstance(key, str) or not key.strip("-").strip():
            return f"petsc_options: {key!r} is not an option name: give names such as 'pc_type'"
        if not (value is None or isinstance(value, (str, bool)) or (is_number(value) and math.isfinite(value))):
            return (f"petsc_options: {key} = {value!r}: give a string, a finite number, True/False or None "
                    "(an option without value)")
    return None


# -- the size of a built-in mesh ------------------------------------------------------------------
def _structured(nx: float, ny: float) -> float:
    return 2.0 * nx * ny              # each cell of the grid cut into two triangles


def _cells_quarter_disc(p: dict) -> float:
    """Unstructured: the area at each distance r from the origin over that of an equilateral triangle
    of the size there (size_contact within contact_zone, then growing by ``growth`` per unit length
    up to size); near the origin the body fills a quarter of the plane (half with ``half``)."""
    R, size, fine, zone = p["R"], p["size"], p["size_contact"], p["contact_zone"]
    growth, part = p.get("growth", 0.25), (1.0 if p.get("half") else 0.5)
    tri = math.sqrt(3.0) / 4.0
    area = part * math.pi * R * R / 2.0                  # the quarter (or the half) disc
    a_fine = min(part * math.pi * zone * zone / 2.0, area)
    cells, done = a_fine / (tri * fine * fine), a_fine
    r2, n = zone + (size - fine) / growth, 64             # the graded band, by the midpoint rule
    for k in range(n):
        r = zone + (k + 0.5) * (r2 - zone) / n
        da = min(part * math.pi * r * (r2 - zone) / n, area - done)
        cells += da / (tri * (fine + growth * (r - zone)) ** 2)
        done += da
    return cells + (area - done) / (tri * size * size)


def _cells_graded_3d(volume: float, p: dict) -> float:
    """Unstructured tetrahedra in ``volume``: the volume at each distance r from the refined point
    over that of a tetrahedron of the size there (as for the quarter disc; an eighth of the ball near
    the point). Gmsh's tetrahedra of target edge s have on average 1.7 times the volume of the regular
    one, s^3 / (6 sqrt 2) (measured on the builders' meshes: the estimate within 15 %)."""
    size, fine = p["size"], p.get("size_contact", p["size"])
    zone, growth = p.get("contact_zone", 0.0), p.get("growth", 0.25)
    tet = 1.7 * size ** 3 / (6.0 * math.sqrt(2.0))
    if "size_contact" not in p:
        return volume / tet
    v_fine = min(math.pi * zone ** 3 / 6.0, volume)
    cells, done = v_fine / (tet * (fine / size) ** 3), v_fine
    r2, n = zone + (size - fine) / growth, 64
    for k in range(n):
        r = zone + (k + 0.5) * (r2 - zone) / n
        dv = min(math.pi * r * r / 2.0 * (r2 - zone) / n, volume - done)
        cells += dv / (tet * ((fine + growth * (r - zone)) / size) ** 3)
        done += dv
    return cells + (volume - done) / tet


def _bricks_of_tube(p: dict) -> float:
    """The transfinite bricks of ``tube_sector(..., hexahedra=True)``: around, through, along."""
    return (math.ceil(p.get("angle", math.pi / 2) * 0.5 * (p["r_in"] + p["r_out"]) / p["size"])
            * math.ceil((p["r_out"] - p["r_in"]) / p["size"]) * math.ceil(p["length"] / p["size"]))


def _cells_graded_band(dv0: float, dv1: float, fine: float, size: float, growth: float, tet: float) -> float:
    """The tetrahedra added to a uniform mesh of size ``size`` by the band about a refined set where
    the size grows from ``fine`` by ``growth`` per unit distance rho: the volume at distance rho is
    (dv0 + dv1 rho) d rho; integrated over the size h (geometric steps: the finest scales count)."""
    n, cells = 400, 0.0
    hs = [fine * (size / fine) ** (k / n) for k in range(n + 1)]
    for a, b in zip(hs[:-1], hs[1:]):
        h = 0.5 * (a + b)
        dv = (dv0 + dv1 * (h - fine) / growth) * (b - a) / growth
        cells += dv / (tet * (h / size) ** 3) - dv / tet
    return cells


def _cells_plate_quarter(p: dict) -> float:
    """Unstructured tetrahedra in the quarter plate: its volume over that of a tetrahedron of size
    ``size``, plus the graded bands about the refined disc (z = 0, r <= contact_radius) and rim
    support (r = R, z <= z_support). In this thin plate Gmsh's tetrahedra have on average 1.3 times
    the volume of the regular one (measured on the builder's meshes of size t / 4, uniform and
    refined: the estimate within 5 %; it falls short on coarser meshes, 1025 against 1507 at size
    t / 2, where the count is far from any limit)."""
    R, t, size, growth = p["R"], p["t"], p["size"], p.get("growth", 0.25)
    tet = 1.3 * size ** 3 / (6.0 * math.sqrt(2.0))
    cells = math.pi * R * R * t / 4.0 / tet
    if "size_contact" in p:             # the quarter disc, and a quarter tube about its rim
        rc = p["contact_radius"]
        cells += _cells_graded_band(math.pi * rc * rc / 4.0, math.pi * math.pi * rc / 4.0, p["size_contact"],
                                    size, growth, tet)
    if "size_rim" in p:                 # the strip, and a quarter tube about its upper edge
        arc = math.pi * R / 2.0
        cells += _cells_graded_band(arc * p["z_support"], arc * math.pi / 2.0, p["size_rim"], size, growth, tet)
    return cells


#: builder -> its cell count from its parameters (the builders' own formulas, geometry/builders.py)
CELLS = {
    "rectangle": lambda p: _structured(math.ceil(p["L"] / p["size"]), max(math.ceil(p["H"] / p["size"]), 2)),
    "plate_section": lambda p: _structured(
        math.ceil(p["R"] / p["size"]), max(math.ceil(p["z_support"] / p["size"]), 1)
        + max(math.ceil((p["t"] - p["z_support"]) / p["size"]), 1)),
    "annulus_sector": lambda p: _structured(
        max(math.ceil((p["r_out"] - p["r_in"]) / p["size"]), 2),
        max(math.ceil(p.get("angle", math.pi / 2) * 0.5 * (p["r_in"] + p["r_out"]) / p["size"]), 1)),
    "quarter_disc": _cells_quarter_disc,
    "necking_bar": lambda p: _structured(p.get("n_r", 5), p.get("n_z", 40)),
    # box: the rectangle's triangles extruded in layers, each prism cut into 3 tetrahedra (or bricks)
    "box": lambda p: (0.5 if p.get("hexahedra") else 3) * _structured(
        math.ceil(p["Lx"] / p["size"]), max(math.ceil(p["Ly"] / p["size"]), 2)) * max(math.ceil(p["Lz"] / p["size"]), 1),
    "tube_sector": lambda p: _bricks_of_tube(p) if p.get("hexahedra") else _cells_graded_3d(
        0.5 * p.get("angle", math.pi / 2) * (p["r_out"] ** 2 - p["r_in"] ** 2) * p["length"], p),
    "sphere_octant": lambda p: _cells_graded_3d(math.pi * p["R"] ** 3 / 6.0, p),
    "plate_quarter": _cells_plate_quarter,
}


def mesh_cells(builder: str, params: dict) -> float:
    """The number of cells (triangles; tetrahedra for the 3D builders) the builder ``builder`` makes
    from ``params`` (an estimate for the unstructured quarter_disc, tube_sector and sphere_octant);
    inf when the sizes are so small that the count overflows."""
    try:
        return float(CELLS[builder](params))
    except OverflowError:
        return math.inf


def mesh_size_error(builder: str, params: dict, limit: int = MAX_CELLS) -> str | None:
    """Why the built-in mesh ``builder`` of ``params`` (positive sizes) is too fine to build, or None:
    more than ``limit`` cells. The message names the size and the smallest size allowed."""
    cells = mesh_cells(builder, params)
    if cells <= limit:
        return None
    sizes = [k for k in ("size", "size_contact", "size_rim") if k in params]
    if not sizes:                                   # necking_bar: cells by count
        return (f"n_r = {params.get('n_r')}, n_z = {params.get('n_z')} give {cells:.3g} cells, more than "
                f"{limit}: give fewer")
    least = _least_size(builder, params, sizes, limit)
    shown = ", ".join(f"{k} = {params[k]!r}" for k in sizes)
    raise_ = ", ".join(f"{k} >= {_round_up(least):g}" for k in sizes if params[k] < least)
    count = f"about {cells:.3g}" if math.isfinite(cells) else "countless"
    return (f"{shown} would make {count} cells, more than the {limit} a mesh may have here "
            f"(the memory runs out): give {raise_}")


def _round_up(x: float) -> float:
    """``x`` rounded up to three significant digits (a bound that the rounding keeps)."""
    unit = 10.0 ** (math.floor(math.log10(x)) - 2)
    return math.ceil(x / unit * (1 - 1e-12)) * unit


def _least_size(builder: str, params: dict, sizes: list, limit: int) -> float:
    """The smallest s (to 1 %) such that the mesh has at most ``limit`` cells when every size of
    ``sizes`` below s is raised to s (bisection on a log scale: the count falls as the sizes grow)."""
    def cells(s):
        return mesh_cells(builder, {**params, **{k: max(params[k], s) for k in sizes}})
    lo = min(params[k] for k in sizes)
    hi = 2.0 * lo
    while cells(hi) > limit:
        lo, hi = hi, 2.0 * hi
    while hi > 1.01 * lo:
        mid = math.sqrt(lo) * math.sqrt(hi)            # (lo * hi may overflow)
        lo, hi = (mid, hi) if cells(mid) > limit else (lo, mid)
    return hi


# -- a job's parts --------------------------------------------------------------------------------
def _listed(name: str, value, single, fits, example: str) -> str | None:
    """Why ``value`` is not a list (or tuple) whose entries ``fits``, or None; a single entry
    (``single``) is named with the fix: pass it in a list."""
    if single(value):
        shown = repr(value) if len(repr(value)) <= 40 else f"<{type(value).__name__}>"
        return f"{name} = {shown}: give a list, [{shown}], also for one"
    if not isinstance(value, (list, tuple)):
        return f"{name} = {value!r}: give a list of {example}"
    bad = next((k for k, v in enumerate(value) if not fits(v)), None)
    return None if bad is None else f"{name}[{bad}] = {value[bad]!r}: not one of {example}"


def _parts_error(body, items, steps, probes, writers, newton, load) -> str | None:
    """Why a Job's parts cannot be used (:func:`check_job`), or None."""
    from .job import Step
    from .loads import Item
    from .mechanics.body import Body
    from .solver import NewtonSettings

    def is_item(v):
        return isinstance(v, Item)

    def is_probe(v):         # a Probe, or an object that does what one does
        return hasattr(v, "columns") and callable(v) and callable(getattr(v, "attach", None))

    def is_writer(v):        # a Writer, or an object with its three methods
        return all(callable(getattr(v, m, None)) for m in ("open", "write", "close"))

    if not isinstance(body, Body):
        return f"body = {body!r}: give a Body(mesh, kind, material)"
    why = first(_listed("items", items, is_item, is_item, "the items (Fixed, Displacement, Pressure, "
                        "Traction, BodyForce, PointLoad, Contact)"),
                None if steps is None else _listed("steps", steps, lambda v: isinstance(v, Step),
                                                   lambda v: isinstance(v, Step), "Step(n, ...)"),
                _listed("probes", probes, is_probe, is_probe, "the probes (NodeDisplacement, "
                        "ContactForce, Reaction, ...; a probe of your own subclasses Probe)"),
                _listed("writers", writers, is_writer, is_writer, "the writers (HistoryCSV, VTK, XDMF, "
                        "...; a writer of your own subclasses Writer)"))
    if why:
        return why
    if steps is not None and not steps:
        return (f"steps = {steps!r}: give at least one Step (or leave steps out for one Step of "
                f"{Step.n} increments)")
    twice = next((i for k, i in enumerate(items) if any(i is j for j in items[:k])), None)
    if twice is not None:
        return f"items: {twice!r} is listed twice: list each item once"
    if newton is not None and not isinstance(newton, NewtonSettings):
        return f"newton = {newton!r}: give NewtonSettings(...) or leave it out"
    if load is not None and not callable(load):
        return f"load = {load!r}: give a function of the history's time (or leave it out)"
    return None


def check_job(body, items, steps, probes, writers, newton, load) -> None:
    """Refuse the parts of a :class:`~comove_dolfinx.job.Job` that cannot be used: ``JobError``
    naming the part and the fix (``items``, ``probes`` and ``writers`` are lists: a single item is
    refused with the fix "pass [item]"; ``steps`` is a non-empty list, or None for the default; F-bar
    takes no Nitsche contact), and ``ProbeError`` for a probe of a contact not among the items."""
    from .job import JobError
    from .probes import check_contacts
    nitsche = getattr(body, "fbar", False) and any(getattr(i, "method", None) == "nitsche" for i in items)
    why = _parts_error(body, items, steps, probes, writers, newton, load) or (nitsche and (
        "fbar = True with Nitsche contact: Nitsche's facet stress is not averaged; give the contact "
        "method='penalty' (or leave fbar out)")) or None
    if why is not None:
        raise JobError(why)
    check_contacts(probes, items)

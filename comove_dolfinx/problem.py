"""Problem files: a job described in TOML, for ``comove run problem.toml`` (docs/api.md).

::

    [mesh]                       # a built-in builder with its parameters, or file = "part.msh"
    builder = "annulus_sector"
    r_in = 4.849
    r_out = 5.715
    size = 0.22

    [body]
    kind = "plane_strain"        # plane_stress, plane_strain, axisymmetric
    update = "sr"
    degree = 2
    material = { law = "j2", E = 1.89e6, nu = 0.3, hardening = [[0, 2800], [0.5, 5300]] }

    [[items]]                    # fixed, displacement, pressure, traction, body_force, point_load, contact
    type = "fixed"
    boundary = "xsym"
    component = 0

    [[items]]
    type = "contact"
    name = "plate"
    boundary = "outer"
    obstacle = { type = "plane", point = [0, 5.715], normal = [0, -1], motion = [0, -3.3] }
    mu = 0.1

    [[steps]]                    # n increments; ramp: item name -> target factor (others hold);
                                 # release: support items taken away (their force ramped to 0)
    n = 36
    predictor = "tangent"

    [newton]                     # any NewtonSettings field
    scale = "force"

    [[probes]]                   # node, contact_force, contact_length, contact_peak, reaction, max_plastic_strain
    type = "contact_force"
    item = "plate"
    column = "force"
    scale = -2.0

Everything is checked here, before dolfinx is imported: a bad file gets one line that names the key
(``[[items]] 2 (contact): mu = -1 ...``) and the fix. Paths are relative to the problem file.
"""
from __future__ import annotations

import math
import pathlib
import tomllib

from .choices import first_increment_error


class ProblemError(ValueError):
    """A problem file that cannot be used; the message names the key and the fix."""


BUILDERS = {"rectangle": ("L", "H", "size"), "annulus_sector": ("r_in", "r_out", "size"),
            "plate_section": ("R", "t", "z_support", "size"), "quarter_disc": ("R", "size", "size_contact",
                                                                            "contact_zone")}
ITEMS = {"fixed": {"boundary": str, "component": int},
         "displacement": {"boundary": str, "value": "vector|number", "component": int},
         "pressure": {"boundary": str, "p": float},
         "traction": {"boundary": str, "vector": "vector"},
         "body_force": {"vector": "vector"},
         "point_load": {"point": "vector", "vector": "vector"},
         "contact": {"boundary": str, "obstacle": dict, "method": str, "gamma0": float, "theta": int,
                     "mu": float, "relag": bool, "friction": str, "gamma0_t": float}}
OBSTACLES = {"plane": {"point": "vector", "normal": "vector", "motion": "vector"},
             "circle": {"centre": "vector", "radius": float, "motion": "vector"},
             "profile": {"points": "points", "radius": float, "motion": "vector"},
             "gmsh_profile": {"file": str, "curve": str, "radius": float, "spacing": float, "motion": "vector"}}
OPTIONAL = ("motion", "spacing")
PROBES = {"node": {"name": str, "point": "vector", "component": int, "column": str},
          "contact_force": {"item": str, "column": str, "component": int, "scale": float},
          "contact_length": {"item": str, "column": str, "scale": float},
          "contact_peak": {"item": str, "column": str, "scale": float},
          "reaction": {"boundary": str, "name": str},
          "max_plastic_strain": {}}
NEWTON = {"rtol": float, "atol": float, "stol": float, "max_it": int, "divergence": float, "backtracks": int,
          "free_its": int, "line_search": str, "energy_eta": float, "scale": str, "petsc_options": dict}
SECTIONS = {"mesh", "body", "items", "steps", "newton", "probes"}


def _check(where: str, table: dict, spec: dict, required=()) -> dict:
    """Keys of ``table`` against ``spec`` (key -> type), values finite; returns the table."""
    if not isinstance(table, dict):
        raise ProblemError(f"{where}: expected a table of keys, got {table!r}")
    for key, value in table.items():
        if key not in spec:
            raise ProblemError(f"{where}: unknown key {key!r}; the keys are {', '.join(spec) or 'none'}")
        kind = spec[key]
        ok = True
        if kind is float:
            ok = isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)
        elif kind is int:
            ok = isinstance(value, int) and not isinstance(value, bool)
        elif kind in (str, bool, dict, list):
            ok = isinstance(value, kind)
        elif kind in ("vector", "vector|number"):
            ok = (isinstance(value, list) and len(value) == 2 and all(
                isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) for v in value))
            if kind == "vector|number" and not ok:
                ok = isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)
        elif kind == "points":
            ok = isinstance(value, list) and len(value) >= 2 and all(
                isinstance(p, list) and len(p) == 2 and all(isinstance(v, (int, float)) and math.isfinite(v)
                                                            for v in p) for p in value)
        if not ok:
            want = {float: "a finite number", int: "a whole number", str: "a string", bool: "true or false",
                    dict: "a table", list: "a list of item names", "vector": "two finite numbers [x, y]", "points": "a list of [x, y] points",
                    "vector|number": "a finite number or [x, y]"}[kind]
            raise ProblemError(f"{where}: {key} = {value!r}: give {want}")
    for key in required:
        if key not in table:
            raise ProblemError(f"{where}: {key} is missing: add it")
    return table


def read(path) -> dict:
    """Parse and check a problem file; returns its tables (nothing heavy is imported)."""
    path = pathlib.Path(path)
    if not path.is_file():
        raise ProblemError(f"{path}: no such problem file: check the path")
    try:
        data = tomllib.loads(path.read_text())
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as err:
        raise ProblemError(f"{path}: not valid TOML ({err}): fix the syntax") from None
    unknown = set(data) - SECTIONS
    if unknown:
        raise ProblemError(f"{path}: unknown section {sorted(unknown)[0]!r}; the sections are "
                           f"{', '.join(sorted(SECTIONS))}")
    def need(key):
        if key not in data:
            raise ProblemError(f"{path}: the [{key}] section is missing: add it")

    need("mesh")
    mesh = data["mesh"]
    if "file" in mesh:
        _check(f"{path}: [mesh]", mesh, {"file": str, "tags": list})
        mesh["file"] = str((path.parent / mesh["file"]).resolve())
        if not pathlib.Path(mesh["file"]).is_file():
            raise ProblemError(f"{path}: [mesh] file = {mesh['file']!r} does not exist: check the path")
    else:
        b = mesh.get("builder")
        if b not in BUILDERS:
            raise ProblemError(f"{path}: [mesh] builder = {b!r}: choose one of {', '.join(BUILDERS)} or "
                               "give file = \"part.msh\"")
        spec = {"builder": str, "order": int, **{k: float for k in BUILDERS[b]}}
        _check(f"{path}: [mesh]", mesh, spec, required=BUILDERS[b])
        for k in BUILDERS[b]:
            if mesh[k] <= 0 and k != "z_support":
                raise ProblemError(f"{path}: [mesh] {k} = {mesh[k]}: give a number > 0")
    need("body")
    body = _check(f"{path}: [body]", data["body"], {"kind": str, "update": str, "degree": int, "thickness": float,
                                                    "material": dict}, required=("kind", "material"))
    mat = _check(f"{path}: [body] material", body["material"],
                 {"law": str, "E": float, "nu": float, "hardening": "points"}, required=("E", "nu"))
    law = mat.get("law", "elastic")
    if law not in ("elastic", "j2", "chen"):
        raise ProblemError(f"{path}: [body] material law = {law!r}: choose elastic, j2 or chen")
    if law != "elastic" and "hardening" not in mat:
        raise ProblemError(f"{path}: [body] material: a {law} material needs hardening = [[0, sigma_y], ...]")
    names = {}
    need("items")
    if not isinstance(data["items"], list) or not data["items"]:
        raise ProblemError(f"{path}: give the items as [[items]] tables")
    for k, item in enumerate(data["items"], 1):
        kind = item.get("type") if isinstance(item, dict) else None
        if kind not in ITEMS:
            raise ProblemError(f"{path}: [[items]] {k}: type = {kind!r}: choose one of {', '.join(ITEMS)}")
        where = f"{path}: [[items]] {k} ({kind})"
        _check(where, item, {"type": str, "name": str, **ITEMS[kind]},
               required=[key for key in ITEMS[kind] if key in ("boundary", "p", "vector", "point", "obstacle")])
        if kind == "contact":
            obs = item["obstacle"]
            if obs.get("type") not in OBSTACLES:
                raise ProblemError(f"{where}: obstacle type = {obs.get('type')!r}: choose one of "
                                   f"{', '.join(OBSTACLES)}")
            _check(f"{where} obstacle", obs, {"type": str, **OBSTACLES[obs["type"]]},
                   required=[key for key in OBSTACLES[obs["type"]] if key not in OPTIONAL])
            if "file" in obs:
                obs["file"] = str((path.parent / obs["file"]).resolve())
                if not pathlib.Path(obs["file"]).is_file():
                    raise ProblemError(f"{where} obstacle: file = {obs['file']!r} does not exist: check the path")
        name = item.get("name", f"{kind}{k}")
        if name in names:
            raise ProblemError(f"{where}: the name {name!r} is taken by item {names[name]}: rename one")
        names[name] = k
        item["name"] = name
    steps = data.get("steps", [{}])
    for k, step in enumerate(steps, 1):
        _check(f"{path}: [[steps]] {k}", step, {"n": int, "predictor": str, "max_cutbacks": int, "ramp": dict,
                                                "name": str, "release": list, "first": float, "retry": bool})
        why = first_increment_error(step.get("first", 1.0), step.get("max_cutbacks", 6))
        if why:
            raise ProblemError(f"{path}: [[steps]] {k}: {why}")
        supports = [n for n, i in names.items() if data["items"][i - 1]["type"] in ("fixed", "displacement")]
        for key in step.get("release", []):
            if key not in supports:
                raise ProblemError(f"{path}: [[steps]] {k} release: {key!r} is not a support item; the supports "
                                   f"are {', '.join(supports) or 'none'}")
        for key, target in step.get("ramp", {}).items():
            if key not in names:
                raise ProblemError(f"{path}: [[steps]] {k} ramp: no item named {key!r}; the items are "
                                   f"{', '.join(names)}")
            _check(f"{path}: [[steps]] {k} ramp", {key: target}, {key: float})
    data["steps"] = steps
    _check(f"{path}: [newton]", data.get("newton", {}), NEWTON)
    for k, probe in enumerate(data.get("probes", []), 1):
        kind = probe.get("type") if isinstance(probe, dict) else None
        if kind not in PROBES:
            raise ProblemError(f"{path}: [[probes]] {k}: type = {kind!r}: choose one of {', '.join(PROBES)}")
        _check(f"{path}: [[probes]] {k} ({kind})", probe, {"type": str, **PROBES[kind]})
        if "item" in probe and probe["item"] not in names:
            raise ProblemError(f"{path}: [[probes]] {k}: no item named {probe['item']!r}")
    return data


def build(data: dict, comm, writers=()):
    """The :class:`Job` of a checked problem (imports dolfinx)."""
    from . import contact as c
    from . import geometry, loads, probes
    from .job import Job, Step
    from .mechanics.body import Body
    from .mechanics.material_data import Hardening
    from .mechanics.materials import as_material
    from .solver import NewtonSettings

    mesh = dict(data["mesh"])
    if "file" in mesh:
        md = geometry.load_msh(mesh["file"], comm, required=mesh.get("tags", ()))
    else:
        builder = getattr(geometry, mesh.pop("builder"))
        md = builder(**mesh, comm=comm)
    b = data["body"]
    m = b["material"]
    table = m.get("hardening")
    hard = Hardening([p for p, _ in table], [s for _, s in table]) if table else None
    law = m.get("law", "elastic")
    material = as_material(m["E"], m["nu"], None if law == "elastic" else law, hard)
    body = Body(md, b["kind"], material, update=b.get("update", "sr_log"), degree=b.get("degree", 2),
                thickness=b.get("thickness", 1.0))
    named = {}
    for spec in data["items"]:
        s = dict(spec)
        kind, name = s.pop("type"), s.pop("name")
        if kind == "contact":
            o = dict(s.pop("obstacle"))
            otype = o.pop("type")
            if "file" in o:
                o["path"] = o.pop("file")
            obstacle = {"plane": c.Plane, "circle": c.Circle, "profile": c.Profile,
                        "gmsh_profile": c.Profile.from_gmsh}[otype](**o)
            item = c.Contact(s.pop("boundary"), obstacle, **s)
        else:
            cls = {"fixed": loads.Fixed, "displacement": loads.Displacement, "pressure": loads.Pressure,
                   "traction": loads.Traction, "body_force": loads.BodyForce, "point_load": loads.PointLoad}[kind]
            item = cls(**s)
        named[name] = item
    steps = [Step(st.get("n", 10), ramp={named[k]: v for k, v in st["ramp"].items()} if "ramp" in st else None,
                  predictor=st.get("predictor", Step.predictor), max_cutbacks=st.get("max_cutbacks", 6),
                  name=st.get("name", ""), release=[named[k] for k in st.get("release", [])],
                  first=st.get("first", 1.0), retry=st.get("retry", Step.retry))
             for st in data["steps"]]
    plist = []
    for spec in data.get("probes", []):
        s = dict(spec)
        kind = s.pop("type")
        if kind == "node":
            plist.append(probes.NodeDisplacement(s.get("name", "node"), s["point"], s.get("component"),
                                                 s.get("column")))
        elif kind == "contact_force":
            plist.append(probes.ContactForce(named[s["item"]], s.get("column", "contact_force"),
                                             s.get("component", 1), s.get("scale", 1.0)))
        elif kind == "contact_length":
            plist.append(probes.ContactLength(named[s["item"]], s.get("column", "contact_length"),
                                              s.get("scale", 1.0)))
        elif kind == "contact_peak":
            plist.append(probes.ContactPeak(named[s["item"]], s.get("column", "peak_pressure"),
                                            s.get("scale", 1.0)))
        elif kind == "reaction":
            plist.append(probes.Reaction(s["boundary"], s.get("name")))
        else:
            plist.append(probes.MaxPlasticStrain())
    newton = NewtonSettings(**data.get("newton", {}))
    return Job(body, list(named.values()), steps, plist, writers, newton=newton)

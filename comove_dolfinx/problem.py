"""Problem files: a job described in TOML, for ``comove run problem.toml`` (docs/api.md).

::

    [mesh]                       # a built-in builder with its parameters, or file = "part.msh"
    builder = "annulus_sector"
    r_in = 4.849
    r_out = 5.715
    size = 0.22

    [body]
    kind = "plane_strain"        # plane_stress, plane_strain, axisymmetric, solid (3D)
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

    [[probes]]                   # node, contact_force, contact_length (3D: contact_area, contact_radius), contact_peak,
                                 # reaction, max_plastic_strain
    type = "contact_force"
    item = "plate"
    column = "force"
    scale = -2.0

Everything is checked here, before dolfinx is imported: every key's type and range (problem_schema.py, the
``NewtonSettings`` fields through checks.newton_error, the material through ``Elastic`` and
``Hardening``), the builder's sizes in their order and the number of cells they would make
(checks.mesh_size_error), and the names the steps and probes refer to. A bad file gets one line that
names the key (``[[items]] 2 (contact): mu = -1 ...``) and the fix. Paths are relative to the problem
file.
"""
from __future__ import annotations

import pathlib
import tomllib

from .checks import mesh_size_error, newton_error
from .choices import PLASTIC_UPDATES, first_increment_error
from .mechanics.material_data import Elastic, Hardening, MaterialError
from .problem_schema import (BUILDER_OPTIONS, BUILDERS, BUILDERS_3D, ITEMS, OBSTACLE_REQUIRED, OBSTACLES,
                             OBSTACLES_2D, OBSTACLES_3D, PROBES, REQUIRED, SECTIONS, ProblemError, _check)


def _load(path: pathlib.Path) -> dict:
    """The file's tables, with only known sections."""
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
    return data


def _need(path: pathlib.Path, data: dict, key: str):
    """The section ``key``; [[items]] and [[steps]] non-empty lists of tables, [[probes]] a list."""
    if key not in data and key in ("mesh", "body", "items"):
        raise ProblemError(f"{path}: the [{key}] section is missing: add it")
    value = data.get(key, [])
    if key in ("items", "steps", "probes") and (not isinstance(value, list) or (not value and key != "probes")):
        raise ProblemError(f"{path}: give the {key} as [[{key}]] tables"
                           + (" (or leave them out)" if key != "items" else ""))
    return value


def _mesh(path: pathlib.Path, mesh) -> None:
    """[mesh]: a file with tags, or a builder with positive sizes in their order and not too fine."""
    where = f"{path}: [mesh]"
    if isinstance(mesh, dict) and "file" in mesh:
        _check(where, mesh, {"file": str, "tags": "names"})
        mesh["file"] = str((path.parent / mesh["file"]).resolve())
        if not pathlib.Path(mesh["file"]).is_file():
            raise ProblemError(f"{where} file = {mesh['file']!r} does not exist: check the path")
        return
    b = mesh.get("builder") if isinstance(mesh, dict) else None
    if not isinstance(b, str) or b not in BUILDERS:
        raise ProblemError(f"{where} builder = {b!r}: choose one of {', '.join(BUILDERS)} or "
                           "give file = \"part.msh\"")
    sizes = BUILDERS[b] + BUILDER_OPTIONS.get(b, ())
    bricks = {"hexahedra": bool} if b in ("box", "tube_sector") else {}
    _check(where, mesh, {"builder": str, "order": int, **bricks, **{k: float for k in sizes}}, required=BUILDERS[b])
    for k in sizes:
        if k in mesh and mesh[k] <= 0:
            raise ProblemError(f"{where} {k} = {mesh[k]}: give a number > 0")
    pair = {"annulus_sector": ("r_in", "r_out"), "plate_section": ("z_support", "t"),
            "quarter_disc": ("size_contact", "size"), "tube_sector": ("r_in", "r_out")}.get(b)
    if pair:
        (a, lo), (c, hi) = ((k, mesh[k]) for k in pair)
        strict = b != "quarter_disc"
        if lo > hi or (strict and lo == hi):
            raise ProblemError(f"{where} {a} = {lo}, {c} = {hi}: {a} must be {'<' if strict else '<='} {c}")
    why = mesh_size_error(b, mesh)
    if why is not None:
        raise ProblemError(f"{where} {why}")


def _body(path: pathlib.Path, body) -> None:
    """[body] and its material: the names known, E and nu and the hardening table usable."""
    where = f"{path}: [body]"
    _check(where, body, {"kind": str, "update": str, "degree": int, "thickness": float, "fbar": bool,
                         "material": dict}, required=("kind", "material"))
    if body.get("fbar") and body["kind"] == "plane_stress":
        raise ProblemError(f"{where} fbar = true in plane stress: the thickness takes the volume change, so "
                           "plane stress does not lock; leave fbar out")
    mat = _check(f"{where} material", body["material"], {"law": str, "E": float, "nu": float,
                                                        "hardening": "table"}, required=("E", "nu"))
    law = mat.get("law", "elastic")
    try:
        Elastic(mat["E"], mat["nu"])
        if "hardening" in mat:
            Hardening([p for p, _ in mat["hardening"]], [s for _, s in mat["hardening"]])
    except MaterialError as err:
        raise ProblemError(f"{where} material: {err}") from None
    if law != "elastic" and "hardening" not in mat:
        raise ProblemError(f"{where} material: a {law} material needs hardening = [[0, sigma_y], ...]")
    if law == "elastic" and "hardening" in mat:
        raise ProblemError(f"{where} material: hardening is for law = \"j2\" or \"chen\": give the law "
                           "or remove the table")
    update = body.get("update", "sr_log")
    if law != "elastic" and update not in PLASTIC_UPDATES:
        raise ProblemError(f"{where} update = {update!r} cannot carry plasticity: choose one of "
                           f"{', '.join(PLASTIC_UPDATES)}")


def _dimension(path: pathlib.Path, data: dict) -> None:
    """The body's dimension (3 for kind = "solid", else 2) in its mesh builder, every vector of the
    items, obstacles and probes, and every component."""
    solid = data["body"]["kind"] == "solid"
    dim = 3 if solid else 2
    builder = data["mesh"].get("builder")
    if builder is not None and (builder in BUILDERS_3D) != solid:
        want = f"a 3D builder ({', '.join(BUILDERS_3D)})" if solid else "a 2D builder, or kind = \"solid\""
        raise ProblemError(f"{path}: [mesh] builder = {builder!r} for a body of kind = "
                           f"{data['body']['kind']!r}: give {want}")
    tables = [(f"[[items]] {k} ({t['type']})", t, ITEMS[t["type"]]) for k, t in enumerate(data["items"], 1)]
    tables += [(f"[[items]] {k} ({t['type']}) obstacle", t["obstacle"], OBSTACLES[t["obstacle"]["type"]])
               for k, t in enumerate(data["items"], 1) if t["type"] == "contact"]
    tables += [(f"[[probes]] {k} ({t['type']})", t, PROBES[t["type"]]) for k, t in enumerate(data.get("probes", []), 1)]
    _of_dimension(path, data, dim)
    for where, table, spec in tables:
        for key, value in table.items():
            if spec.get(key) in ("vector", "vector|number") and isinstance(value, list) and len(value) != dim:
                raise ProblemError(f"{path}: {where}: {key} = {value!r}: give {dim} numbers (the body is "
                                   f"{'3D' if solid else '2D'})")
            if key == "component" and value >= dim:
                raise ProblemError(f"{path}: {where}: component = {value}: the body is 2D, give 0 (x) or 1 (y)")


def _of_dimension(path: pathlib.Path, data: dict, dim: int) -> None:
    """The obstacles and the contact probes of the body's dimension ``dim``."""
    body = f"the body is {dim}D (kind = {data['body']['kind']!r})"
    for k, t in enumerate(data["items"], 1):
        otype = t["obstacle"]["type"] if t["type"] == "contact" else None
        if otype in (OBSTACLES_2D if dim == 3 else OBSTACLES_3D):
            use = ", ".join(("plane",) + (OBSTACLES_3D if dim == 3 else OBSTACLES_2D))
            raise ProblemError(f"{path}: [[items]] {k} (contact) obstacle: type = {otype!r} is a {5 - dim}D "
                               f"obstacle, {body}: choose one of {use}")
    wrong = {3: {"contact_length": "contact_area"},
             2: {"contact_area": "contact_length", "contact_radius": "contact_length"}}[dim]
    for k, t in enumerate(data.get("probes", []), 1):
        if t["type"] in wrong:
            raise ProblemError(f"{path}: [[probes]] {k}: type = {t['type']!r} is not defined when {body}: "
                               f"use {wrong[t['type']]}")


def _items(path: pathlib.Path, items: list) -> dict:
    """[[items]]: each of a known type with its keys; their names (name -> position from 1)."""
    names = {}
    for k, item in enumerate(items, 1):
        kind = item.get("type") if isinstance(item, dict) else None
        if not isinstance(kind, str) or kind not in ITEMS:
            raise ProblemError(f"{path}: [[items]] {k}: type = {kind!r}: choose one of {', '.join(ITEMS)}")
        where = f"{path}: [[items]] {k} ({kind})"
        _check(where, item, {"type": str, "name": str, **ITEMS[kind]},
               required=[key for key in ITEMS[kind] if key in REQUIRED])
        if kind == "contact":
            _contact(where, path, item)
        name = item.get("name", f"{kind}{k}")
        if name in names:
            raise ProblemError(f"{where}: the name {name!r} is taken by item {names[name]}: rename one")
        names[name] = k
        item["name"] = name
    return names


def _contact(where: str, path: pathlib.Path, item: dict) -> None:
    """A contact item's obstacle, and relag only with the lagged law."""
    if item.get("relag") and item.get("friction", "lagged") != "lagged":
        raise ProblemError(f"{where}: relag = true re-solves the lagged law: give friction = \"lagged\" "
                           "or relag = false")
    obs = item["obstacle"]
    if not isinstance(obs.get("type"), str) or obs["type"] not in OBSTACLES:
        raise ProblemError(f"{where}: obstacle type = {obs.get('type')!r}: choose one of {', '.join(OBSTACLES)}")
    _check(f"{where} obstacle", obs, {"type": str, **OBSTACLES[obs["type"]]}, required=OBSTACLE_REQUIRED[obs["type"]])
    for key, what in (("normal", "a direction towards the body"), ("axis", "the axis's direction"),
                      ("u", "the direction of the profile's x"), ("v", "the direction of the profile's y")):
        if key in obs and not any(obs[key]):
            raise ProblemError(f"{where} obstacle: {key} = [{', '.join('0' for _ in obs[key])}]: give {what}")
    if obs["type"] in ("extruded", "revolved"):
        _swept(f"{where} obstacle", obs)
    if obs["type"] == "surface" and obs.get("size", 1.0) <= 0:
        raise ProblemError(f"{where} obstacle: size = {obs['size']!r}: give the triangles' size, a number > 0")
    if "file" in obs:
        obs["file"] = str((path.parent / obs["file"]).resolve())
        if not pathlib.Path(obs["file"]).is_file():
            raise ProblemError(f"{where} obstacle: file = {obs['file']!r} does not exist: check the path")


def _swept(where: str, obs: dict) -> None:
    """An extruded or revolved obstacle's profile: its points, or a file and a curve; a revolved
    profile at x >= 0 (the distance from the axis); an extruded one's u and v across each other."""
    if ("points" in obs) == ("file" in obs):
        raise ProblemError(f"{where}: give the profile as points = [[x, y], ...] or as file and curve"
                           + (", not both" if "points" in obs else ""))
    if "file" in obs and "curve" not in obs:
        raise ProblemError(f"{where}: curve is missing: add the name of the file's physical curve")
    if "points" in obs and ("curve" in obs or "spacing" in obs):
        raise ProblemError(f"{where}: curve and spacing are for a profile from a file: remove them or give "
                           "file instead of points")
    behind = [p for p in obs.get("points", []) if p[0] < 0]
    if obs["type"] == "revolved" and behind:
        raise ProblemError(f"{where}: points: {behind[0]} has x < 0: x is the distance from the axis, "
                           "give x >= 0")
    u, v = obs.get("u", [1.0, 0.0, 0.0]), obs.get("v", [0.0, 0.0, 1.0])
    if obs["type"] == "extruded" and len(u) == len(v) == 3:
        cross = [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]]
        if sum(c * c for c in cross) <= 1e-16 * sum(a * a for a in u) * sum(b * b for b in v):
            raise ProblemError(f"{where}: u = {u} and v = {v} are parallel: give the profile's y direction v "
                               "across its x direction u")


def _steps(path: pathlib.Path, data: dict, names: dict) -> None:
    """[[steps]] (one default step if none): their keys, and the items they ramp or release."""
    data.setdefault("steps", [{}])
    supports = [n for n, i in names.items() if data["items"][i - 1]["type"] in ("fixed", "displacement")]
    for k, step in enumerate(data["steps"], 1):
        where = f"{path}: [[steps]] {k}"
        _check(where, step, {"n": int, "predictor": str, "max_cutbacks": int, "ramp": dict, "name": str,
                             "release": "names", "first": float, "retry": bool})
        why = first_increment_error(step.get("first", 1.0), step.get("max_cutbacks", 6))
        if why:
            raise ProblemError(f"{where}: {why}")
        for key in step.get("release", []):
            if key not in supports:
                raise ProblemError(f"{where} release: {key!r} is not a support item; the supports "
                                   f"are {', '.join(supports) or 'none'}")
        for key, target in step.get("ramp", {}).items():
            if key not in names:
                raise ProblemError(f"{where} ramp: no item named {key!r}; the items are {', '.join(names)}")
            _check(f"{where} ramp", {key: target}, {key: float})


def _probes(path: pathlib.Path, probes: list, items: list, names: dict) -> None:
    """[[probes]]: each of a known type; a contact probe names a contact item."""
    contacts = [n for n, i in names.items() if items[i - 1]["type"] == "contact"]
    for k, probe in enumerate(probes, 1):
        kind = probe.get("type") if isinstance(probe, dict) else None
        if not isinstance(kind, str) or kind not in PROBES:
            raise ProblemError(f"{path}: [[probes]] {k}: type = {kind!r}: choose one of {', '.join(PROBES)}")
        where = f"{path}: [[probes]] {k} ({kind})"
        _check(where, probe, {"type": str, **PROBES[kind]},
               required=[key for key in ("item", "point", "boundary") if key in PROBES[kind]])
        if "item" in probe and probe["item"] not in contacts:
            raise ProblemError(f"{where}: item = {probe['item']!r} is not a contact item; the contact items "
                               f"are {', '.join(contacts) or 'none'}")


def read(path) -> dict:
    """Parse and check a problem file; returns its tables (nothing heavy is imported)."""
    path = pathlib.Path(path)
    data = _load(path)
    _mesh(path, _need(path, data, "mesh"))
    _body(path, _need(path, data, "body"))
    names = _items(path, _need(path, data, "items"))
    if "steps" in data:
        _need(path, data, "steps")
    _steps(path, data, names)
    newton = data.get("newton", {})
    why = newton_error(newton) if isinstance(newton, dict) else f"expected a table of keys, got {newton!r}"
    if why is None and "monitor" in newton:
        why = "monitor: an observer is a Python object; run the problem from Python to give one"
    if why is not None:
        raise ProblemError(f"{path}: [newton] {why}")
    _probes(path, _need(path, data, "probes"), data["items"], names)
    _dimension(path, data)
    return data


def build(data: dict, comm, writers=()):
    """The :class:`Job` of a checked problem (imports dolfinx)."""
    from . import geometry
    from .job import Job, Step
    from .mechanics.body import Body
    from .mechanics.materials import as_material
    from .solver import NewtonSettings

    mesh = dict(data["mesh"])
    if "file" in mesh:
        md = geometry.load_msh(mesh["file"], comm, required=mesh.get("tags", ()))
    else:
        md = getattr(geometry, mesh.pop("builder"))(**mesh, comm=comm)
    b, m = data["body"], data["body"]["material"]
    table = m.get("hardening")
    hard = Hardening([p for p, _ in table], [s for _, s in table]) if table else None
    law = m.get("law", "elastic")
    material = as_material(m["E"], m["nu"], None if law == "elastic" else law, hard)
    body = Body(md, b["kind"], material, update=b.get("update", "sr_log"), degree=b.get("degree", 2),
                thickness=b.get("thickness", 1.0), fbar=b.get("fbar", False))
    named = {spec["name"]: _item(spec) for spec in data["items"]}
    steps = [Step(st.get("n", 10), ramp={named[k]: v for k, v in st["ramp"].items()} if "ramp" in st else None,
                  predictor=st.get("predictor", Step.predictor), max_cutbacks=st.get("max_cutbacks", 6),
                  name=st.get("name", ""), release=[named[k] for k in st.get("release", [])],
                  first=st.get("first", 1.0), retry=st.get("retry", Step.retry))
             for st in data["steps"]]
    plist = [_probe(spec, named, 3 if b["kind"] == "solid" else 2) for spec in data.get("probes", [])]
    newton = NewtonSettings(**data.get("newton", {}))
    return Job(body, list(named.values()), steps, plist, writers, newton=newton)


def _item(spec: dict):
    """The item of a checked [[items]] table."""
    from . import contact as c
    from . import loads
    s = dict(spec)
    kind, _ = s.pop("type"), s.pop("name")
    if kind != "contact":
        return {"fixed": loads.Fixed, "displacement": loads.Displacement, "pressure": loads.Pressure,
                "traction": loads.Traction, "body_force": loads.BodyForce, "point_load": loads.PointLoad}[kind](**s)
    o = dict(s.pop("obstacle"))
    otype = o.pop("type")
    if "file" in o:
        o["path"] = o.pop("file")
    if otype in ("extruded", "revolved"):
        source = {k: o.pop(k) for k in ("points", "path", "curve", "radius", "spacing") if k in o}
        o["profile"] = (c.Profile(source["points"], source["radius"]) if "points" in source
                        else c.Profile.from_gmsh(**source))
    obstacle = {"plane": c.Plane, "circle": c.Circle, "profile": c.Profile, "gmsh_profile": c.Profile.from_gmsh,
                "sphere": c.Sphere, "cylinder": c.Cylinder, "extruded": c.Extruded, "revolved": c.Revolved,
                "surface": c.Surface.from_gmsh}[otype](**o)
    return c.Contact(s.pop("boundary"), obstacle, **s)


def _probe(s: dict, named: dict, dim: int = 2):
    """The probe of a checked [[probes]] table (``named``: the items by name; ``dim``: the body's)."""
    from . import probes
    kind, scale = s["type"], s.get("scale", 1.0)
    if kind == "node":
        return probes.NodeDisplacement(s.get("name", "node"), s["point"], s.get("component"), s.get("column"))
    if kind == "contact_force":
        return probes.ContactForce(named[s["item"]], s.get("column", "contact_force"), s.get("component", 1), scale)
    if kind == "contact_length":
        return probes.ContactLength(named[s["item"]], s.get("column", "contact_length"), scale)
    if kind == "contact_area":
        return probes.ContactArea(named[s["item"]], s.get("column", "contact_area"), scale)
    if kind == "contact_radius":
        where = {k: s[k] for k in ("origin", "direction", "axis") if k in s}
        return probes.ContactRadius(named[s["item"]], s.get("column", "contact_radius"), scale=scale, **where)
    if kind == "contact_peak":
        return probes.ContactPeak(named[s["item"]], s.get("column", "peak_pressure"), scale)
    if kind == "reaction":
        return probes.Reaction(s["boundary"], s.get("name"), dim=dim)
    return probes.MaxPlasticStrain()

"""comove_dolfinx: large deformation of solids against rigid obstacles by the co-moving S-R method.

The package solves large elastic and elastic-plastic deformations in 2D (plane stress, plane strain,
axisymmetry) on dolfinx 0.5, 0.9 and 0.11, with Chen's S-R decomposition of each increment, the
convected stress update, follower loads and unilateral frictional contact with rigid obstacles.
Units are whatever the user supplies consistently; the scenes use cm and kgf.

The public API (docs/api.md), imported on first use so that ``import comove_dolfinx`` stays light::

    import comove_dolfinx as cm
    mesh = cm.rectangle(10.0, 0.5, 0.125)                   # or cm.load_msh("part.msh")
    body = cm.Body(mesh, "plane_stress", cm.Elastic(1000.0, 0.3))
    items = [cm.Fixed("left"), cm.Pressure("top", 0.5),
             cm.Contact("bottom", cm.Plane((0, -3), (0, 1)), mu=0.1)]
    results = cm.Job(body, items, [cm.Step(20)], probes=[cm.NodeDisplacement("tip", (10, 0))]).run()
"""

import sys

__version__ = "0.3.0"


class _MPIFirst:
    """The PyPI wheel of dolfinx needs its bootstrap (``import dolfinx_solver``: mpi4py's MPI loaded
    ahead of dolfinx's and PETSc's bindings) before any of them. This import hook runs it at the
    first import of mpi4py, petsc4py or dolfinx, not when the package is imported: ``import
    comove_dolfinx`` stays light, and the ``comove`` command has its Ctrl-C handler installed
    before anything heavy loads. Elsewhere (Debian's packages) the bootstrap is not installed and
    the hook only removes itself."""

    def find_spec(self, name, path=None, target=None):
        if name in ("mpi4py", "petsc4py", "dolfinx"):
            sys.meta_path.remove(self)
            try:
                import dolfinx_solver  # noqa: F401
            except ModuleNotFoundError as err:
                if err.name != "dolfinx_solver":
                    raise
            except BaseException:           # its refusal, or Ctrl-C: the next import tries again
                sys.meta_path.insert(0, self)
                raise
        return None


if not {"mpi4py", "petsc4py", "dolfinx"} & set(sys.modules):
    sys.meta_path.insert(0, _MPIFirst())


_API = {
    "geometry": ("MeshData", "MeshError", "rectangle", "annulus_sector", "plate_section", "quarter_disc",
                 "necking_bar", "necking_bar_grid", "box", "tube_sector", "sphere_octant", "plate_quarter",
                 "load_msh", "from_dolfinx"),
    "mechanics.body": ("Body", "BodyError"),
    "mechanics.materials": ("Elastic", "J2", "Chen", "Hardening", "MaterialError"),
    "loads": ("Fixed", "Displacement", "Pressure", "Traction", "BodyForce", "PointLoad", "ItemError"),
    "contact": ("Contact", "Plane", "Circle", "Profile", "Sphere", "Cylinder", "Extruded", "Revolved",
                "Surface", "ContactError"),
    "job": ("Step", "Job", "Results", "JobError"),
    "solver": ("NewtonSettings", "SettingsError"),
    "probes": ("Probe", "NodeDisplacement", "ContactForce", "ContactLength", "ContactEdges", "ContactPeak",
               "ContactArea", "ContactRadius", "Reaction", "MaxPlasticStrain", "Value"),
    "io": ("Writer", "HistoryCSV", "VTK", "XDMF", "RunInfo", "Console", "Snapshots", "read_history"),
    "presets": ("get_scene", "SCENES"),
}
_WHERE = {name: module for module, names in _API.items() for name in names}
__all__ = sorted(_WHERE)


def lazy_names(package: str, where: dict[str, str], namespace: dict):
    """(__getattr__, __dir__) of a package whose names ``where`` (name -> submodule) are imported
    on first use (PEP 562), so that importing the package loads none of them."""
    import importlib

    def getattr_(name: str):
        if name not in where:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        value = getattr(importlib.import_module(f".{where[name]}", package), name)
        namespace[name] = value
        return value

    def dir_():
        return sorted(set(namespace) | set(where))
    return getattr_, dir_


# the public API, imported on first use (dolfinx is heavy)
__getattr__, __dir__ = lazy_names(__name__, _WHERE, globals())


def check_platform() -> None:
    """Fail with a clear message unless a supported dolfinx (0.5, 0.9, 0.11) and gmsh are importable."""
    import importlib.util
    try:
        import dolfinx  # noqa: F401
        if importlib.util.find_spec("gmsh") is None:     # (found, not imported: gmsh_session.py)
            raise ModuleNotFoundError("No module named 'gmsh'")
    except ModuleNotFoundError as err:
        raise SystemExit(
            f"comove_dolfinx needs dolfinx and gmsh ({err}). On Debian they serve /usr/bin/python3 "
            "only: run 'make demo', or create the venv with '/usr/bin/python3 -m venv "
            "--system-site-packages .venv'; elsewhere 'make demo DOLFINX=pip' installs the PyPI "
            "wheels. A PETSC_DIR in the environment that points elsewhere also hides Debian's "
            "dolfinx: unset it.") from None
    from .compat import check_version
    check_version()

"""comove_dolfinx: large deformation of solids against rigid obstacles by the co-moving S-R method.

The package solves large elastic and elastic-plastic deformations in 2D (plane stress, plane strain,
axisymmetry) on dolfinx 0.5.2, with Chen's S-R decomposition of each increment, the convected stress
update, follower loads and unilateral frictional contact with rigid obstacles.
Units are whatever the user supplies consistently; the scenes use cm and kgf.
"""

__version__ = "0.1.0"

try:        # the PyPI wheel of dolfinx: its bootstrap loads mpi4py's MPI ahead of dolfinx's bindings
    import dolfinx_solver  # noqa: F401
except ModuleNotFoundError:
    pass


def check_platform() -> None:
    """Fail with a clear message unless a supported dolfinx (0.5, 0.9, 0.11) and gmsh are importable."""
    try:
        import dolfinx  # noqa: F401
        import gmsh  # noqa: F401
    except ModuleNotFoundError as err:
        raise SystemExit(
            f"comove_dolfinx needs dolfinx and gmsh ({err}). On Debian they serve /usr/bin/python3 "
            "only: run 'make demo', or create the venv with '/usr/bin/python3 -m venv "
            "--system-site-packages .venv'; elsewhere 'make demo DOLFINX=pip' installs the PyPI "
            "wheels. A PETSC_DIR in the environment that points elsewhere also hides Debian's "
            "dolfinx: unset it.") from None
    from .compat import check_version
    check_version()

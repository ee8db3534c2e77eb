"""comove_dolfinx: large deformation of solids against rigid obstacles by the co-moving S-R method.

The package solves large elastic and elastic-plastic deformations in 2D (plane stress, plane strain,
axisymmetry) on dolfinx 0.5.2, with Chen's S-R decomposition of each increment, the convected stress
update, follower loads and unilateral frictional contact with rigid obstacles.
Units are whatever the user supplies consistently; the scenes use cm and kgf.
"""

__version__ = "0.1.0"

REQUIRED_DOLFINX = "0.5"


def check_platform() -> None:
    """Fail with a clear message unless Debian's dolfinx 0.5 stack and gmsh are importable."""
    try:
        import dolfinx
        import gmsh  # noqa: F401
    except ModuleNotFoundError as err:
        raise SystemExit(
            f"comove_dolfinx needs Debian's python3-dolfinx-real and python3-gmsh ({err}). "
            "They serve /usr/bin/python3 only: run 'make demo' or create the venv with "
            "'/usr/bin/python3 -m venv --system-site-packages .venv'. A PETSC_DIR in the "
            "environment that points elsewhere also hides dolfinx: unset it.") from None
    if not dolfinx.__version__.startswith(REQUIRED_DOLFINX):
        raise SystemExit(f"comove_dolfinx is written for dolfinx {REQUIRED_DOLFINX}.x, found "
                         f"{dolfinx.__version__}; install Debian 12's python3-dolfinx-real.")

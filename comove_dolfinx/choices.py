"""The choices a user picks from, and the rule for a step's first increment.

The kinematic models, stress updates, contact methods, friction laws, predictors and plasticity
laws by the names a scene, a problem file or the API takes, and :func:`first_increment_error`;
checked here before anything heavy is imported. The modules that implement the choices check that
they implement exactly these (tests/test_input.py).
"""

MODELS = ("plane_strain", "plane_stress", "axisymmetric", "solid")
UPDATES = ("sr_log", "sr", "hughes_winget", "polar", "svk", "neo_hooke", "small_strain")
PLASTIC_UPDATES = ("sr_log", "sr", "hughes_winget", "small_strain")   # those that carry a rotated old stress
CONTACT_METHODS = ("penalty", "nitsche")
FRICTION_LAWS = ("coulomb", "lagged")        # the threshold: current pressure, or the last increment's
PREDICTORS = {"none": False, "linear": 1, "quadratic": 2, "tangent": "tangent"}
LAWS = ("j2", "chen")
#: NewtonSettings.line_search: None (chosen from the items), True / "residual", "energy", False / "none"
LINE_SEARCHES = (None, True, False, "residual", "energy", "none")
#: NewtonSettings.scale: what rtol is relative to (solver/newton.py)
CONVERGENCE_SCALES = ("initial", "force")
#: NewtonSettings.linear_solver: direct, GMRES + GAMG, GMRES + BoomerAMG, by size (solver/krylov.py)
LINEAR_SOLVERS = ("mumps", "gamg", "hypre", "auto")


def first_increment_error(first, max_cutbacks: int) -> str | None:
    """Why ``first`` (a step's first increment as a fraction of the nominal one) cannot be used, or
    None: it must be 1, 1/2, 1/4, ... with at most ``max_cutbacks`` halvings, so that the increments
    double back onto the nominal load levels."""
    ok = isinstance(first, (int, float)) and not isinstance(first, bool) and \
        any(first == 0.5 ** k for k in range(int(max_cutbacks) + 1))
    if ok:
        return None
    return (f"first = {first!r}: give the first increment as 1, 0.5, 0.25, ... of the nominal one "
            f"(at most max_cutbacks = {max_cutbacks} halvings)")

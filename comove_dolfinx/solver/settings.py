"""Newton's settings: its tolerances, line search, convergence scale, linear solver and PETSc
options, checked when they are made (the convergence test itself: newton.py's module docstring)."""
from __future__ import annotations

from dataclasses import dataclass, field, fields

from ..checks import SettingsError, SolverOptionError, newton_field_error


@dataclass
class NewtonSettings:
    """How Newton iterates and when it has converged (the module docstring; docs/api.md).

    Every field is checked when the settings are made, and again by :class:`Newton`: a value that
    cannot be used raises :class:`~comove_dolfinx.checks.SettingsError` naming it and the fix
    (tolerances finite and >= 0, 0 turning a test off, with rtol or atol > 0; ``max_it`` a whole
    number >= 1; ``divergence`` > 0; ``backtracks`` and ``free_its`` whole numbers >= 0;
    ``energy_eta`` in (0, 1]; ``line_search`` and ``scale`` one of the names below;
    ``petsc_options`` a dict of option names to strings, numbers or True/False). An option value
    that PETSc does not know is refused when the linear solver is set up (solver/linear.py).
    """

    rtol: float = 1e-8
    atol: float = 1e-12
    stol: float = 1e-10
    max_it: int = 25
    divergence: float = 1e12
    backtracks: int = 4
    free_its: int = 5              # corrections taken in full (unless inadmissible) before the Armijo test
    line_search: bool | str | None = None   # None: with contact "residual", with friction (a contact
                                            # with mu > 0) "energy", else off; True/"residual": Armijo
                                            # on ||R||; "energy": du.R(u + a du); False/"none": off
    energy_eta: float = 0.8        # energy search: accept a step once |du.R| <= eta |du.R(u)|
    scale: str = "initial"         # what rtol is relative to: "initial", the largest initial
                                   # residual of the run; "force", ||F_int|| of the iterate
    petsc_options: dict = field(default_factory=dict)   # the linear solver's PETSc options, keys
                                   # without the prefix comove_: {"pc_factor_mat_solver_type": "petsc"}
    linear_solver: str = "auto"    # "mumps", "gamg", "hypre" (GMRES + algebraic multigrid) or "auto" (by size)
                                   # (by the number of dofs): krylov.py; petsc_options come after it
    monitor: object | None = None  # an observer of the iterations (methods iteration, rejected,
                                   # solved: the module docstring), e.g. stability.Recorder

    def __post_init__(self):
        self.check()

    def check(self) -> None:
        """:class:`SettingsError` naming the first field that cannot be used and the fix
        (checks.newton_error: tolerances finite and >= 0, max_it a whole number >= 1, the names
        known, petsc_options a dict of names to values); a Newton checks its settings again."""
        bad = newton_field_error({f.name: getattr(self, f.name) for f in fields(self)}, unknown=False)
        if bad is not None:
            error = SolverOptionError if bad[0] == "petsc_options" else SettingsError
            raise error(f"NewtonSettings: {bad[1]}")

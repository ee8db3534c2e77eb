"""Newton iterations, line searches and the increment loop."""
from ..checks import SettingsError
from ..deprecated import warn_renamed
from .increments import Increment, IncrementalSolver, StepOutcome, StepSettings, _extrapolate
from .newton import Newton, NewtonSettings, Timer

__all__ = ["Increment", "IncrementalSolver", "Newton", "NewtonSettings", "SettingsError", "StepOutcome", "StepSettings", "Timer",
           "_extrapolate"]


def __getattr__(name: str):
    """``RunResult``, the old name of :class:`StepOutcome`, with a DeprecationWarning."""
    if name == "RunResult":
        warn_renamed("comove_dolfinx.solver.RunResult", "StepOutcome")
        return StepOutcome
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")

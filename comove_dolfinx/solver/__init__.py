"""Newton iterations, line searches and the increment loop."""
from ..checks import SettingsError
from .increments import Increment, IncrementalSolver, RunResult, StepSettings, _extrapolate
from .newton import Newton, NewtonSettings, Timer

__all__ = ["Increment", "IncrementalSolver", "Newton", "NewtonSettings", "RunResult", "SettingsError",
           "StepSettings", "Timer", "_extrapolate"]

"""Old names that still work: each use gives a DeprecationWarning that names the new one.

Light (the standard library only), so that the scenes' parameters and the history's tables can use
it before dolfinx is imported.
"""
from __future__ import annotations

import warnings


def warn_renamed(old: str, new: str, stacklevel: int = 3) -> None:
    """A DeprecationWarning: ``old`` is now called ``new`` (``stacklevel`` as for warnings.warn,
    counted from the caller of this function)."""
    warnings.warn(f"{old} is now called {new}", DeprecationWarning, stacklevel=stacklevel)


def renamed_field(old: str, new: str):
    """A class decorator for a dataclass with the field ``new``: its constructor still takes the
    keyword ``old`` and its instances the attribute ``old``, for ``new``, with a DeprecationWarning.
    (``dataclasses.replace(obj, old=...)`` then works too: the old keyword wins.)"""

    def decorate(cls):
        init = cls.__init__
        label = f"{cls.__name__}.{old}"

        def __init__(self, *args, **kwargs):
            if old in kwargs:
                warn_renamed(label, new)
                kwargs[new] = kwargs.pop(old)
            init(self, *args, **kwargs)

        def get(self):
            warn_renamed(label, new)
            return getattr(self, new)

        def set_(self, value):
            warn_renamed(label, new)
            setattr(self, new, value)

        __init__.__doc__, __init__.__wrapped__ = init.__doc__, init
        cls.__init__ = __init__
        setattr(cls, old, property(get, set_, doc=f"The old name of ``{new}`` (deprecated)."))
        return cls
    return decorate

"""Names that an object lends from its parts: ``reaction = delegate("supports.reaction")``.

A class made of collaborating parts (mechanics.model.Model, contact.Contact) keeps the names its
callers use while each part does one job; such a name is a read-only attribute that reads the part's
attribute of the same role, a method, a property or plain data alike.
"""
from __future__ import annotations

import operator


def delegate(path: str, doc: str | None = None) -> property:
    """A read-only attribute whose value is ``self.<path>`` (a dotted path such as
    ``"supports.reaction"``), read anew at each access."""
    part, _, name = path.rpartition(".")
    return property(operator.attrgetter(path),
                    doc=doc or f"``{name}`` of the part ``{part}`` (``self.{path}``), which documents it.")

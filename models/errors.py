"""Errors of the physics package (``models`` never imports ``rigtools``).

::

    ModelError (ValueError)
    └── GeometryError        impossible gear geometry; names the offending parameter
"""

from __future__ import annotations

from typing import Any

__all__ = ["GeometryError", "ModelError"]


class ModelError(ValueError):
    """Base class of errors raised by ``models`` on purpose."""


class GeometryError(ModelError):
    """Impossible or unusable gear geometry.

    Attributes
    ----------
    parameter : str
        The parameter at fault (e.g. ``"pinion.profile_shift"``).
    value : object
        Its value.
    reason : str
        What is wrong and what was expected.
    """

    def __init__(self, parameter: str, value: Any, reason: str) -> None:
        self.parameter = parameter
        self.value = value
        self.reason = reason
        super().__init__(str(self))

    def __str__(self) -> str:
        return f"`{self.parameter}` = {self.value!r}: {self.reason}"

    def __reduce__(self) -> tuple[Any, ...]:
        return (type(self), (self.parameter, self.value, self.reason))

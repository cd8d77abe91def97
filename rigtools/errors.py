"""The rigtools error tree.

Every error rigtools raises on purpose derives from :class:`RigtoolsError`, so a caller (and
the CLI) can tell "rigtools refused this input, here is why" from a bug::

    RigtoolsError
    ├── RecordingFormatError (ValueError)   a file is not what it claims, or is damaged beyond use
    │   └── UnsupportedFormatError          no reader knows this suffix or content
    ├── DbcError (ValueError)               a DBC file does not load, or lacks what a layout needs
    ├── MappingError (ValueError)           a user mapping is malformed or names unknown things
    └── NoDataError                         a file is readable but holds nothing that decodes

Structured fields (``path``, ``position``, ``expected``, ``found``) ride on the exception and the
message is built from them in ``__str__``; ``__reduce__`` keeps them through pickling, so errors
survive Dask and multiprocessing.
"""

from __future__ import annotations

from typing import Any

__all__ = [
    "DbcError",
    "MappingError",
    "NoDataError",
    "RecordingFormatError",
    "RigtoolsError",
    "UnsupportedFormatError",
]


class RigtoolsError(Exception):
    """Base class of every error rigtools raises on purpose."""


class _LocatedError(RigtoolsError):
    """An error about a place in a file: path, position, what was expected, what was found."""

    def __init__(
        self,
        path: Any,
        position: str | int | None = None,
        expected: str | None = None,
        found: str | None = None,
        detail: str | None = None,
    ) -> None:
        self.path = str(path) if path is not None else None
        self.position = position
        self.expected = expected
        self.found = found
        self.detail = detail
        super().__init__(str(self))

    def __str__(self) -> str:
        parts = [self.path or "<input>"]
        if self.position is not None:
            pos = self.position
            parts.append(f"at byte {pos}" if isinstance(pos, int) else f"at {pos}")
        head = " ".join(parts)
        body = []
        if self.expected is not None:
            body.append(f"expected {self.expected}")
        if self.found is not None:
            body.append(f"found {self.found}")
        if self.detail:
            body.append(self.detail)
        return f"{head}: " + ", ".join(body) if body else head

    def __reduce__(self) -> tuple[Any, ...]:
        return (type(self), (self.path, self.position, self.expected, self.found, self.detail))


class RecordingFormatError(_LocatedError, ValueError):
    """A recording file is not in the format expected, or is damaged beyond use."""


class UnsupportedFormatError(RecordingFormatError):
    """No reader knows this file's suffix or content."""


class DbcError(_LocatedError, ValueError):
    """A DBC file does not load, or lacks a message or signal a layout needs."""


class MappingError(_LocatedError, ValueError):
    """A user channel mapping is malformed or names signals, topics or fields that do not exist."""


class NoDataError(_LocatedError):
    """A file reads, but nothing in it decodes into a channel or slow signal."""

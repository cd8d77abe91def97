"""The rigtools error tree.

Every error rigtools raises on purpose derives from :class:`RigtoolsError`, so a caller (and
the CLI) can tell "rigtools refused this input, here is why" from a bug::

    RigtoolsError
    ├── LocatedError                        about a place in a file: path, position, expected, found
    │   ├── RecordingFormatError (ValueError)   a file is not what it claims, or damaged beyond use
    │   │   ├── UnsupportedFormatError          no reader knows this suffix or content
    │   │   ├── PayloadDecodeError              an MCAP payload does not decode under its schema
    │   │   └── SchemaUnusableError             an MCAP schema names a known type but is unusable
    │   ├── DbcError (ValueError)               a DBC does not load, or lacks what a layout needs
    │   ├── MappingError (ValueError)           a user mapping is malformed or names unknown things
    │   ├── NoDataError                         a file is readable but holds nothing that decodes
    │   └── CampaignError (ValueError)          a campaign manifest is malformed (file, line, key)
    ├── SignalError (ValueError)            a signal cannot be analysed as asked (argument, channel)
    │   ├── InsufficientDataError           too short for the requested resolution
    │   └── ConstantSignalError             every valid sample has the same value
    ├── MissingSpeedError (LookupError)     order analysis needs a speed the recording lacks
    └── CalibrationError                    the data cannot be calibrated as asked, naming the
                                            run or key (rigtools.calibration.errors: it carries
                                            the calibration's own fields)

    models.ModelError (ValueError)          the physics refuses its inputs (re-exported here)
    ├── models.GeometryError                impossible gear geometry, naming the parameter
    └── models.thermal.ThermalJamError      the thermal closure jams the mesh

The command line maps every one of these to exit code 3 with its one-line message.

Structured fields (``path``, ``position``, ``expected``, ``found``) ride on the exception and the
message is built from them in ``__str__``; ``__reduce__`` keeps them through pickling, so errors
survive Dask and multiprocessing.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from models.errors import GeometryError, ModelError
from models.thermal.thermoelastic import ThermalJamError

__all__ = [
    "CampaignError",
    "ConstantSignalError",
    "DbcError",
    "GeometryError",
    "InsufficientDataError",
    "LocatedError",
    "MappingError",
    "MissingSpeedError",
    "ModelError",
    "NoDataError",
    "PayloadDecodeError",
    "RecordingFormatError",
    "RigtoolsError",
    "SchemaUnusableError",
    "SignalError",
    "ThermalJamError",
    "UnsupportedFormatError",
]


class RigtoolsError(Exception):
    """Base class of every error rigtools raises on purpose."""


class LocatedError(RigtoolsError):
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


class RecordingFormatError(LocatedError, ValueError):
    """A recording file is not in the format expected, or is damaged beyond use."""


class UnsupportedFormatError(RecordingFormatError):
    """No reader knows this file's suffix or content."""


class DbcError(LocatedError, ValueError):
    """A DBC file does not load, or lacks a message or signal a layout needs."""


class MappingError(LocatedError, ValueError):
    """A user channel mapping is malformed or names signals, topics or fields that do not exist."""


class NoDataError(LocatedError):
    """A file reads, but nothing in it decodes into a channel or slow signal."""


class PayloadDecodeError(RecordingFormatError):
    """A message payload does not decode under its channel's schema.

    The MCAP reader catches it and counts the message as ``decode_error``; it never leaves
    :func:`rigtools.ingest.read`.
    """


class SchemaUnusableError(RecordingFormatError):
    """A schema names a known type but cannot be used (it does not parse, or its fields differ)."""


class CampaignError(LocatedError, ValueError):
    """A campaign manifest is malformed: the message names the file, the line and the key."""


class SignalError(RigtoolsError, ValueError):
    """A signal cannot be analysed as asked.

    Parameters
    ----------
    argument : str
        The argument (or array row, ``"x[2]"``) at fault.
    expected, found : str, optional
        What was expected and what was received; the message reads
        ``` `argument` must be <expected>, was <found>```.
    detail : str, optional
        Free text; alone it reads ``` `argument` <detail>```.
    channel : str, optional
        Channel name, prefixed to the message.
    """

    def __init__(self, argument: str, expected: str | None = None, found: str | None = None,
                 detail: str | None = None, channel: str | None = None) -> None:
        self.argument = argument
        self.expected = expected
        self.found = found
        self.detail = detail
        self.channel = channel
        super().__init__(str(self))

    def __str__(self) -> str:
        head = f"channel {self.channel!r}: " if self.channel is not None else ""
        if self.expected is not None:
            msg = f"`{self.argument}` must be {self.expected}, was {self.found}"
            if self.detail:
                msg += f" ({self.detail})"
        else:
            msg = f"`{self.argument}` {self.detail or 'cannot be analysed'}"
        return head + msg

    def __reduce__(self) -> tuple[Any, ...]:
        return (type(self), (self.argument, self.expected, self.found, self.detail,
                             self.channel))

    def for_channel(self, channel: str) -> SignalError:
        """The same error, naming ``channel``."""
        return type(self)(self.argument, self.expected, self.found, self.detail, channel)


class InsufficientDataError(SignalError):
    """The signal (or its longest valid segment) is too short for the requested resolution."""


class ConstantSignalError(SignalError):
    """Every valid sample has the same value: there is no spectrum to analyse."""


class MissingSpeedError(RigtoolsError, LookupError):
    """Order analysis needs a shaft speed that is absent or covers none of the data.

    Parameters
    ----------
    name : str or None
        The speed signal asked for (``None`` when none was given).
    available : sequence of str
        Slow signals and channels the recording does hold.
    detail : str or None
        What exactly is missing.
    """

    def __init__(
        self, name: str | None, available: Sequence[str] = (), detail: str | None = None
    ) -> None:
        self.name = name
        self.available = tuple(available)
        self.detail = detail
        super().__init__(str(self))

    def __str__(self) -> str:
        what = f"speed signal {self.name!r}" if self.name is not None else "a speed signal"
        msg = f"order analysis needs {what}"
        if self.detail:
            msg += f": {self.detail}"
        if self.available:
            msg += f" (the recording holds: {', '.join(sorted(self.available))})"
        return msg

    def __reduce__(self) -> tuple[Any, ...]:
        return (type(self), (self.name, self.available, self.detail))

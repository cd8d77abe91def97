"""rigtools: faithful ingest, analysis and calibration for spur-gear test rigs."""

from rigtools.errors import (
    DbcError,
    MappingError,
    NoDataError,
    RecordingFormatError,
    RigtoolsError,
    UnsupportedFormatError,
)

__version__ = "0.1.0"

__all__ = [
    "DbcError",
    "MappingError",
    "NoDataError",
    "RecordingFormatError",
    "RigtoolsError",
    "UnsupportedFormatError",
    "__version__",
]

"""The error a report raises when a stage file in OUTDIR cannot be read.

::

    RigtoolsError
    └── LocatedError
        └── ReportInputError (ValueError)   a file of OUTDIR is malformed (file, position, what)

A *missing* file is never an error (the report says what is absent and shows the rest); a file
that is present but malformed is, naming the file and where it breaks.
"""

from __future__ import annotations

from rigtools.errors import LocatedError

__all__ = ["ReportInputError"]


class ReportInputError(LocatedError, ValueError):
    """A file of OUTDIR is present but cannot be used (malformed JSON, not an object, ...).

    Examples
    --------
    >>> str(ReportInputError("out/pipeline.json", "line 3 column 1", "a JSON object",
    ...                      "'Expecting value'"))
    "out/pipeline.json at line 3 column 1: expected a JSON object, found 'Expecting value'"
    """

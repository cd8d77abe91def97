"""The pipeline's error: it cannot start or go on (the output folder, the stages asked for).

::

    RigtoolsError
    └── PipelineError     OUTDIR unusable, stages out of order; names the path or argument

A recording that fails is not an error of the pipeline: it becomes a failed run and the
others go on. A write that fails (a full disk) stays an :class:`OSError` naming the file.
"""

from __future__ import annotations

from typing import Any

from rigtools.errors import RigtoolsError

__all__ = ["PipelineError"]


class PipelineError(RigtoolsError):
    """The pipeline cannot run as asked.

    Parameters
    ----------
    message : str
        Names the path or the argument, the expectation and what was found.
    """

    def __init__(self, message: str) -> None:
        super().__init__(message)
        self.message = message

    def __str__(self) -> str:
        return self.message

    def __reduce__(self) -> tuple[Any, ...]:
        return (type(self), (self.message,))

"""The error a calibration raises when its input cannot give a posterior.

::

    RigtoolsError
    └── CalibrationError (ValueError)   names the run or the [calibration] key at fault

Problems with the ``[calibration]`` block itself (unknown keys, bad priors) are
:class:`rigtools.errors.CampaignError` with the line; :class:`CalibrationError` is for what
only shows when the block meets the data: no usable run, priors that exclude every run's
peaks, a campaign whose runs all jam, too few walkers for the free parameters. The command
line maps it to exit code 3 like every :class:`~rigtools.errors.RigtoolsError`.
"""

from __future__ import annotations

from typing import Any

from rigtools.errors import RigtoolsError

__all__ = ["CalibrationError"]


class CalibrationError(RigtoolsError, ValueError):
    """A calibration cannot run on this input.

    Parameters
    ----------
    detail : str
        What is wrong and what would fix it.
    run : str, optional
        The run at fault.
    key : str, optional
        The configuration key at fault (``calibration.priors.backlash``).

    Examples
    --------
    >>> str(CalibrationError("no natural-frequency rows", run="LS9-90C"))
    "run 'LS9-90C': no natural-frequency rows"
    """

    def __init__(self, detail: str, *, run: str | None = None, key: str | None = None) -> None:
        self.detail = detail
        self.run = run
        self.key = key
        super().__init__(str(self))

    def __str__(self) -> str:
        if self.run is not None:
            return f"run {self.run!r}: {self.detail}"
        if self.key is not None:
            return f"{self.key}: {self.detail}"
        return self.detail

    def __reduce__(self) -> tuple[Any, ...]:
        return (_rebuild, (self.detail, self.run, self.key))


def _rebuild(detail: str, run: str | None, key: str | None) -> CalibrationError:
    return CalibrationError(detail, run=run, key=key)

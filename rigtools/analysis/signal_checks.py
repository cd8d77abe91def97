"""Errors and argument checks shared by the spectral analyses.

:class:`SignalError` and its subclasses :class:`InsufficientDataError` and
:class:`ConstantSignalError`, the ``Window``/``Detrend``/``Average`` argument types, the
default window length, and the private validation helpers (signal, sample rate, mask, window
length, overlap, detrend, band, axis) used by the Welch, RMS and recording analyses.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any, Literal

import numpy as np

from rigtools.errors import RigtoolsError

#: Window length used when neither ``nperseg`` nor ``resolution_Hz`` is given (samples).
DEFAULT_NPERSEG = 4096

Window = str | tuple[Any, ...] | np.ndarray
Detrend = Literal["constant", "linear", False] | Callable[[np.ndarray], np.ndarray]
Average = Literal["mean", "median"]


# --------------------------------------------------------------------------------------------
# errors


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


# --------------------------------------------------------------------------------------------
# validation helpers


def _as_signal(x: Any, axis: int) -> np.ndarray:
    """``x`` as float32/float64 with the time axis last."""
    a = np.asarray(x)
    if a.ndim == 0:
        raise SignalError("x", "an array with a time axis", "a scalar")
    if np.iscomplexobj(a):
        raise SignalError("x", "real", f"complex ({a.dtype})")
    if a.dtype not in (np.float32, np.float64):
        a = a.astype(np.float64)
    try:
        return np.moveaxis(a, axis, -1)
    except np.exceptions.AxisError as e:
        raise SignalError("axis", f"in [-{a.ndim}, {a.ndim})", str(axis)) from e


def _check_fs(fs: float) -> float:
    fs = float(fs)
    if not np.isfinite(fs) or fs <= 0:
        raise SignalError("fs", "a finite positive sample rate (Hz)", repr(fs))
    return fs


def _check_valid(valid: Any, x: np.ndarray, axis: int) -> np.ndarray | None:
    """The mask, time axis last, shape ``(n,)`` or ``x.shape``; None when every sample is valid.

    Without a mask, the finite samples are the valid ones. With one, samples marked valid must
    be finite.
    """
    n = x.shape[-1]
    if valid is None:
        if np.isfinite(np.sum(x, dtype=np.float64)):
            return None
        v = np.isfinite(x)
        return None if v.all() else v
    v = np.asarray(valid)
    if v.dtype != np.bool_:
        raise SignalError("valid", "a boolean mask", f"dtype {v.dtype}")
    if v.ndim > 1 or v.shape == x.shape:
        v = np.moveaxis(v, axis, -1) if v.ndim > 1 else v
    if v.shape not in ((n,), x.shape):
        raise SignalError("valid", f"of shape ({n},) or {x.shape} (time axis last)",
                          str(v.shape))
    if v.all():
        if not np.isfinite(np.sum(x, dtype=np.float64)) and not np.isfinite(x).all():
            raise SignalError("x", "finite where `valid` is True", "NaN or inf there")
        return None
    if not np.isfinite(np.sum(np.where(v, x, 0.0), dtype=np.float64)) and not np.isfinite(
            np.where(v, x, 0.0)).all():
        raise SignalError("x", "finite where `valid` is True", "NaN or inf there")
    return v


def _resolve_nperseg(nperseg: int | None, resolution_Hz: float | None, fs: float) -> int:
    if nperseg is not None and resolution_Hz is not None:
        raise SignalError("resolution_Hz", "None when `nperseg` is given", repr(resolution_Hz))
    if resolution_Hz is not None:
        r = float(resolution_Hz)
        if not np.isfinite(r) or r <= 0 or r > fs / 2:
            raise SignalError("resolution_Hz", f"in (0, fs/2={fs / 2:g}] Hz", repr(resolution_Hz))
        return int(np.ceil(fs / r - 1e-9))
    if nperseg is None:
        return DEFAULT_NPERSEG
    if int(nperseg) != nperseg or nperseg < 2:
        raise SignalError("nperseg", "an integer >= 2", repr(nperseg))
    return int(nperseg)


def _check_noverlap(noverlap: int | None, nperseg: int) -> int:
    if noverlap is None:
        return nperseg // 2
    if int(noverlap) != noverlap or not 0 <= noverlap < nperseg:
        raise SignalError("noverlap", f"an integer in [0, nperseg={nperseg})", repr(noverlap))
    return int(noverlap)


def _check_detrend(detrend: Any) -> Any:
    if detrend is False or callable(detrend) or detrend in ("constant", "linear"):
        return detrend
    raise SignalError("detrend", "'constant', 'linear', False or a callable", repr(detrend))


def _check_band(band_Hz: Sequence[float] | None, fs: float) -> tuple[float, float]:
    if band_Hz is None:
        return (0.0, fs / 2)
    try:
        lo, hi = (float(b) for b in band_Hz)
    except (TypeError, ValueError) as e:
        raise SignalError("band_Hz", "a pair (f_lo, f_hi) in Hz", repr(band_Hz)) from e
    if not (0.0 <= lo < hi) or np.isnan(hi):
        raise SignalError("band_Hz", "0 <= f_lo < f_hi (Hz)", repr(band_Hz))
    return (lo, min(hi, fs / 2))


def _row_name(i: tuple[Any, ...], batch: tuple[int, ...]) -> str:
    return "x" if not batch else "x[" + ", ".join(str(j) for j in i) + "]"


def _norm_axis(axis: int, ndim: int) -> int:
    """``axis`` in [0, ndim) (-1 when ndim is 0)."""
    return int(axis) % ndim if ndim else -1

"""Argument types and the argument checks shared by the analyses of :mod:`rigtools.analysis`.

Validate once, at the boundary (STYLE.md 3.7): each check is named after the argument it
checks, returns the normalised value and names the argument in backticks with what was
expected and what was received. Two families:

* the spectral analyses (Welch, RMS, peaks, a recording's channels) raise
  :class:`~rigtools.errors.SignalError`: :func:`as_signal`, :func:`check_fs`,
  :func:`check_valid`, :func:`resolve_nperseg`, :func:`check_noverlap`, :func:`check_detrend`,
  :func:`check_band`, :func:`check_not_constant`, :func:`check_response`, with
  :func:`row_name` and :func:`norm_axis`;
* the speed and order analyses (speed profiles, tacho, angular resampling, order spectra)
  raise :class:`ValueError` (and :class:`~rigtools.errors.MissingSpeedError` for a missing
  speed): :func:`as_1d`, :func:`check_positive`, :func:`check_sample_rate`,
  :func:`check_valid_1d`, :func:`check_int`, :func:`check_speed`, :func:`check_harmonics`,
  :func:`check_quantity`.

Also the argument types ``Window``, ``Detrend``, ``Average``, ``Response``, ``Quantity`` and the
default Welch window length.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any, Final, Literal

import numpy as np

from rigtools.analysis.speed_types import SpeedProfile
from rigtools.errors import ConstantSignalError, MissingSpeedError, SignalError

__all__ = [
    "DEFAULT_NPERSEG",
    "RESPONSE_POWER",
    "Average",
    "Detrend",
    "Quantity",
    "Response",
    "Window",
    "as_1d",
    "as_signal",
    "check_band",
    "check_detrend",
    "check_fs",
    "check_harmonics",
    "check_int",
    "check_not_constant",
    "check_noverlap",
    "check_positive",
    "check_quantity",
    "check_response",
    "check_sample_rate",
    "check_speed",
    "check_valid",
    "check_valid_1d",
    "norm_axis",
    "resolve_nperseg",
    "row_name",
]

#: Window length used when neither ``nperseg`` nor ``resolution_Hz`` is given (samples).
DEFAULT_NPERSEG = 4096

Window = str | tuple[Any, ...] | np.ndarray
Detrend = Literal["constant", "linear", False] | Callable[[np.ndarray], np.ndarray]
Average = Literal["mean", "median"]
#: The response a single-DOF fit assumes: displacement, velocity or acceleration.
Response = Literal["displacement", "velocity", "acceleration"]
#: Power p of the frequency ratio in the SDOF PSD shape, per response.
RESPONSE_POWER: Final[dict[str, int]] = {"displacement": 0, "velocity": 1, "acceleration": 2}
#: What an order analysis reports: the input as given, or converted to displacement.
Quantity = Literal["acceleration", "displacement"]


# --------------------------------------------------------------------------------------------
# spectral analyses (SignalError)


def as_signal(x: Any, axis: int) -> np.ndarray:
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


def check_fs(fs: float) -> float:
    """The sample rate ``fs`` (Hz) as a float when finite and > 0."""
    fs = float(fs)
    if not np.isfinite(fs) or fs <= 0:
        raise SignalError("fs", "a finite positive sample rate (Hz)", repr(fs))
    return fs


def check_valid(valid: Any, x: np.ndarray, axis: int) -> np.ndarray | None:
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


def resolve_nperseg(nperseg: int | None, resolution_Hz: float | None, fs: float) -> int:
    """Window length (samples): ``nperseg``, or ``ceil(fs / resolution_Hz)``, or the default."""
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


def check_noverlap(noverlap: int | None, nperseg: int) -> int:
    """Overlap (samples) in ``[0, nperseg)``; default half a window."""
    if noverlap is None:
        return nperseg // 2
    if int(noverlap) != noverlap or not 0 <= noverlap < nperseg:
        raise SignalError("noverlap", f"an integer in [0, nperseg={nperseg})", repr(noverlap))
    return int(noverlap)


def check_detrend(detrend: Any) -> Any:
    """``detrend`` when it is ``'constant'``, ``'linear'``, False or a callable."""
    if detrend is False or callable(detrend) or detrend in ("constant", "linear"):
        return detrend
    raise SignalError("detrend", "'constant', 'linear', False or a callable", repr(detrend))


def check_band(band_Hz: Sequence[float] | None, fs: float) -> tuple[float, float]:
    """``(f_lo, f_hi)`` (Hz) with ``0 <= f_lo < f_hi``, ``f_hi`` capped at ``fs / 2``.

    None gives the full band ``(0, fs / 2)``.
    """
    if band_Hz is None:
        return (0.0, fs / 2)
    try:
        lo, hi = (float(b) for b in band_Hz)
    except (TypeError, ValueError) as e:
        raise SignalError("band_Hz", "a pair (f_lo, f_hi) in Hz", repr(band_Hz)) from e
    if not (0.0 <= lo < hi) or np.isnan(hi):
        raise SignalError("band_Hz", "0 <= f_lo < f_hi (Hz)", repr(band_Hz))
    return (lo, min(hi, fs / 2))


def row_name(i: tuple[Any, ...], batch: tuple[int, ...]) -> str:
    """How a row of a batch is named in messages: ``"x"`` or ``"x[2, 0]"``."""
    return "x" if not batch else "x[" + ", ".join(str(j) for j in i) + "]"


def norm_axis(axis: int, ndim: int) -> int:
    """``axis`` in [0, ndim) (-1 when ndim is 0)."""
    return int(axis) % ndim if ndim else -1


def check_not_constant(x: np.ndarray, mask: np.ndarray | None) -> None:
    """Raise :class:`ConstantSignalError` for the first row of ``x`` whose valid samples are equal.

    ``x`` has the time axis last; ``mask`` is None, ``(n,)`` or ``x.shape``.
    """
    batch = x.shape[:-1]
    x2 = x.reshape(-1, x.shape[-1])
    if mask is None:
        hi, lo = x2.max(axis=-1), x2.min(axis=-1)
    else:
        m2 = np.broadcast_to(mask, x.shape).reshape(x2.shape)
        hi = np.where(m2, x2, -np.inf).max(axis=-1)
        lo = np.where(m2, x2, np.inf).min(axis=-1)
    for i in np.flatnonzero(hi == lo):
        idx = np.unravel_index(int(i), batch)
        nv = int(x2.shape[-1] if mask is None else np.count_nonzero(
            np.broadcast_to(mask, x.shape).reshape(x2.shape)[i]))
        raise ConstantSignalError(
            row_name(idx, batch), detail=f"is constant (all {nv} valid samples equal "
            f"{float(hi[i])!r}): its spectrum is zero, no peak or damping can be estimated")


def check_response(response: str) -> int:
    """The power p of ``response`` (:data:`RESPONSE_POWER`); SignalError for another value."""
    if response not in RESPONSE_POWER:
        raise SignalError("response", "'displacement', 'velocity' or 'acceleration'",
                          repr(response))
    return RESPONSE_POWER[response]


# --------------------------------------------------------------------------------------------
# speed and order analyses (ValueError)


def as_1d(name: str, x: Any) -> np.ndarray:
    """``x`` as a one-dimensional float64 array; ValueError naming ``name`` otherwise."""
    a = np.asarray(x, dtype=np.float64)
    if a.ndim != 1:
        raise ValueError(f"`{name}` must be one-dimensional, has shape {a.shape}")
    return a


def check_positive(name: str, value: float) -> float:
    """``value`` as a float when it is finite and > 0; ValueError naming ``name`` otherwise."""
    v = float(value)
    if not np.isfinite(v) or v <= 0.0:
        raise ValueError(f"`{name}` must be a positive finite number, was {value!r}")
    return v


def check_sample_rate(sample_rate_Hz: float) -> float:
    """``sample_rate_Hz`` (Hz) when finite and > 0."""
    return check_positive("sample_rate_Hz", sample_rate_Hz)


def check_valid_1d(valid: Any, n: int) -> np.ndarray:
    """Per-sample validity of shape ``(n,)`` (all True when ``valid`` is None)."""
    if valid is None:
        return np.ones(n, dtype=bool)
    v = np.asarray(valid, dtype=bool)
    if v.shape != (n,):
        raise ValueError(f"`valid` must have shape ({n},) like the values, has {v.shape}")
    return v


def check_int(name: str, value: Any, minimum: int = 1) -> int:
    """``value`` as an int when it is an integer >= ``minimum`` (not a bool)."""
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < minimum:
        raise ValueError(f"`{name}` must be an integer >= {minimum}, was {value!r}")
    return int(value)


def check_speed(speed: SpeedProfile | None) -> SpeedProfile:
    """``speed`` when it is a :class:`SpeedProfile`; MissingSpeedError when None."""
    if speed is None:
        raise MissingSpeedError(None, detail="`speed` is None; build one with "
                                "speed_from_slow_signal, speed_from_tacho or speed_profile")
    if not isinstance(speed, SpeedProfile):
        raise TypeError(f"`speed` must be a SpeedProfile, was {type(speed).__name__}")
    return speed


def check_harmonics(harmonics: int | Sequence[int]) -> tuple[int, ...]:
    """Harmonic numbers: a count ``n`` (1 .. n) or a sequence of integers >= 1."""
    if isinstance(harmonics, (int, np.integer)):
        n = check_int("harmonics", harmonics)
        return tuple(range(1, n + 1))
    hs = tuple(int(h) for h in harmonics)
    if not hs or any(h < 1 or isinstance(h, bool) for h in harmonics):
        raise ValueError(f"`harmonics` must be a count or a sequence of integers >= 1, "
                         f"was {harmonics!r}")
    return hs


def check_quantity(quantity: str) -> str:
    """``quantity`` when it is ``"acceleration"`` or ``"displacement"``."""
    if quantity not in ("acceleration", "displacement"):
        raise ValueError(f"`quantity` must be 'acceleration' or 'displacement', was {quantity!r}")
    return quantity

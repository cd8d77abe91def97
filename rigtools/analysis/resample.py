"""Angular resampling: a Kaiser-windowed sinc kernel onto a uniform shaft-angle grid.

The resampler behind :mod:`rigtools.analysis.orders` (see its docstring for the method and
references): :func:`resample_to_angle` returns an :class:`AngleSignal`.
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from rigtools.analysis.resample_kernel import kaiser_sinc_apply, kaiser_table
from rigtools.analysis.signal_checks import (
    as_1d,
    check_int,
    check_sample_rate,
    check_speed,
    check_valid_1d,
)
from rigtools.analysis.speed_types import SpeedProfile
from rigtools.analysis.windows import true_runs
from rigtools.errors import MissingSpeedError

__all__ = ["RESAMPLER_PASSBAND", "AngleSignal", "resample_to_angle"]


#: Fraction of ``min(fs, P f)`` up to which the angular resampler is flat (within ~1e-5).
RESAMPLER_PASSBAND = 0.42
_ZEROS = 32.0  # zero crossings of the kernel on each side
_BETA = 10.0  # Kaiser shape
_CUTOFF = 0.94  # kernel cutoff, fraction of the Nyquist frequency of min(fs, P f)


# --- results ----------------------------------------------------------------------------------
@dataclass(frozen=True, eq=False)
class AngleSignal:
    """A signal resampled at uniform increments of shaft angle.

    Attributes
    ----------
    angle_rev : numpy.ndarray
        Shaft angle of each sample (rev), ``j / samples_per_rev`` for integers ``j``; the origin
        is arbitrary (the start of the speed record).
    values : numpy.ndarray
        Resampled values (unit of the input).
    time_s : numpy.ndarray
        Time of each sample (s, logger clock).
    speed_rpm : numpy.ndarray
        Shaft speed at each sample (rpm).
    run : numpy.ndarray
        Number of the gap-free run each sample belongs to (int); ``j`` is consecutive within
        a run.
    run_end : tuple of str
        Per run, why it ended: ``"gap"`` (invalid samples follow), ``"speed_unknown"`` (the
        speed is unknown or too low next) or ``"end"``.
    samples_per_rev : int
        Angular samples per revolution ``P``.
    input_rate_Hz : float
        Sample rate of the input (Hz), which bounds the usable orders at high speed.
    dropped : Mapping
        Input samples not resampled, by reason: ``"gap"``, ``"speed_unknown"``, ``"edge"``
        (within a kernel half-width of a gap or of the record's ends).
    """

    angle_rev: np.ndarray
    values: np.ndarray
    time_s: np.ndarray
    speed_rpm: np.ndarray
    run: np.ndarray
    run_end: tuple[str, ...]
    samples_per_rev: int
    input_rate_Hz: float
    dropped: Mapping[str, int] = field(default_factory=dict)

    @property
    def index(self) -> np.ndarray:
        """Angle sample numbers ``j`` (int)."""
        return np.rint(self.angle_rev * self.samples_per_rev).astype(np.int64)


# --- angular resampling -----------------------------------------------------------------------
def resample_to_angle(
    x: np.ndarray,
    sample_rate_Hz: float,
    speed: SpeedProfile | None,
    *,
    samples_per_rev: int,
    start_time_s: float = 0.0,
    valid: np.ndarray | None = None,
    min_speed_rpm: float = 1.0,
) -> AngleSignal:
    """Resample a uniformly sampled signal at uniform increments of shaft angle.

    See the module docstring for the angle integration and the Kaiser-windowed-sinc kernel.

    Parameters
    ----------
    x : array_like
        Signal (any unit), uniformly sampled, NaN allowed where ``valid`` is False.
    sample_rate_Hz : float
        Its sample rate (Hz).
    speed : SpeedProfile
        Shaft speed; ``None`` raises :class:`MissingSpeedError`.
    samples_per_rev : int
        Angular samples per revolution ``P``; orders up to ``RESAMPLER_PASSBAND * P`` are kept.
    start_time_s : float
        Time of ``x[0]`` on the speed's clock (s).
    valid : array_like of bool, optional
        Per-sample validity (``Channel.valid``); default all finite samples.
    min_speed_rpm : float
        Below this speed the angle is treated as unknown (rpm).

    Returns
    -------
    AngleSignal

    Raises
    ------
    MissingSpeedError
        When ``speed`` is None or covers no sample of ``x``.
    """
    speed = check_speed(speed)
    xs = as_1d("x", x)
    fs = check_sample_rate(sample_rate_Hz)
    p = check_int("samples_per_rev", samples_per_rev, 4)
    ok = check_valid_1d(valid, xs.size) & np.isfinite(xs)
    n = xs.size
    t = float(start_time_s) + np.arange(n) / fs
    f = speed.frequency_Hz_at(t)
    known = np.isfinite(f) & (f * 60.0 >= float(min_speed_rpm))
    if not np.any(known):
        raise MissingSpeedError(
            None, detail=(f"the speed ({speed.source}) is known over "
                          f"{_cover_text(speed)}, the signal spans {t[0]:.6g} to "
                          f"{t[-1] if n else t[0]:.6g} s; no sample has a known speed "
                          f">= {min_speed_rpm} rpm"))
    # 1. shaft angle, per stretch of known speed; each stretch starts on a whole revolution
    theta = np.full(n, np.nan)
    offset = 0.0
    for a, b in true_runs(known):
        inc = 0.5 * (f[a + 1:b] + f[a:b - 1]) / fs
        theta[a:b] = offset + np.r_[0.0, np.cumsum(inc)]
        offset = float(np.ceil(theta[b - 1])) + 1.0
    usable = ok & known
    dropped: Counter[str] = Counter()
    dropped["gap"] = int(np.count_nonzero(~ok))
    dropped["speed_unknown"] = int(np.count_nonzero(ok & ~known))
    rho_all = np.minimum(1.0, p * np.where(known, f, 0.0) / fs)
    ang, val, tim, spd, run = [], [], [], [], []
    run_end: list[str] = []
    window = kaiser_table(_BETA)
    for a, b in true_runs(usable):
        th = theta[a:b]
        j0 = int(np.ceil(th[0] * p - 1e-9))
        j1 = int(np.floor(th[-1] * p + 1e-9))
        if j1 < j0:
            dropped["edge"] += b - a
            continue
        j = np.arange(j0, j1 + 1)
        u = np.interp(j / p, th, np.arange(b - a, dtype=np.float64))
        rho = np.interp(u, np.arange(b - a, dtype=np.float64), rho_all[a:b])
        k = np.ceil(_ZEROS / rho)
        fl = np.floor(u)
        keep = (fl - k + 1 >= 0) & (fl + k <= b - a - 1)
        if not np.any(keep):
            dropped["edge"] += b - a
            continue
        reason = "end" if b == n else ("speed_unknown" if ok[b] else "gap")
        # the kept outputs are consecutive (the kernel width changes slowly); guard anyway
        pieces = true_runs(keep)
        covered = 0
        for q, (ka, kb) in enumerate(pieces):
            uu = u[ka:kb]
            ang.append(j[ka:kb] / p)
            val.append(kaiser_sinc_apply(np.ascontiguousarray(xs[a:b]), uu, rho[ka:kb], _ZEROS,
                                         _CUTOFF, window))
            tim.append(t[0] + (a + uu) / fs)
            spd.append(60.0 * np.interp(uu, np.arange(b - a, dtype=np.float64), f[a:b]))
            run.append(np.full(kb - ka, len(run_end), dtype=np.int64))
            run_end.append(reason if q == len(pieces) - 1 else "edge")
            covered += int(np.ceil(uu[-1]) - np.floor(uu[0]))
        dropped["edge"] += max(0, (b - a) - covered)

    def cat(parts: list[np.ndarray], dtype: Any = np.float64) -> np.ndarray:
        return np.concatenate(parts) if parts else np.empty(0, dtype=dtype)

    return AngleSignal(
        angle_rev=cat(ang), values=cat(val), time_s=cat(tim), speed_rpm=cat(spd),
        run=cat(run, np.int64), run_end=tuple(run_end), samples_per_rev=p, input_rate_Hz=fs,
        dropped={k: v for k, v in dropped.items() if v},
    )


def _cover_text(speed: SpeedProfile) -> str:
    spans = [f"{a:.6g} to {b:.6g} s" for a, b in
             zip(speed.cover_start_s[:3], speed.cover_stop_s[:3], strict=True)]
    more = f" and {speed.n_segments - 3} more" if speed.n_segments > 3 else ""
    return ", ".join(spans) + more

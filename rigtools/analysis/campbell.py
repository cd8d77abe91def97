"""Campbell data: order and frequency waterfalls along a run-up.

See :mod:`rigtools.analysis.orders` for the method and references.
"""

from __future__ import annotations

import numpy as np

from rigtools.analysis.order_spectra import (
    Campbell,
    block_amplitudes,
    check_samples_per_rev,
    order_window,
    order_windows,
)
from rigtools.analysis.signal_checks import (
    Quantity,
    as_1d,
    check_int,
    check_positive,
    check_quantity,
    check_sample_rate,
    check_speed,
    check_valid_1d,
)
from rigtools.analysis.speed_types import SpeedProfile

__all__ = ["Campbell", "frequency_campbell", "order_campbell"]


# --- results ----------------------------------------------------------------------
def order_campbell(
    x: np.ndarray,
    sample_rate_Hz: float,
    speed: SpeedProfile | None,
    *,
    start_time_s: float = 0.0,
    valid: np.ndarray | None = None,
    max_order: float = 64.0,
    revs_per_window: int = 8,
    hop_revs: int | None = None,
    samples_per_rev: int | None = None,
    window: str = "hann",
    quantity: Quantity = "acceleration",
    highpass_Hz: float = 10.0,
    highpass_order: int = 4,
    min_speed_rpm: float = 1.0,
) -> Campbell:
    """Order spectra in windows of whole revolutions along a run (order-axis waterfall).

    Parameters
    ----------
    x : array_like
        Signal (m/s^2 for ``quantity="displacement"``), uniformly sampled.
    sample_rate_Hz : float
        Sample rate (Hz).
    speed : SpeedProfile
        Shaft speed (``None`` raises :class:`MissingSpeedError`).
    start_time_s : float
        Time of ``x[0]`` (s).
    valid : array_like of bool, optional
        Per-sample validity.
    max_order : float
        Highest order kept (columns).
    revs_per_window, hop_revs : int
        Window length and step (rev); default step half a window.
    samples_per_rev : int, optional
        Angular sampling; default the smallest power of two that keeps ``max_order`` inside
        the passband.
    window : str
        Window name.
    quantity : {"acceleration", "displacement"}
        Spectra as given, or converted to displacement (m) with the high pass.
    highpass_Hz, highpass_order
        High pass of the displacement conversion.
    min_speed_rpm : float
        Below this the angle is treated as unknown (rpm).

    Returns
    -------
    Campbell
        ``axis_name == "order"``; rows are windows, windows meeting a gap are dropped and
        counted in ``dropped``.
    """
    mo = check_positive("max_order", max_order)
    p = check_samples_per_rev(samples_per_rev, mo)
    camp, _, _ = order_windows(
        x, sample_rate_Hz, speed, start_time_s=start_time_s, valid=valid,
        revs_per_window=revs_per_window, hop_revs=hop_revs, samples_per_rev=p, window=window,
        quantity=check_quantity(quantity), highpass_Hz=highpass_Hz,
        highpass_order=highpass_order, max_order=mo, min_speed_rpm=min_speed_rpm)
    return camp


# --- plain (time-frequency) waterfall ---------------------------------------------------------
def frequency_campbell(
    x: np.ndarray,
    sample_rate_Hz: float,
    speed: SpeedProfile | None = None,
    *,
    start_time_s: float = 0.0,
    valid: np.ndarray | None = None,
    nperseg: int = 4096,
    noverlap: int | None = None,
    window: str = "hann",
) -> Campbell:
    """Amplitude spectra of fixed-length time frames along a run (frequency-axis waterfall).

    No order tracking: an order whose frequency moves during a frame smears over many bins.
    Frames containing an invalid sample are dropped and counted (``dropped["gap"]``).

    Parameters
    ----------
    x : array_like
        Signal, uniformly sampled.
    sample_rate_Hz : float
        Sample rate (Hz).
    speed : SpeedProfile, optional
        When given, each row carries its frame's mean speed (rpm); otherwise NaN.
    start_time_s : float
        Time of ``x[0]`` (s).
    valid : array_like of bool, optional
        Per-sample validity.
    nperseg : int
        Frame length (samples).
    noverlap : int, optional
        Overlap (samples); default half a frame.
    window : str
        Window name; amplitudes are coherent-gain corrected (a sine of amplitude ``A`` on a
        bin reads ``A``).

    Returns
    -------
    Campbell
        ``axis_name == "frequency_Hz"``.
    """
    xs = as_1d("x", x)
    fs = check_sample_rate(sample_rate_Hz)
    nps = check_int("nperseg", nperseg, 2)
    if nps > xs.size:
        raise ValueError(f"`nperseg` must be <= len(x)={xs.size}, was {nps}")
    nov = nps // 2 if noverlap is None else check_int("noverlap", noverlap, 0)
    if nov >= nps:
        raise ValueError(f"`noverlap` must be < nperseg={nps}, was {nov}")
    ok = check_valid_1d(valid, xs.size) & np.isfinite(xs)
    step = nps - nov
    starts = np.arange(0, xs.size - nps + 1, step)
    bad = np.r_[0, np.cumsum(~ok)]
    good = (bad[starts + nps] - bad[starts]) == 0
    dropped = {"gap": int(np.count_nonzero(~good))} if not np.all(good) else {}
    starts = starts[good]
    w = order_window(window, nps)
    freq = np.fft.rfftfreq(nps, 1.0 / fs)
    if starts.size:
        frames = np.stack([xs[s:s + nps] for s in starts])
        amp = block_amplitudes(frames, w)
    else:
        amp = np.empty((0, freq.size))
    t_c = float(start_time_s) + (starts + nps / 2) / fs
    if speed is not None:
        sp = check_speed(speed)
        t_all = float(start_time_s) + np.arange(xs.size) / fs
        rpm_all = sp.rpm_at(t_all)
        rpm = np.array([np.mean(rpm_all[s:s + nps]) for s in starts])
    else:
        rpm = np.full(starts.size, np.nan)
    return Campbell(t_c, rpm, freq, "frequency_Hz", amp, "acceleration", dropped)

r"""The arms rows of the observations table: mesh-harmonic amplitudes per speed step or window.

For each accelerometer channel of a run with ``[sensors] speed``, :func:`arms_rows` gives one
``arms`` row per speed step (``segment = "step"``,
:func:`~rigtools.analysis.orders.step_levels_from_recording`) or, when the speed has no
plateau (a ramped run-up), one per window of ``revs_per_block`` revolutions along the ramp
(``segment = "ramp"``, :func:`~rigtools.analysis.orders.run_up_curve_from_recording`): the
speed, the mesh frequency, the amplitudes of the mesh harmonics :data:`HARMONICS` and
:math:`A_{rms} = \sqrt{A_1^2 + A_2^2 + A_3^2}`, flagged ``low_snr`` when the weakest harmonic
stands less than ``[analysis] low_snr_dB`` over the order-spectrum floor (same bandwidth).
The other rows of a run are made by :mod:`rigtools.campaign.observe`.

Readout band along a ramp
-------------------------
A speed step's harmonics are stationary, and the three Hann bins about each order
(``band_bins = 1``) hold all their power. Along a ramp a harmonic's amplitude and phase change
within the window (through a resonance narrower than the window's span of mesh frequency, the
super-harmonic peaks at ``f_n / 2`` and ``f_n / 3`` most), and that modulation puts power into
the neighbouring bins: read over three bins, the window's value falls short of the
window-weighted mean power that the run-up calibration models
(:mod:`rigtools.calibration.runup_data`, "Windows"). Ramp windows are therefore read over
:data:`RAMP_BAND_BINS` = 3 bins a side (fewer when a window has fewer revolutions, so that the
first shaft-order sideband, ``revs_per_block`` bins off, stays outside). Measured against
the exact angle-weighted window mean of a quasi-static resonance of harmonic 1 crossed by a
linear ramp (8-revolution windows spanning 3.4 half-power widths at ``zeta = 0.01``, 1.7 at
0.02): the peak window read 5.7 % / 1.4 % low over three bins, 1.0 % / 0.07 % over five,
0.14 % / 0.00 % over seven. On the demo's run-up (its VVMS truth's noiseless DTE acceleration
along the 2 x 16 s ramp, against the steady sweep's window means), the windows at the
third-harmonic super-harmonic peak read 1.6 % (up) and 2.2 % (down) low over three bins,
within 1 % over seven; the two jump windows differ from the steady sweep by 5-7 % and 14-26 %
whatever the band: the ramp's own transient there.

Direction
---------
Every arms row that holds a value says which way the speed goes there (``direction``: ``"up"``,
``"down"`` or ``"hold"``; null on failed rows), so the run-up and run-down parts of a recording
can be compared apart (jumps, hysteresis). Along a ramp (:func:`ramp_directions`) the slope of
:math:`\ln f_m` against time is fitted by least squares over each window and its
:data:`DIRECTION_NEIGHBOURS` neighbours either side (a noisy speed signal averages out over
them); the row is ``"hold"`` when that slope changes the mesh frequency by less than
``[analysis] step_rel_tolerance`` over the span of those windows, or lies within twice its
standard error, else ``"up"`` or ``"down"`` by its sign. Speed steps (:func:`step_directions`)
take the sign of the change from the previous step (the first step that of the change to the
next, ``"up"`` when it is the only one), ``"hold"`` under the same relative tolerance.
"""

from __future__ import annotations

import math
from typing import Any, Final

import numpy as np

from models.geometry import speed_rpm_from_mesh_frequency
from rigtools.analysis.orders import (
    RunUpCurve,
    StepLevels,
    run_up_curve_from_recording,
    step_levels_from_recording,
)
from rigtools.analysis.speed import SpeedProfile, SpeedStep
from rigtools.campaign.manifest import Campaign
from rigtools.campaign.observation_rows import ACCEL_TO_M_S2, finite_or_none, row_status
from rigtools.errors import RigtoolsError
from rigtools.ingest.recording import Recording

__all__ = ["DIRECTIONS", "DIRECTION_NEIGHBOURS", "HARMONICS", "RAMP_BAND_BINS", "arms_rows",
           "ramp_band_bins", "ramp_directions", "step_directions"]

#: The mesh harmonics whose amplitudes make Arms.
HARMONICS: Final = (1, 2, 3)
#: Half-width (bins) of the harmonic readout band of a ramp window (module notes).
RAMP_BAND_BINS: Final = 3
#: The values of the ``direction`` column (besides null).
DIRECTIONS: Final = ("up", "down", "hold")
#: Ramp windows either side of a window over which the slope of the speed is fitted.
DIRECTION_NEIGHBOURS: Final = 3
#: A ramp window's slope must exceed this many standard errors of its fit to give a direction.
_SLOPE_SIGMAS: Final = 2.0
#: Labels either side of a ramp window whose majority overrules a label alone among them.
_MODE_HALF_WIDTH: Final = 2


def ramp_band_bins(revs_per_window: int) -> int:
    """Readout half-width (bins) of a ramp window of ``revs_per_window`` revolutions.

    :data:`RAMP_BAND_BINS`, narrowed to keep the first shaft-order sideband (``revs`` bins
    off the mesh order) outside the band; at least 1 (module notes).
    """
    return max(1, min(RAMP_BAND_BINS, int(revs_per_window) - 1))


def ramp_directions(time_s: np.ndarray, mesh_frequency_Hz: np.ndarray, rel_tolerance: float,
                    *, neighbours: int = DIRECTION_NEIGHBOURS) -> np.ndarray:
    r"""Which way the speed goes at each window along a ramp.

    Parameters
    ----------
    time_s : array_like
        Centre times of the windows (s), shape ``(n,)``, in any order.
    mesh_frequency_Hz : array_like
        Mesh frequency of each window (Hz), shape ``(n,)``; non-finite or non-positive values
        are left out of the fits (their own label is still given from their neighbours).
    rel_tolerance : float
        Relative change of the mesh frequency, over the span of the windows fitted, under which
        a window is ``"hold"`` (``[analysis] step_rel_tolerance``).
    neighbours : int
        Windows either side (in time order) fitted with the window.

    Returns
    -------
    numpy.ndarray
        ``"up"``, ``"down"`` or ``"hold"`` per window (dtype object), in the input order.

    Notes
    -----
    For window :math:`i` and the windows :math:`j \in [i-k, i+k]` (in time order; at the
    ends the :math:`2k+1` nearest), :math:`s_i` is the least-squares slope of
    :math:`\ln f_{m,j}` against :math:`t_j`; the window is ``"hold"`` when :math:`|s_i|` times
    the time those windows span is under :math:`\varepsilon`, or :math:`|s_i|` is within twice
    its standard error from the fit's residuals (a noisy speed signal at a dwell), else the
    sign of :math:`s_i`. A label that fewer of the five nearest windows (itself included)
    carry than another is replaced by the most common one there.

    Examples
    --------
    >>> t = np.arange(10.0)
    >>> list(ramp_directions(t, 100.0 + 10.0 * np.minimum(t, 9.0 - t), 0.01))[::3]
    ['up', 'up', 'down', 'down']
    """
    t = np.asarray(time_s, np.float64).ravel()
    f = np.asarray(mesh_frequency_Hz, np.float64).ravel()
    if t.shape != f.shape:
        raise ValueError(f"`time_s` and `mesh_frequency_Hz` must have one shape, were "
                         f"{t.shape} and {f.shape}")
    if not rel_tolerance > 0:
        raise ValueError(f"`rel_tolerance` must be > 0, was {rel_tolerance!r}")
    k = int(neighbours)
    if k < 1:
        raise ValueError(f"`neighbours` must be >= 1, was {neighbours!r}")
    out = np.full(t.shape, "hold", dtype=object)
    order = np.argsort(t, kind="stable")
    ts, fs = t[order], f[order]
    good = np.isfinite(ts) & np.isfinite(fs) & (fs > 0)
    lf = np.log(np.where(good, fs, 1.0))
    labels = np.full(ts.shape, "hold", dtype=object)
    for i in range(ts.size):
        # 2k + 1 windows about i, shifted inwards at the ends (a fit as long as inside)
        lo = min(max(0, i - k), max(0, ts.size - 2 * k - 1))
        hi = min(ts.size, lo + 2 * k + 1)
        sel = np.flatnonzero(good[lo:hi]) + lo
        if sel.size < 2:
            continue
        tt, yy = ts[sel], lf[sel]
        dt = tt - tt.mean()
        den = float(np.sum(dt * dt))
        if not den > 0:
            continue
        slope = float(np.sum(dt * (yy - yy.mean())) / den)
        change = abs(slope) * float(tt[-1] - tt[0])
        # a slope within twice its standard error is noise, not a direction
        resid = yy - yy.mean() - slope * dt
        se = (math.sqrt(float(np.sum(resid * resid)) / (sel.size - 2) / den)
              if sel.size > 2 else 0.0)
        if change >= rel_tolerance and abs(slope) > _SLOPE_SIGMAS * se:
            labels[i] = "up" if slope > 0 else "down"
    # a label alone among its neighbours is noise: take the majority of the five nearest
    kept = labels.copy()
    for i in range(ts.size):
        near = list(labels[max(0, i - _MODE_HALF_WIDTH):i + _MODE_HALF_WIDTH + 1])
        best = max(DIRECTIONS, key=near.count)
        if near.count(best) > near.count(labels[i]):
            kept[i] = best
    out[order] = kept
    return out


def step_directions(speed_rpm: np.ndarray, rel_tolerance: float) -> np.ndarray:
    """Which way the speed goes at each step of a stepped run-up.

    Parameters
    ----------
    speed_rpm : array_like
        Speed of each step (rpm), shape ``(n,)``, in time order.
    rel_tolerance : float
        Relative change from the previous step under which a step is ``"hold"``.

    Returns
    -------
    numpy.ndarray
        ``"up"``, ``"down"`` or ``"hold"`` per step (dtype object): the sign of the change
        from the previous step; the first step that of the change to the next one (``"up"``
        when there is none, or it is under the tolerance); None where the speed is not finite.

    Examples
    --------
    >>> list(step_directions([1000.0, 2000.0, 3000.0, 2000.0, 2005.0], 0.01))
    ['up', 'up', 'up', 'down', 'hold']
    """
    n = np.asarray(speed_rpm, np.float64).ravel()
    if not rel_tolerance > 0:
        raise ValueError(f"`rel_tolerance` must be > 0, was {rel_tolerance!r}")
    out = np.full(n.shape, None, dtype=object)
    idx = np.flatnonzero(np.isfinite(n) & (n > 0))

    def label(a: float, b: float, tie: str) -> str:
        if abs(b - a) < rel_tolerance * a:
            return tie
        return "up" if b > a else "down"

    for j, i in enumerate(idx):
        if j == 0:
            out[i] = label(n[i], n[idx[1]], "up") if idx.size > 1 else "up"
        else:
            out[i] = label(n[idx[j - 1]], n[i], "hold")
    return out


def _order_floor_snr_db(sl: StepLevels, i: int) -> float | None:
    """Weakest mesh harmonic of step ``i`` over the order-spectrum floor, same bandwidth (dB).

    The floor is the median power per bin over orders 0.5 z .. 3.5 z away from the harmonics
    (and below the passband), scaled to the ``2 m + 1`` bins a harmonic is read over and
    divided by the window's noise bandwidth, as the harmonic's amplitude is.
    """
    spec = sl.spectra[i]
    if spec is None:
        return None
    o, amp = spec.order, spec.amplitude
    z = sl.z1
    band = 1  # step_levels' default band_bins
    sel = (o >= 0.5 * z) & (o <= 3.5 * z) & (o <= spec.max_valid_order)
    for h in sl.harmonics:
        sel &= np.abs(o - h * z) > (band + 2) / spec.revolutions
    if np.count_nonzero(sel) < 8:
        return None
    floor = math.sqrt(float(np.median(amp[sel] ** 2)) * (2 * band + 1) / spec.enbw_bins)
    a = sl.amplitude[i]
    a = a[np.isfinite(a)]
    if not a.size or floor <= 0:
        return None
    return float(20 * np.log10(np.min(a) / floor))


def arms_rows(base: dict[str, Any], rec: Recording, name: str, rms_row: dict[str, Any],
              profile: SpeedProfile | None, speed_error: str | None,
              steps: tuple[SpeedStep, ...], z_tracked: int, z1: int, t0: float,
              campaign: Campaign) -> list[dict[str, Any]]:
    """The arms rows of a channel: Arms per speed step, or along the ramp when none.

    Parameters
    ----------
    base : dict
        The run's base row (campaign, run, conditions, provenance).
    rec : Recording
    name : str
        The accelerometer channel.
    rms_row : dict
        The channel's finished ``rms`` row (its counts and clipping flag carry over).
    profile : SpeedProfile or None
        The run's speed profile; None when the speed signal is unusable.
    speed_error : str or None
        Why ``profile`` is None.
    steps : tuple of SpeedStep
        The speed plateaus; empty: one row per window along the ramp (:func:`_ramp_rows`).
    z_tracked, z1 : int
        Teeth of the shaft the speed signal tracks, and of the pinion.
    t0 : float
        Start of the recording (s); step times are given from it.
    campaign : Campaign

    Returns
    -------
    list of dict
        Finished rows (:func:`~rigtools.campaign.observation_rows.row_status`); a failed row
        when the speed is missing, the unit is not an acceleration or the order analysis fails.
    """
    a = campaign.analysis
    factor = ACCEL_TO_M_S2.get(rec.channels[name].unit.strip())
    keep = ("n_samples", "n_invalid", "n_clipped")
    common = {**base, "channel": name, "quantity": "arms",
              **{k: rms_row.get(k) for k in keep}}
    ch_flags = ["clipping"] if rms_row["flag_clipping"] else []
    if profile is None:
        return [row_status({**common, "status": "failed", "message": speed_error or "no speed",
                            "_flags": ["speed_missing"]})]
    if factor is None:
        return [row_status({**common, "status": "failed", "_flags": ["unit_not_acceleration"],
                            "message": f"unit {rec.channels[name].unit!r} is not an acceleration"})]
    if not steps:
        return _ramp_rows(common, rec, name, profile, ch_flags, factor, z_tracked, z1, t0,
                          campaign)
    try:
        sl = step_levels_from_recording(rec, name, profile, z_tracked, steps=steps,
                                        harmonics=HARMONICS, revs_per_block=a.revs_per_block)
    except (RigtoolsError, ValueError) as exc:
        return [row_status({**common, "status": "failed", "message": f"Arms per step: {exc}",
                            "_flags": ["arms_failed"]})]
    directions = step_directions(np.array([st.speed_rpm for st in sl.steps]),
                                 a.step_rel_tolerance)
    rows = []
    for i, st in enumerate(sl.steps):
        flags = list(ch_flags)
        msg = []
        n_gaps = int(sl.n_gaps[i])
        if n_gaps:
            flags += ["gaps", "windows_dropped"]
            msg.append(f"{n_gaps} stretch(es) of invalid samples or unknown speed in the step")
        row = {**common, "segment": "step", "step_index": i, "step_start_s": st.start_s - t0,
               "step_stop_s": st.stop_s - t0, "n_gaps": n_gaps,
               "n_windows": int(sl.n_blocks[i])}
        if sl.n_blocks[i] == 0:
            flags.append("step_without_block")
            rows.append(row_status({**row, "status": "failed", "_flags": flags,
                                    "message": "; ".join([*msg, "no whole block of "
                                                          f"{sl.revs_per_block} revolutions"])}))
            continue
        rows.append(_harmonics_row(row, sl.amplitude[i] * factor, sl.arms[i] * factor,
                                   _order_floor_snr_db(sl, i), float(sl.mesh_frequency_Hz[i]),
                                   directions[i], z1, a.low_snr_dB, flags, msg))
    return rows


def _harmonics_row(row: dict[str, Any], amp: np.ndarray, arms: float, snr: float | None,
                   f_mesh: float, direction: str, z1: int, low_snr_dB: float,
                   flags: list[str], msg: list[str]) -> dict[str, Any]:
    """An arms row (step or ramp window) completed with its harmonics, Arms and SNR.

    ``row`` holds the columns before the mesh frequency; ``amp`` (m/s^2) the amplitudes of
    :data:`HARMONICS`, ``arms`` their Arms (m/s^2), ``snr`` the weakest harmonic over the
    floor (dB); ``f_mesh`` is the mesh frequency (Hz), ``z1`` the pinion's teeth. A NaN
    amplitude flags ``above_passband``, an SNR under ``low_snr_dB`` ``low_snr``: appended to
    ``flags`` and ``msg``, which hold the row's flags and messages so far.
    """
    if not np.all(np.isfinite(amp)):
        flags.append("above_passband")
        msg.append("a mesh harmonic lies above the resampler's passband (NaN)")
    if snr is not None and snr < low_snr_dB:
        flags.append("low_snr")
        msg.append(f"weakest mesh harmonic {snr:.1f} dB over the floor < {low_snr_dB:g} dB")
    return row_status({
        **row, "mesh_frequency_Hz": f_mesh, "direction": direction,
        "step_speed_rpm": float(speed_rpm_from_mesh_frequency(f_mesh, z1)),
        "a1_m_s2": finite_or_none(amp[0]), "a2_m_s2": finite_or_none(amp[1]),
        "a3_m_s2": finite_or_none(amp[2]),
        "arms_m_s2": finite_or_none(arms), "snr_dB": finite_or_none(snr),
        "message": "; ".join(msg), "_flags": flags})


def _ramp_snr_db(rc: RunUpCurve, i: int) -> float | None:
    """:func:`_order_floor_snr_db` for window ``i`` of a run-up curve."""
    o = np.asarray(rc.spectra.axis, np.float64)
    amp = np.asarray(rc.spectra.amplitude, np.float64)
    amp = amp[i] if amp.shape[0] == len(rc.time_s) else amp[:, i]
    z, revs = rc.z1, rc.revs_per_window
    band = ramp_band_bins(revs)
    n = revs * rc.samples_per_rev
    w = np.hanning(n + 1)[:-1] if n > 1 else np.ones(1)
    enbw = float(n * np.sum(w**2) / np.sum(w) ** 2)
    sel = (o >= 0.5 * z) & (o <= 3.5 * z) & np.isfinite(amp)
    for h in rc.harmonics:
        sel &= np.abs(o - h * z) > (band + 2) / revs
    if np.count_nonzero(sel) < 8:
        return None
    floor = math.sqrt(float(np.median(amp[sel] ** 2)) * (2 * band + 1) / enbw)
    a = rc.amplitude[i]
    a = a[np.isfinite(a)]
    if not a.size or floor <= 0:
        return None
    return float(20 * np.log10(np.min(a) / floor))


def _ramp_rows(common: dict[str, Any], rec: Recording, name: str, profile: SpeedProfile,
               ch_flags: list[str], factor: float, z_tracked: int, z1: int, t0: float,
               campaign: Campaign) -> list[dict[str, Any]]:
    """Arms per window along a speed without plateau (a ramped run-up), ``segment = "ramp"``."""
    a = campaign.analysis
    try:
        rc = run_up_curve_from_recording(rec, name, profile, z_tracked, harmonics=HARMONICS,
                                         revs_per_window=a.revs_per_block,
                                         band_bins=ramp_band_bins(a.revs_per_block))
    except (RigtoolsError, ValueError) as exc:
        return [row_status({**common, "segment": "ramp", "status": "failed",
                            "message": f"no speed plateau; Arms along the ramp: {exc}",
                            "_flags": ["arms_failed"]})]
    if not len(rc.time_s):
        dropped = ", ".join(f"{n} {why}" for why, n in sorted(rc.dropped.items()))
        return [row_status({**common, "segment": "ramp", "status": "failed",
                            "message": f"no speed plateau, and no whole window of "
                            f"{rc.revs_per_window} revolutions along the ramp"
                            + (f" (dropped: {dropped})" if dropped else ""),
                            "_flags": ["no_speed_step", "arms_failed"]})]
    directions = ramp_directions(rc.time_s, rc.mesh_frequency_Hz, a.step_rel_tolerance)
    rows = []
    for i in range(len(rc.time_s)):
        f_mesh = float(rc.mesh_frequency_Hz[i])  # z_tracked n_tracked / 60 = z1 n_pinion / 60
        half = 0.5 * rc.revs_per_window * 60.0 / float(rc.speed_rpm[i])
        t = float(rc.time_s[i]) - t0
        row = {**common, "segment": "ramp", "step_index": i, "step_start_s": t - half,
               "step_stop_s": t + half, "n_windows": 1, "n_gaps": 0}
        rows.append(_harmonics_row(row, rc.amplitude[i] * factor, rc.arms[i] * factor,
                                   _ramp_snr_db(rc, i), f_mesh, directions[i], z1,
                                   a.low_snr_dB, list(ch_flags), []))
    return rows


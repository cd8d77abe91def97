r"""Shaft speed as a function of time, the mesh frequency, and the steps of a stepped run-up.

A speed reaches rigtools in one of two forms:

* a **slow signal** (``SlowSignal``: irregular samples, e.g. ``"PinionSpeed_rpm"`` at about
  10 Hz). :func:`speed_from_slow_signal` interpolates it **linearly** between samples: exact for
  a constant speed and for a linear ramp, and it never overshoots. It does not interpolate
  across a hole in the samples longer than ``max_gap_s`` (default five median sample
  intervals), and holds the end values for at most ``hold_s`` (default one median interval)
  beyond the first and last sample; elsewhere the speed is unknown (NaN).
* a **tacho channel** (``Channel``: uniform samples of a pulse train, ``pulses_per_rev`` pulses
  per revolution). :func:`tacho_edges` finds the rising edges with a Schmitt trigger and times
  each one to a fraction of a sample by linear interpolation of the crossing of the mid level;
  :func:`speed_from_tacho` turns the edges into one speed value per pulse, each averaged over
  one whole revolution (edges ``i`` and ``i + pulses_per_rev``), so unequal pulse spacing on
  the encoder wheel cancels. Edges are never paired across a gap (``valid == False``).

Both give a :class:`SpeedProfile`: knots ``(time_s, speed_rpm)`` in one or more segments,
linear between the knots of a segment, unknown between segments.

The mesh frequency of a gear with ``z`` teeth on the shaft turning at ``n`` rpm,
:math:`f_m = z n / 60` (ISO 21771 / any gear text; seed 003 Sec. 4: 600-4100 rpm with z = 50
gives 500-3400 Hz), is :func:`models.geometry.mesh_frequency_Hz`, the one place rigtools and
models compute it, re-exported here as :func:`mesh_frequency_Hz`.

Steps of a stepped run-up are plateaus of the speed (:func:`detect_speed_steps`): maximal
stretches lasting at least ``min_duration_s`` in which every knot lies within the stability
tolerance ``max(abs_tolerance_rpm, rel_tolerance * n)`` of the stretch's mid-range speed
``n`` (default: 1 % or 2 rpm, whichever is larger, for at least 1 s).

Errors
------
::

    RigtoolsError
    └── MissingSpeedError (LookupError)   no speed signal, or none covering the data analysed

:class:`MissingSpeedError` is defined in :mod:`rigtools.errors` and re-exported here; it
carries ``name``, ``available`` and ``detail`` and survives pickling.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from models.geometry import mesh_frequency_Hz
from rigtools.analysis.signal_checks import as_1d, check_positive
from rigtools.analysis.speed_steps import detect_speed_steps
from rigtools.analysis.speed_types import SpeedProfile, SpeedStep
from rigtools.analysis.tacho import speed_from_tacho, tacho_edges
from rigtools.errors import MissingSpeedError
from rigtools.ingest.recording import Recording

__all__ = [
    "MissingSpeedError",
    "SpeedProfile",
    "SpeedStep",
    "detect_speed_steps",
    "mesh_frequency_Hz",
    "speed_from_slow_signal",
    "speed_from_tacho",
    "speed_profile",
    "tacho_edges",
]

#: Speed units a slow signal may carry, and the factor to rpm.
_RPM_PER_UNIT: dict[str, float] = {
    "rpm": 1.0,
    "1/min": 1.0,
    "r/min": 1.0,
    "rev/min": 1.0,
    "min^-1": 1.0,
    "min-1": 1.0,
    "hz": 60.0,
    "rev/s": 60.0,
    "r/s": 60.0,
    "1/s": 60.0,
    "rad/s": 60.0 / (2.0 * np.pi),
}


def _rpm_factor(unit: str) -> float:
    key = unit.strip().lower().replace(" ", "")
    if key not in _RPM_PER_UNIT:
        raise ValueError(
            f"`unit` must be a speed unit ({', '.join(sorted(_RPM_PER_UNIT))}), was {unit!r}"
        )
    return _RPM_PER_UNIT[key]


# --- slow signal ------------------------------------------------------------------------------
def speed_from_slow_signal(
    time_s: np.ndarray,
    values: np.ndarray,
    *,
    unit: str = "rpm",
    max_gap_s: float | None = None,
    hold_s: float | None = None,
    name: str = "speed",
) -> SpeedProfile:
    """Speed profile from an irregularly sampled speed signal, interpolated linearly.

    Parameters
    ----------
    time_s : array_like
        Sample times (s, logger clock), non-decreasing.
    values : array_like
        Speed samples in ``unit``. Non-finite samples are dropped and counted.
    unit : str
        ``"rpm"`` (also ``"1/min"``, ``"r/min"``), ``"Hz"`` (``"rev/s"``) or ``"rad/s"``.
    max_gap_s : float, optional
        Samples farther apart than this are not interpolated across: the profile splits into
        segments and the speed between them is unknown (s). Default: five times the median
        sample interval.
    hold_s : float, optional
        How far beyond each segment's first and last sample the end value is held (s).
        Default: one median sample interval.
    name : str
        Signal name, for the ``source`` text.

    Returns
    -------
    SpeedProfile

    Raises
    ------
    MissingSpeedError
        When no finite sample remains.
    """
    t = as_1d("time_s", time_s)
    v = as_1d("values", values)
    if t.shape != v.shape:
        raise ValueError(f"`time_s` and `values` must have the same shape, have {t.shape} "
                         f"and {v.shape}")
    factor = _rpm_factor(unit)
    keep = np.isfinite(t) & np.isfinite(v)
    n_rejected = int(np.count_nonzero(~keep))
    t, rpm = t[keep], v[keep] * factor
    if t.size == 0:
        raise MissingSpeedError(name, detail="it holds no finite sample")
    if np.any(np.diff(t) < 0):
        raise ValueError("`time_s` must be non-decreasing")
    # Repeated time stamps: keep the last value at each time (interp needs increasing x).
    last = np.r_[np.diff(t) > 0, True]
    n_rejected += int(np.count_nonzero(~last))
    t, rpm = t[last], rpm[last]
    dt = np.diff(t)
    median_dt = float(np.median(dt)) if dt.size else 0.0
    gap = 5.0 * median_dt if max_gap_s is None else check_positive("max_gap_s", max_gap_s)
    hold = median_dt if hold_s is None else float(hold_s)
    if hold < 0 or not np.isfinite(hold):
        raise ValueError(f"`hold_s` must be a finite number >= 0, was {hold_s!r}")
    segment = np.r_[0, np.cumsum(dt > gap)].astype(np.int64)
    n_seg = int(segment[-1]) + 1
    first = np.searchsorted(segment, np.arange(n_seg), side="left")
    lastk = np.searchsorted(segment, np.arange(n_seg), side="right") - 1
    return SpeedProfile(
        time_s=t,
        speed_rpm=rpm,
        segment=segment,
        cover_start_s=t[first] - hold,
        cover_stop_s=t[lastk] + hold,
        source=(f"slow signal {name!r} ({unit}), linear interpolation, not across holes "
                f"> {gap:.3g} s, ends held {hold:.3g} s"),
        n_rejected=n_rejected,
    )


# --- from a Recording -------------------------------------------------------------------------
def speed_profile(
    recording: Recording,
    name: str | None,
    *,
    pulses_per_rev: int | None = None,
    **kwargs: Any,
) -> SpeedProfile:
    """The speed profile of a Recording's speed signal: a slow signal or a tacho channel.

    Parameters
    ----------
    recording : Recording
        The run.
    name : str or None
        Name of a slow signal (speed in rpm, Hz or rad/s, by its unit) or of a tacho channel.
    pulses_per_rev : int, optional
        Needed when ``name`` is a channel.
    **kwargs
        Passed to :func:`speed_from_slow_signal` or :func:`speed_from_tacho`.

    Returns
    -------
    SpeedProfile

    Raises
    ------
    MissingSpeedError
        When ``name`` is None or names neither a slow signal nor a channel.
    """
    available = [*recording.slow, *recording.channels]
    if name is None:
        raise MissingSpeedError(None, available, "no speed signal was named")
    if name in recording.slow:
        s = recording.slow[name]
        return speed_from_slow_signal(s.time_s, s.values, unit=s.unit, name=name, **kwargs)
    if name in recording.channels:
        if pulses_per_rev is None:
            raise ValueError(f"`pulses_per_rev` is needed: {name!r} is a channel, read as a "
                             "tacho pulse train")
        c = recording.channels[name]
        return speed_from_tacho(c.values, c.sample_rate_Hz, pulses_per_rev,
                                start_time_s=float(c.time_s[0]) if len(c) else c.start_time_s,
                                valid=c.valid, name=name, **kwargs)
    raise MissingSpeedError(name, available,
                            "no slow signal or channel of that name is in the recording")

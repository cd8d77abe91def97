"""Messages read as slow signals that look like sampled channels: what was found, and the way out.

A DBC without rigtools' message attributes (``RigSampleRate``, ``RigChannel``, ``RigCounter``)
and no mapping make every signal a slow signal, a 25.6 kHz accelerometer included: its frames
are then not placed by a sample counter, no gap is counted, and the analysis finds no uniform
channel. :func:`fast_message_warning` says so for one message, with its rate, the frames its
counter (when one of its signals counts frames) says were lost, and how to write the mapping
that reads it as uniform channels.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Final

import numpy as np

__all__ = ["MAPPING_HOWTO", "MIN_FRAMES", "FAST_RATE_Hz", "fast_message_warning"]

#: A message read as slow signals that arrives at least this often (Hz) looks like samples.
FAST_RATE_Hz: Final = 1000.0
#: Fewest frames for a rate (and a counter) to be judged.
MIN_FRAMES: Final = 64
#: Share of steps of +1 that makes a signal a frame counter.
COUNTER_SHARE: Final = 0.9

#: How to read such signals as uniform channels (no mapping generator exists yet).
MAPPING_HOWTO: Final = (
    "write a mapping file (TOML) with one [[uniform]] entry per channel: channel, message, "
    "samples (the signals holding consecutive samples), counter (the frame-counter signal), "
    "sample_rate_Hz and unit (schema: data_schemas/channel_mapping.schema.json), and pass it "
    "with --map"
)


def _counter_losses(values: np.ndarray) -> tuple[int, int] | None:
    """(gaps, frames lost) when ``values`` count frames (steps of +1, wrapping), else None."""
    v = values[np.isfinite(values)]
    if v.size < MIN_FRAMES or np.any(v < 0) or np.any(v != np.round(v)):
        return None
    d = np.diff(v)
    if np.count_nonzero(d == 1) < COUNTER_SHARE * d.size:
        return None
    top = float(v.max())
    modulus = 1 << int(np.ceil(np.log2(top + 1))) if top >= 1 else 2
    step = np.mod(d, modulus)
    skipped = step[step > 1]
    return int(skipped.size), int(np.sum(skipped - 1))


def fast_message_warning(
    message: str,
    signals: Mapping[str, tuple[Sequence[np.ndarray], Sequence[np.ndarray]]],
    dbc: str,
) -> str | None:
    """The warning for a message read as slow signals that arrives fast, or None.

    Parameters
    ----------
    message : str
        The message as the user knows it (``"message 'IMU_ACCEL'"``, with its bus when it
        arrives on several).
    signals : mapping of str to (sequence of numpy.ndarray, sequence of numpy.ndarray)
        Per slow signal of the message, the blocks of its logger times (s) and of its values.
    dbc : str
        The DBC path, named in the warning.

    Returns
    -------
    str or None
        None when the message arrives more slowly than :data:`FAST_RATE_Hz` or has fewer than
        :data:`MIN_FRAMES` frames.
    """
    if not signals:
        return None
    name0 = max(signals, key=lambda k: sum(np.size(t) for t in signals[k][0]))
    t = np.concatenate(list(signals[name0][0])) if signals[name0][0] else np.zeros(0)
    t = np.sort(t[np.isfinite(t)])
    if t.size < MIN_FRAMES or not t[-1] > t[0]:
        return None
    dt = np.diff(t)
    positive = dt[dt > 0]
    if positive.size == 0:
        return None
    usual = float(np.median(positive))
    rate = 1.0 / usual
    if rate < FAST_RATE_Hz:
        return None
    evidence = ""
    for name, (_times, values) in signals.items():
        found = _counter_losses(np.concatenate(list(values)) if values else np.zeros(0))
        if found is not None:
            gaps, lost = found
            evidence = (f"its signal {name!r} counts frames and skips {lost} frame(s) in "
                        f"{gaps} gap(s); " if lost else
                        f"its signal {name!r} counts frames and skips none; ")
            break
    if not evidence:
        n_long = int(np.count_nonzero(dt > 1.5 * usual))
        if n_long:
            evidence = (f"{n_long} interval(s) between its frames exceed 1.5 x the usual "
                        f"{usual * 1e6:.0f} us (frames lost?); ")
    names = ", ".join(sorted(signals))
    return (f"{message} arrives at about {rate / 1e3:.3g} kHz ({t.size} frames; signals "
            f"{names}) and was read as slow signals, so no gap in it is counted; {evidence}"
            f"the DBC {dbc} marks no message as a uniform channel (message attributes "
            f"RigSampleRate, RigChannel, RigCounter); to read its samples as uniform channels, "
            f"{MAPPING_HOWTO}")

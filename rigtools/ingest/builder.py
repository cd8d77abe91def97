"""Assemble a Recording from the pieces readers decode, batch by batch.

Readers stream: they hand over blocks of samples with absolute sample indices (already
unwrapped from the source's counters) and blocks of slow-signal points. The builder keeps
the blocks, and only at the end lays each channel on its index grid: duplicates dropped and
counted, out-of-order blocks sorted, gaps left as NaN with ``valid == False`` and recorded,
never interpolated. Peak memory is the blocks plus the final arrays, about twice the decoded
data.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from rigtools.errors import RecordingFormatError
from rigtools.ingest.recording import (
    Channel,
    Gap,
    IngestReport,
    Provenance,
    Recording,
    RunMetadata,
    SlowSignal,
)
from rigtools.ingest.timebase import timebase_check

__all__ = ["RecordingBuilder"]

#: A channel's index span may exceed its sample count by this factor (plus a fixed allowance)
#: before the builder refuses to fill the gaps: a corrupt counter must not allocate gigabytes.
MAX_SPAN_FACTOR = 4
MAX_SPAN_ALLOWANCE = 10_000_000


@dataclass
class _ChannelParts:
    unit: str
    sample_rate_Hz: float
    index: list[np.ndarray] = field(default_factory=list)
    values: list[np.ndarray] = field(default_factory=list)
    stamp_index: list[np.ndarray] = field(default_factory=list)
    stamps: list[np.ndarray] = field(default_factory=list)
    start_time_s: float | None = None


@dataclass
class _SlowParts:
    unit: str
    time: list[np.ndarray] = field(default_factory=list)
    values: list[np.ndarray] = field(default_factory=list)


class RecordingBuilder:
    """Collect decoded blocks and build a :class:`~rigtools.ingest.recording.Recording`.

    Parameters
    ----------
    path : str
        Source path, for error messages.
    report : IngestReport
        Tallies shared with the reader.
    """

    def __init__(self, path: str, report: IngestReport) -> None:
        self.path = path
        self.report = report
        self._channels: dict[str, _ChannelParts] = {}
        self._slow: dict[str, _SlowParts] = {}

    def add_samples(
        self,
        channel: str,
        unit: str,
        sample_rate_Hz: float,
        index: np.ndarray,
        values: np.ndarray,
        stamp_index: np.ndarray | None = None,
        stamps_s: np.ndarray | None = None,
    ) -> None:
        """Add a block of samples of a uniform channel.

        Parameters
        ----------
        channel, unit : str
            Channel name and unit; a channel keeps the unit and rate of its first block.
        sample_rate_Hz : float
            Nominal rate (Hz).
        index : numpy.ndarray
            Absolute sample index of each value (int64).
        values : numpy.ndarray
            Sample values (converted to float64).
        stamp_index, stamps_s : numpy.ndarray, optional
            Logger timestamps (s) and the sample index each belongs to, used only to place
            index 0 on the logger clock and to check the clock.
        """
        parts = self._channels.get(channel)
        if parts is None:
            parts = self._channels[channel] = _ChannelParts(unit, float(sample_rate_Hz))
        elif parts.unit != unit or parts.sample_rate_Hz != float(sample_rate_Hz):
            self.report.reject("inconsistent_channel_layout", int(np.size(values)))
            self.report.warn(
                f"channel {channel!r}: block with unit {unit!r} at {sample_rate_Hz} Hz differs "
                f"from the first block ({parts.unit!r} at {parts.sample_rate_Hz} Hz); dropped"
            )
            return
        if np.size(values) == 0:
            return
        parts.index.append(np.asarray(index, np.int64))
        parts.values.append(np.asarray(values, np.float64))
        if stamps_s is not None and stamp_index is not None and np.size(stamps_s):
            parts.stamp_index.append(np.asarray(stamp_index, np.int64))
            parts.stamps.append(np.asarray(stamps_s, np.float64))

    def set_start_time(self, channel: str, start_time_s: float) -> None:
        """Fix the time of sample index 0 (when the source states it exactly)."""
        if channel in self._channels:
            self._channels[channel].start_time_s = float(start_time_s)

    def add_slow(self, name: str, unit: str, time_s: np.ndarray, values: np.ndarray) -> None:
        """Add points of a slow signal."""
        parts = self._slow.get(name)
        if parts is None:
            parts = self._slow[name] = _SlowParts(unit)
        if np.size(values) == 0:
            return
        parts.time.append(np.asarray(time_s, np.float64))
        parts.values.append(np.asarray(values, np.float64))

    @property
    def n_channels(self) -> int:
        """Uniform channels seen so far."""
        return len(self._channels)

    def build(self, metadata: RunMetadata, provenance: Provenance) -> Recording:
        """Lay every channel on its grid and return the Recording."""
        channels = {}
        for name in sorted(self._channels):
            ch = self._build_channel(name, self._channels.pop(name))
            if ch is not None:
                channels[name] = ch
        slow = {}
        for name in sorted(self._slow):
            s = self._build_slow(name, self._slow.pop(name))
            if s is not None:
                slow[name] = s
        return Recording(channels, slow, metadata, provenance)

    def _build_channel(self, name: str, parts: _ChannelParts) -> Channel | None:
        if not parts.values:
            return None
        idx = _join(parts.index)
        vals = _join(parts.values)
        if idx.size > 1 and np.any(np.diff(idx) < 0):
            order = np.argsort(idx, kind="stable")
            self.report.warn(f"channel {name!r}: blocks arrived out of order and were sorted")
            idx = idx[order]
            vals = vals[order]
            del order
        dup = np.zeros(idx.size, bool)
        dup[1:] = idx[1:] == idx[:-1]
        n_dup = int(dup.sum())
        if n_dup:
            self.report.reject("duplicate_sample", n_dup, f"channel {name!r}")
            idx = idx[~dup]
            vals = vals[~dup]
        first = int(idx[0])
        span = int(idx[-1]) - first + 1
        if span > MAX_SPAN_FACTOR * idx.size + MAX_SPAN_ALLOWANCE:
            raise RecordingFormatError(
                self.path,
                f"channel {name!r}",
                f"sample indices spanning about the {idx.size} samples received",
                f"indices from {first} to {int(idx[-1])} (span {span})",
                "the sample counter is corrupt or restarted beyond repair",
            )
        pos = idx - first
        if span == idx.size:
            values = vals
            valid = np.ones(span, bool)
        else:
            values = np.full(span, np.nan)
            values[pos] = vals
            valid = np.zeros(span, bool)
            valid[pos] = True
        del vals
        nonfinite = valid & ~np.isfinite(values)
        n_nonfinite = int(nonfinite.sum())
        if n_nonfinite:
            valid &= ~nonfinite
            at = int(np.flatnonzero(nonfinite)[0]) + first
            self.report.reject("non_finite_sample", n_nonfinite, f"channel {name!r} index {at}")
        # Start time: exact when the source states it, else from the logger stamps.
        if parts.start_time_s is not None:
            t0 = parts.start_time_s
        elif parts.stamps:
            t0, stats = timebase_check(
                np.concatenate(parts.stamp_index), np.concatenate(parts.stamps), parts.sample_rate_Hz
            )
            self.report.timebase[name] = stats
            if stats.get("n_stamps_backwards", 0):
                self.report.warn(
                    f"channel {name!r}: logger timestamps went backwards "
                    f"{int(stats['n_stamps_backwards'])} time(s); the sample counter was kept"
                )
        else:
            t0 = 0.0
        steps = np.diff(idx)
        for p in np.flatnonzero(steps > 1):
            start = int(idx[p]) + 1
            self.report.gaps.append(
                Gap(name, start, int(steps[p]) - 1, t0 + start / parts.sample_rate_Hz)
            )
        return Channel(name, parts.unit, parts.sample_rate_Hz, float(t0), first, values, valid)

    def _build_slow(self, name: str, parts: _SlowParts) -> SlowSignal | None:
        if not parts.values:
            return None
        t = _join(parts.time)
        v = _join(parts.values)
        back = int(np.count_nonzero(np.diff(t) < 0))
        if back:
            order = np.argsort(t, kind="stable")
            t, v = t[order], v[order]
            self.report.warn(
                f"slow signal {name!r}: timestamps went backwards {back} time(s); "
                "points sorted by time, none dropped"
            )
        return SlowSignal(name, parts.unit, t, v)


def _join(blocks: list[np.ndarray]) -> np.ndarray:
    """Concatenate and release the blocks (no copy for a single block)."""
    out = blocks[0] if len(blocks) == 1 else np.concatenate(blocks)
    blocks.clear()
    return out

"""Assemble a Recording from the pieces readers decode, batch by batch.

Readers stream: they hand over blocks of samples with absolute sample indices (already
unwrapped from the source's counters) and blocks of slow-signal points. The builder keeps
the blocks, and only at the end lays each channel on its index grid: duplicates dropped and
counted, out-of-order blocks sorted, gaps left as NaN with ``valid == False`` and recorded,
never interpolated. Peak memory is the blocks plus the final arrays, about twice the decoded
data.
"""

from __future__ import annotations

import dataclasses
import itertools
from dataclasses import dataclass, field

import numpy as np

from rigtools.errors import RecordingFormatError
from rigtools.ingest.conversion import convert_into
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
#: Logger stamps used for the clock check (evenly picked when there are more).
MAX_CLOCK_POINTS = 200_000


@dataclass
class _Block:
    """Rows of consecutive samples: ``raw[i, j]`` is sample ``starts[i] + j``."""

    starts: np.ndarray  # int64, (m,)
    raw: np.ndarray  # any numeric dtype, (m, k)
    conversion: tuple[tuple[float, float], ...]


@dataclass
class _ChannelParts:
    unit: str
    sample_rate_Hz: float
    blocks: list[_Block] = field(default_factory=list)
    stamp_index: list[np.ndarray] = field(default_factory=list)
    stamps: list[np.ndarray] = field(default_factory=list)
    n_samples: int = 0


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
        self._others: dict[str, list[_ChannelParts]] = {}  # blocks with another unit or rate
        self._slow: dict[str, _SlowParts] = {}
        self._restarts: dict[str, set[int]] = {}
        # second clocks of a channel, by clock name: (stamp_index parts, stamps_s parts)
        self._other_clocks: dict[str, dict[str, tuple[list[np.ndarray], list[np.ndarray]]]] = {}
        self._carriers: dict[str, dict[str, str | int]] = {}
        # clock checks made, by the identity of their arrays (kept alive with the result)
        self._clock_checks: dict[tuple[int, int, float],
                                 tuple[np.ndarray, np.ndarray, float, dict[str, float]]] = {}

    def add_samples(
        self,
        channel: str,
        unit: str,
        sample_rate_Hz: float,
        index: np.ndarray | int,
        values: np.ndarray,
        stamp_index: np.ndarray | None = None,
        stamps_s: np.ndarray | None = None,
        conversion: tuple[tuple[float, float], ...] = (),
    ) -> None:
        """Add a block of samples of a uniform channel.

        Parameters
        ----------
        channel, unit : str
            Channel name and unit. Blocks of one channel that disagree on unit or rate are
            kept apart; the channel takes the unit and rate that carry the most samples, the
            other blocks are counted ``inconsistent_channel_layout`` (a damaged rate field in
            the first block must not cost every intact block after it).
        sample_rate_Hz : float
            Nominal rate (Hz).
        index : int or numpy.ndarray
            Where the samples go on the channel's absolute sample-index grid: an int (the
            index of ``values[0]`` of a 1-D block of consecutive samples); an int64 array of the
            same length as a 1-D ``values`` (one index per sample); or, for a 2-D ``values`` of
            shape ``(m, k)`` (``m`` frames of ``k`` consecutive samples), an array of ``m`` row
            start indices.
        values : numpy.ndarray
            Sample values, or raw integers to be converted with ``conversion``. Kept in their
            own dtype until the channel is built (int16 CAN samples cost 2 bytes each).
            The builder keeps the array it is given, without a copy (a single gap-free
            float64 block with no conversion becomes the channel's values as it is): do not
            modify it afterwards.
        stamp_index, stamps_s : numpy.ndarray, optional
            Logger timestamps (s) and the sample index each belongs to, used only to place
            index 0 on the logger clock and to check the clock.
        conversion : tuple of (scale, offset)
            Applied in order in float64 when the channel is built:
            ``v = (raw * s1 + o1) * s2 + o2 ...``, exactly as a DBC and then a mapping scale it.
        """
        parts = self._channels.get(channel)
        if parts is None:
            parts = self._channels[channel] = _ChannelParts(unit, float(sample_rate_Hz))
        elif parts.unit != unit or parts.sample_rate_Hz != float(sample_rate_Hz):
            parts = self._variant(channel, unit, float(sample_rate_Hz))
        vals = np.asarray(values)
        if vals.size == 0:
            return
        if vals.ndim == 2:
            starts = np.asarray(index, np.int64).reshape(-1)
            raw = vals
        elif np.ndim(index) == 0:
            starts = np.asarray([int(index)], np.int64)  # type: ignore[arg-type]
            raw = vals.reshape(1, -1)
        else:
            starts = np.asarray(index, np.int64)
            raw = vals.reshape(-1, 1)
        if starts.shape[0] != raw.shape[0]:
            raise ValueError(f"`index` has {starts.shape[0]} rows, `values` {raw.shape[0]}")
        conv = tuple(conversion)
        for b_starts, b_raw in _contiguous_runs(starts, raw):
            parts.blocks.append(_Block(b_starts, b_raw, conv))
        parts.n_samples += raw.size
        if stamps_s is not None and stamp_index is not None and np.size(stamps_s):
            parts.stamp_index.append(np.asarray(stamp_index, np.int64))
            parts.stamps.append(np.asarray(stamps_s, np.float64))

    def _variant(self, channel: str, unit: str, sample_rate_Hz: float) -> _ChannelParts:
        """The parts of ``channel`` with another unit or rate than its first block."""
        others = self._others.setdefault(channel, [])
        for p in others:
            if p.unit == unit and p.sample_rate_Hz == sample_rate_Hz:
                return p
        others.append(_ChannelParts(unit, sample_rate_Hz))
        return others[-1]

    def _choose_layout(self, name: str, parts: _ChannelParts) -> _ChannelParts:
        """Of a channel's layouts (unit, rate), the one with most samples; count the rest."""
        candidates = [parts, *self._others.pop(name, [])]
        best = max(candidates, key=lambda p: p.n_samples)  # ties: the first block's layout
        for p in candidates:
            if p is not best and p.n_samples:
                self.report.reject("inconsistent_channel_layout", p.n_samples,
                                   f"channel {name!r}")
                self.report.warn(
                    f"channel {name!r}: {p.n_samples} sample(s) in blocks with unit {p.unit!r} "
                    f"at {p.sample_rate_Hz} Hz differ from the {best.n_samples} of the channel "
                    f"({best.unit!r} at {best.sample_rate_Hz} Hz); dropped"
                )
        return best

    def add_clock(self, channel: str, stamp_index: np.ndarray, stamps_s: np.ndarray) -> None:
        """Add logger timestamps of a channel (and the sample index each belongs to)."""
        parts = self._channels.get(channel)
        if parts is not None and np.size(stamps_s):
            parts.stamp_index.append(np.asarray(stamp_index, np.int64))
            parts.stamps.append(np.asarray(stamps_s, np.float64))

    def add_other_clock(
        self, channel: str, clock: str, stamp_index: np.ndarray, stamps_s: np.ndarray
    ) -> None:
        """Add stamps of a second clock of a channel, one that does not place it.

        A source may stamp each sample twice (an MCAP message: its header stamp and its log
        time). The clock given to :meth:`add_samples` places the channel; this one is only
        compared with the counter time base: when the channel is built,
        ``report.timebase[f"{channel}@{clock}"]`` holds the same statistics as the channel's
        own entry (see :func:`~rigtools.ingest.timebase.timebase_check`) plus
        ``start_time_s`` (time of sample index 0 on this clock, s) and ``offset_s`` (that
        minus the channel's ``start_time_s``: the median of this clock minus the channel's
        clock, s). Non-finite stamps are ignored.
        """
        if not np.size(stamps_s):
            return
        idx, st = self._other_clocks.setdefault(channel, {}).setdefault(clock, ([], []))
        idx.append(np.asarray(stamp_index, np.int64))
        st.append(np.asarray(stamps_s, np.float64))

    def _timebase_check(self, index: np.ndarray, stamps_s: np.ndarray,
                        sample_rate_Hz: float) -> tuple[float, dict[str, float]]:
        """:func:`timebase_check`, once for channels given the very same clock arrays.

        The channels of one CAN message share their frames, hence one clock: the check of
        the first is the check of the others.
        """
        key = (id(index), id(stamps_s), float(sample_rate_Hz))
        hit = self._clock_checks.get(key)
        if hit is not None and hit[0] is index and hit[1] is stamps_s:
            return hit[2], dict(hit[3])
        t0, stats = timebase_check(index, stamps_s, sample_rate_Hz)
        self._clock_checks[key] = (index, stamps_s, t0, dict(stats))
        return t0, stats

    def _check_other_clocks(self, name: str, sample_rate_Hz: float, t0: float) -> None:
        """Fill ``report.timebase[f"{name}@{clock}"]`` for each second clock of a channel."""
        for clock, (idx, st) in sorted(self._other_clocks.pop(name, {}).items()):
            si, ts = _join(idx), _join(st)
            if si.size > MAX_CLOCK_POINTS:
                pick = np.linspace(0, si.size - 1, MAX_CLOCK_POINTS).astype(np.int64)
                si, ts = si[pick], ts[pick]
            t1, stats = timebase_check(si, ts, sample_rate_Hz)
            if not stats:  # no finite stamp
                continue
            stats["start_time_s"] = float(t1)
            stats["offset_s"] = float(t1 - t0)
            self.report.timebase[f"{name}@{clock}"] = stats

    def note_carrier(self, channel: str, source: str, samples_per_frame: int) -> None:
        """Say which frames or messages carry a channel, and how many samples each holds.

        Channels of one ``source`` (a CAN message on one bus, an MCAP topic) lose samples
        together when one of its frames is lost: :func:`rigtools.ingest.losses.loss_tally`
        counts such a loss once, in frames. The built Recording keeps the carriers in
        ``provenance.layout["carriers"]`` (channel -> ``{"source", "samples_per_frame"}``),
        for the channels it holds.

        Parameters
        ----------
        channel : str
            Channel name, as given to :meth:`add_samples`.
        source : str
            What carries it, in words the user knows (``"message 'ACC1'"``,
            ``"topic '/imu'"``); equal for channels fed by the same frames.
        samples_per_frame : int
            Consecutive samples of the channel in each frame or message (>= 1).
        """
        if samples_per_frame < 1:
            raise ValueError(f"`samples_per_frame` must be >= 1, was {samples_per_frame}")
        self._carriers[channel] = {"source": source, "samples_per_frame": int(samples_per_frame)}

    def mark_restart(self, channel: str, index: int) -> None:
        """Note that the source's counter restarted at sample ``index`` (gap kind "restart")."""
        self._restarts.setdefault(channel, set()).add(int(index))

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
            ch = self._build_channel(name, self._choose_layout(name, self._channels.pop(name)))
            if ch is not None:
                channels[name] = ch
        self._clock_checks.clear()
        slow = {}
        for name in sorted(self._slow):
            s = self._build_slow(name, self._slow.pop(name))
            if s is not None:
                slow[name] = s
        carriers = {name: self._carriers[name] for name in channels if name in self._carriers}
        if carriers:
            provenance = dataclasses.replace(
                provenance, layout={**provenance.layout, "carriers": carriers})
        return Recording(channels, slow, metadata, provenance)

    def _build_channel(self, name: str, parts: _ChannelParts) -> Channel | None:
        blocks = parts.blocks
        if not blocks:
            return None
        # Row table over all blocks: start index and width of every row, in arrival order.
        widths = np.concatenate([np.full(b.starts.shape[0], b.raw.shape[1], np.int64)
                                 for b in blocks])
        starts = np.concatenate([b.starts for b in blocks])
        row0 = np.cumsum([0] + [b.starts.shape[0] for b in blocks])
        order = None
        if starts.size > 1 and np.any(np.diff(starts) < 0):
            order = np.argsort(starts, kind="stable")
            self.report.warn(f"channel {name!r}: samples arrived out of order and were sorted")
        s_sorted = starts if order is None else starts[order]
        w_sorted = widths if order is None else widths[order]
        ends = s_sorted + w_sorted
        prev_end = np.empty_like(ends)
        prev_end[0] = s_sorted[0]
        if ends.size > 1:
            np.maximum.accumulate(ends[:-1], out=prev_end[1:])
        skip_sorted = np.clip(prev_end - s_sorted, 0, w_sorted)  # samples already received
        n_dup = int(skip_sorted.sum())
        first = int(s_sorted[0])
        last_end = int(ends.max())
        span = last_end - first
        n_kept = int(widths.sum()) - n_dup
        if span > MAX_SPAN_FACTOR * n_kept + MAX_SPAN_ALLOWANCE:
            # A corrupt counter must not allocate gigabytes, nor cost the intact data: keep the
            # run of rows holding most samples, count the rest.
            e_run = np.maximum.accumulate(ends)
            cut = np.flatnonzero(s_sorted[1:] - e_run[:-1] > MAX_SPAN_ALLOWANCE) + 1
            bounds = np.r_[0, cut, s_sorted.size]
            weight = np.add.reduceat(w_sorted, bounds[:-1])
            best = int(np.argmax(weight))
            if cut.size == 0 or weight[best] == 0:
                raise RecordingFormatError(
                    self.path,
                    f"channel {name!r}",
                    f"sample indices spanning about the {n_kept} samples received",
                    f"indices from {first} to {last_end - 1} (span {span})",
                    "the sample counter is corrupt beyond repair",
                )
            keep_sorted = np.zeros(s_sorted.size, bool)
            keep_sorted[bounds[best] : bounds[best + 1]] = True
            keep_row = keep_sorted if order is None else np.empty_like(keep_sorted)
            if order is not None:
                keep_row[order] = keep_sorted
            dropped = int(widths.sum() - weight[best])
            self.report.reject("implausible_sample_index", dropped, f"channel {name!r}")
            self.report.warn(
                f"channel {name!r}: {dropped} sample(s) carried indices far from the "
                f"{int(weight[best])} others (a corrupt or restarted counter); not used"
            )
            parts.blocks = [
                _Block(b.starts[sel], b.raw[sel], b.conversion)
                for bi, b in enumerate(blocks)
                if (sel := keep_row[row0[bi] : row0[bi + 1]]).any()
            ]
            return self._build_channel(name, parts)
        if n_dup:
            self.report.reject("duplicate_sample", n_dup, f"channel {name!r}")
        if order is None:
            skip = skip_sorted
        else:
            skip = np.empty_like(skip_sorted)
            skip[order] = skip_sorted
        # Gaps: holes between the running end of the rows and the next row's start.
        e_sorted = np.maximum.accumulate(ends)
        hole = s_sorted[1:] - e_sorted[:-1]
        gap_at = np.flatnonzero(hole > 0)
        del w_sorted, prev_end, skip_sorted, order, ends, s_sorted
        complete = gap_at.size == 0
        adopt = _adoptable(blocks, complete, n_dup)
        if adopt is not None:
            # One complete float64 block with nothing to convert is the channel already: the
            # builder owns what add_samples was given, so take it instead of copying it.
            values = adopt
        else:
            values = np.empty(span) if complete else np.full(span, np.nan)
        valid = np.ones(span, bool) if complete else np.zeros(span, bool)
        # every value written known finite (the compiled conversion says so on the way)
        known_finite = adopt is None
        for bi, b in enumerate(blocks if adopt is None else []):
            bs = b.starts - first
            bskip = skip[row0[bi] : row0[bi + 1]]
            k = b.raw.shape[1]
            conv = b.conversion
            clean = not bskip.any()
            if clean and (bs.shape[0] == 1 or np.all(np.diff(bs) == k)):
                lo = int(bs[0])
                dst = values[lo : lo + b.raw.size]
                known_finite &= convert_into(b.raw.reshape(-1), conv, dst) is True
                if not complete:
                    valid[lo : lo + b.raw.size] = True
                continue
            conv_rows = np.empty(b.raw.shape, np.float64)
            known_finite &= convert_into(b.raw, conv, conv_rows) is True
            full = bskip == 0
            if full.any():
                pos = bs[full][:, None] + np.arange(k)
                values[pos] = conv_rows[full]
                if not complete:
                    valid[pos] = True
            for r in np.flatnonzero(~full):
                sk = int(bskip[r])
                if sk >= k:
                    continue
                lo = int(bs[r]) + sk
                values[lo : int(bs[r]) + k] = conv_rows[r, sk:]
                if not complete:
                    valid[lo : int(bs[r]) + k] = True
        # Integer samples with finite scales cannot be NaN or Inf: skip the pass over them.
        may_be_nonfinite = any(
            b.raw.dtype.kind not in "iub"
            or any(not (abs(sc) < 1e200 and abs(off) < 1e300) for sc, off in b.conversion)
            for b in blocks
        )
        parts.blocks = []
        # One cheap reduction first: a sum over finite values is finite (an overflowing sum
        # merely falls back to the full pass).
        if may_be_nonfinite and not (complete and (
                known_finite or np.isfinite(np.add.reduce(values)))):
            nonfinite = valid & ~np.isfinite(values)
            n_nonfinite = int(nonfinite.sum())
            if n_nonfinite:
                valid &= ~nonfinite
                at = int(np.flatnonzero(nonfinite)[0]) + first
                self.report.reject("non_finite_sample", n_nonfinite,
                                   f"channel {name!r} index {at}")
            del nonfinite
        # Start time (sample index 0) from the logger stamps.
        if parts.stamps:
            si, st = _join(parts.stamp_index), _join(parts.stamps)
            if si.size > MAX_CLOCK_POINTS:  # the clock check needs no more than this
                pick = np.linspace(0, si.size - 1, MAX_CLOCK_POINTS).astype(np.int64)
                si, st = si[pick], st[pick]
            t0, stats = self._timebase_check(si, st, parts.sample_rate_Hz)
            self.report.timebase[name] = stats
            if stats.get("n_stamps_backwards", 0):
                self.report.warn(
                    f"channel {name!r}: logger timestamps went backwards "
                    f"{int(stats['n_stamps_backwards'])} time(s); the sample counter was kept"
                )
        else:
            t0 = 0.0
        self._check_other_clocks(name, parts.sample_rate_Hz, float(t0))
        for p in gap_at:
            start = int(e_sorted[p])
            end = start + int(hole[p])
            kind = "restart" if end in self._restarts.get(name, ()) else "gap"
            self.report.gaps.append(
                Gap(name, start, int(hole[p]), t0 + start / parts.sample_rate_Hz, kind)
            )
        return Channel(name, parts.unit, parts.sample_rate_Hz, float(t0), first, values, valid)

    def _build_slow(self, name: str, parts: _SlowParts) -> SlowSignal | None:
        if not parts.values:
            return None
        t = _join(parts.time)
        v = _join(parts.values)
        bad_t = ~np.isfinite(t)
        if bad_t.any():
            self.report.reject("non_finite_timestamp", int(bad_t.sum()), f"slow signal {name!r}")
            t, v = t[~bad_t], v[~bad_t]
        n_bad_v = int(np.count_nonzero(~np.isfinite(v)))
        if n_bad_v:  # kept as received: a NaN reading is data about the sensor
            self.report.warn(f"slow signal {name!r}: {n_bad_v} non-finite value(s), kept")
        back = int(np.count_nonzero(np.diff(t) < 0))
        if back:
            order = np.argsort(t, kind="stable")
            t, v = t[order], v[order]
            self.report.warn(
                f"slow signal {name!r}: timestamps went backwards {back} time(s); "
                "points sorted by time, none dropped"
            )
        return SlowSignal(name, parts.unit, t, v)


def _adoptable(blocks: list[_Block], complete: bool, n_dup: int) -> np.ndarray | None:
    """The channel's values if they are one gap-free, duplicate-free float64 block, else None."""
    if not (complete and n_dup == 0 and len(blocks) == 1):
        return None
    b = blocks[0]
    if b.conversion or b.raw.dtype != np.float64 or b.raw.shape[0] != 1:
        return None
    flat = b.raw.reshape(-1)
    return flat if flat.flags.c_contiguous and flat.flags.writeable else None


def _join(blocks: list[np.ndarray]) -> np.ndarray:
    """Concatenate and release the blocks (no copy for a single block)."""
    out = blocks[0] if len(blocks) == 1 else np.concatenate(blocks)
    blocks.clear()
    return out


#: A block whose rows break contiguity more often than this stays a table of rows.
MAX_RUNS_PER_BLOCK = 64


def _contiguous_runs(
    starts: np.ndarray, raw: np.ndarray
) -> list[tuple[np.ndarray, np.ndarray]]:
    """Merge consecutive rows that continue each other into single rows.

    CAN frames of one channel usually follow each other sample for sample; one row per run
    keeps the builder's row table (int64 per row) from costing as much as the samples.
    """
    m, k = raw.shape
    if m == 1:
        return [(starts, raw)]
    breaks = np.flatnonzero(np.diff(starts) != k) + 1
    if breaks.size >= MAX_RUNS_PER_BLOCK:
        return [(starts, raw)]
    bounds = [0, *breaks.tolist(), m]
    raw = np.ascontiguousarray(raw)
    return [(starts[a : a + 1], raw[a:b].reshape(1, -1)) for a, b in itertools.pairwise(bounds)]

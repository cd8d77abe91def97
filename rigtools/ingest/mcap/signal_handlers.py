"""The MCAP handlers of Imu, slow-value, scalar and mapped (generic) channels.

See :mod:`rigtools.ingest.mcap.handlers` for what each makes and the reasons they count.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from rigtools.errors import MappingError
from rigtools.ingest.builder import MAX_CLOCK_POINTS
from rigtools.ingest.layout import SlowSpec, UniformSpec
from rigtools.ingest.mcap.cdr import ImuColumns, Ros2Columns
from rigtools.ingest.mcap.decoders import Decoder, get_field, message_stamp_ns
from rigtools.ingest.mcap.handler_base import (
    DecodingHandler,
    HandlerContext,
    message_position,
)
from rigtools.ingest.mcap.records import ChannelRecord
from rigtools.ingest.mcap.timing import stamp_grid
from rigtools.ingest.mcap.walk import MessageBlock
from rigtools.ingest.timebase import indices_from_stamps

__all__ = [
    "ImuHandler",
    "MappedHandler",
    "ScalarHandler",
    "Slabs",
    "SlowValueHandler",
    "Thinned",
    "numeric_array",
]


class Slabs:
    """A 1-D array appended to block by block, in slabs (one allocation per many blocks).

    A per-sample stream hands on a few thousand samples per chunk; gathering them in slabs of
    :data:`_SLAB` values instead of one small array per chunk keeps the heap from fragmenting
    (the peak resident set stays near what the arrays hold). The first slab is smaller when
    the first block is (16 blocks' worth, at least :data:`_MIN_SLAB`): short files stay small.
    """

    def __init__(self, dtype: type) -> None:
        self.dtype = dtype
        self.full: list[np.ndarray] = []
        self.cur: np.ndarray | None = None
        self.used = 0
        self.n = 0

    def append(self, x: np.ndarray) -> None:
        """Copy ``x`` (1-D, any strides) to the end."""
        k = int(x.shape[0])
        i = 0
        while i < k:
            cur = self.cur
            if cur is None or self.used == cur.shape[0]:
                if cur is not None:
                    self.full.append(cur)
                size = _SLAB if cur is not None else min(_SLAB, max(_MIN_SLAB, 16 * k))
                cur = self.cur = np.empty(size, self.dtype)
                self.used = 0
            take = min(k - i, cur.shape[0] - self.used)
            cur[self.used : self.used + take] = x[i : i + take]
            self.used += take
            i += take
        self.n += k

    def take(self) -> np.ndarray:
        """All values as one array (a view of the slab when there is one); empties this.

        Several slabs are copied one by one into the result, each released as soon as it is
        copied: the pages of the result become resident as the slabs' are given back, so
        joining costs about one slab, not a second copy of the whole array.
        """
        parts = [*self.full, *([self.cur[: self.used]] if self.cur is not None else [])]
        n = self.n
        self.full, self.cur, self.used, self.n = [], None, 0, 0
        if not parts:
            return np.empty(0, self.dtype)
        if len(parts) == 1:
            return parts[0]
        out: np.ndarray = np.empty(n, self.dtype)
        at = 0
        parts.reverse()
        while parts:
            part = parts.pop()
            out[at : at + part.shape[0]] = part
            at += part.shape[0]
            del part
        return out


#: Stamps of a second clock kept at most (evenly spread): enough for its median offset and
#: spread, small beside a per-sample stream (512 KiB).
_OTHER_CLOCK_POINTS = 1 << 16

#: Values per slab of :class:`Slabs` (2 MiB of float64), and the least first slab.
_SLAB = 1 << 18
_MIN_SLAB = 1 << 12


class Thinned:
    """The values of a stream at positions ``0, step, 2 step, ...``, at most ``limit``.

    ``step`` (a power of two) doubles whenever more would be kept, so the values kept are
    always evenly spread over the whole stream and their positions need no storing: a
    second clock needs no more stamps than that for its statistics and median offset.
    """

    def __init__(self, limit: int) -> None:
        self.limit = limit
        self.step = 1
        self.n = 0
        self.kept = 0
        self.val: list[np.ndarray] = []

    def append(self, x: np.ndarray) -> None:
        """Take the values of ``x`` (1-D, any strides) whose position is a multiple of step."""
        k = int(x.shape[0])
        first = (-self.n) % self.step
        if first < k:
            part = np.array(x[first :: self.step])
            self.val.append(part)
            self.kept += int(part.shape[0])
        self.n += k
        while self.kept > self.limit:
            self.step *= 2
            v = np.concatenate(self.val)[::2].copy()  # positions 0, 2 step', 4 step', ...
            self.val = [v]
            self.kept = int(v.shape[0])

    def take(self) -> tuple[np.ndarray, np.ndarray]:
        """Positions (int64) and values kept; empties this."""
        val = np.concatenate(self.val) if self.val else np.empty(0)
        pos = np.arange(val.shape[0], dtype=np.int64) * self.step
        self.val, self.kept, self.n, self.step = [], 0, 0, 1
        return pos, val


class ImuHandler(DecodingHandler):
    """sensor_msgs/msg/Imu: three channels ``<topic>/linear_acceleration.x|y|z`` (m/s^2).

    The header stamps (the MCAP log times when every header stamp is zero, or when the
    context's ``clock`` is ``"log_time"``) give the rate and each sample's index:
    :func:`~rigtools.ingest.mcap.timing.stamp_grid` fits a grid
    to them, tolerant of stamp jitter (the message order when no message is missing, a
    fitted grid otherwise), and the rate is the fitted one, snapped to a value of 3
    significant digits only when within 0.1 %. Gaps and duplicates the grid shows are
    recorded by the builder, never filled. The other clock (the log times; the header stamps
    with ``clock="log_time"`` unless all zero) is handed to the builder as a second clock of
    each axis (:meth:`~rigtools.ingest.builder.RecordingBuilder.add_other_clock`), thinned
    to at most :data:`_OTHER_CLOCK_POINTS` stamps evenly spread (every ``2^k``-th message).

    A chunk whose Imu messages all have one layout (same length, encapsulation header and
    ``frame_id`` length) is read at once (:func:`~rigtools.ingest.mcap.cdr.decode_imu_cdr_many`);
    any other chunk message by message, with the same values.
    """

    def __init__(self, ctx: HandlerContext, channel: ChannelRecord, decoder: Decoder) -> None:
        super().__init__(ctx, channel, decoder)
        self.decode_many = decoder.decode_many
        self.by_log = ctx.clock == "log_time"
        # the stamps (ns) of the clock that places the channel, and the other one, thinned
        self.stamps = Slabs(np.int64)
        self.other = Thinned(_OTHER_CLOCK_POINTS)
        self.any_header = False  # some header stamp is not zero
        self.axes = (Slabs(np.float64), Slabs(np.float64), Slabs(np.float64))  # x, y, z
        # log times (ns, int64), per block: kept only while every header stamp is zero and
        # the header clock places the channel (then they place it instead)
        self.log_times: list[np.ndarray] | None = None if self.by_log else []

    def add(self, block: MessageBlock) -> None:
        """Collect header stamps, log times and accelerations (a chunk at once if it can)."""
        if block.buf is not None and block.start is not None and block.end is not None \
                and self.decode_many is not None:
            cols: ImuColumns | None = self.decode_many(block.buf, block.start, block.end)
            if cols is not None:
                self._keep(cols.stamp_ns, cols.accel, block.log_time)
                return
        stamps: list[int] = []
        rows: list[tuple[float, float, float]] = []
        logs: list[int] = []
        for _i, m, sample in self._decoded(block):
            stamps.append(sample[0])
            rows.append(sample[1:])
            logs.append(m[2])
        if rows:
            self._keep(np.asarray(stamps, np.int64), np.asarray(rows, np.float64),
                       np.asarray(logs, np.uint64))

    def _keep(self, stamps: np.ndarray, accel: np.ndarray, log_times: np.ndarray) -> None:
        logs = log_times.astype(np.int64)  # a contiguous copy: the chunk is not pinned
        nonzero = bool(np.any(stamps))
        self.any_header |= nonzero
        self.stamps.append(logs if self.by_log else stamps)
        self.other.append(stamps if self.by_log else logs)
        for k, axis in enumerate(self.axes):
            axis.append(accel[:, k])
        if self.log_times is not None:
            if nonzero:
                self.log_times = None
            else:
                self.log_times.append(logs)
        self.ctx.report.decoded += int(stamps.shape[0])

    def finish(self) -> None:
        """Hand the three axes to the builder, on the grid fitted to the stamps."""
        if not self.stamps.n:
            return
        topic = self.channel.topic
        stamps_ns = self.stamps.take()
        n = int(stamps_ns.shape[0])
        other_pos, other_ns = self.other.take()
        other_clock = "header" if self.by_log else "log_time"
        if self.by_log and not self.any_header:  # header stamps all zero: no second clock
            other_pos, other_ns = other_pos[:0], other_ns[:0]
        if self.log_times is not None:  # every header stamp is zero
            self.ctx.report.warn(f"topic {topic!r}: Imu header stamps are all zero; the "
                                 "MCAP log times are used instead")
            stamps_ns = np.concatenate(self.log_times)
            self.log_times = None
            other_pos, other_ns = other_pos[:0], other_ns[:0]
        grid = stamp_grid(stamps_ns)
        if grid is None:
            self.ctx.report.reject("no_sample_rate", n, f"topic {topic!r}")
            self.ctx.report.warn(f"topic {topic!r}: too few distinct Imu stamps to estimate "
                                 "a sample rate; give it in a mapping")
            for parts in self.axes:
                parts.take()
            return
        rate = grid.sample_rate_Hz
        how = ("the stamps against the message order (no message missing)"
               if grid.method == "order" else "a grid fitted to the stamps")
        self.ctx.report.warn(
            f"topic {topic!r}: sample rate {rate:g} Hz estimated from {how} (fitted "
            f"{grid.fitted_rate_Hz:.6g} Hz); give sample_rate_Hz in a mapping to fix it"
        )
        if grid.n_moved:
            self.ctx.report.warn(f"topic {topic!r}: {grid.n_moved} Imu sample(s) jittered into "
                                 "the slot of another and were moved to the free slot beside")
        index = grid.index
        other_index = other_pos if grid.method == "order" else index[other_pos]
        other_s = other_ns.astype(np.float64)
        other_s *= 1e-9
        del other_pos, other_ns
        if n > MAX_CLOCK_POINTS:
            # the builder checks the clock on MAX_CLOCK_POINTS stamps picked evenly: picked
            # here the same way, the rest need not be kept (the result is the same)
            pick = np.linspace(0, n - 1, MAX_CLOCK_POINTS).astype(np.int64)
            stamps_ns, stamp_index = stamps_ns[pick], index[pick]
        else:
            stamp_index = index
        t = stamps_ns.astype(np.float64)
        t *= 1e-9
        del stamps_ns
        # samples one after the other (no gap, no duplicate): placed by their first index
        start: int | np.ndarray = 0 if grid.method == "order" else index
        del index, grid
        for axis, parts in zip("xyz", self.axes, strict=True):
            values = parts.take()
            name = f"{topic}/linear_acceleration.{axis}"
            self.ctx.builder.add_samples(name, "m/s^2", rate, start, values,
                                         stamp_index=stamp_index, stamps_s=t)
            # one message, one sample of each axis: a lost message is one gap of all three
            self.ctx.builder.note_carrier(name, f"topic {topic!r}", 1)
            self.ctx.builder.add_other_clock(name, other_clock, other_index, other_s)


class SlowValueHandler(DecodingHandler):
    """rigtools.SlowValue JSON points: slow signals named by the payload (or the mapping).

    Parameters
    ----------
    ctx : HandlerContext
    channel : ChannelRecord
    decoder : Decoder
        Of kind ``"slow"``.
    spec : SlowSpec or None
        The mapping's entry for the topic: name, unit and conversion of all its points.
    """

    def __init__(self, ctx: HandlerContext, channel: ChannelRecord, decoder: Decoder,
                 spec: SlowSpec | None) -> None:
        super().__init__(ctx, channel, decoder)
        self.spec = spec
        self.points: dict[str, tuple[str, list[int], list[float]]] = {}

    def add(self, block: MessageBlock) -> None:
        """Collect points by signal; a point in another unit than its signal's is counted."""
        spec = self.spec
        for i, m, p in self._decoded(block):
            name = spec.name if spec is not None else p.name
            unit = spec.unit if spec is not None and spec.unit is not None else p.unit
            entry = self.points.get(name)
            if entry is None:
                entry = self.points[name] = (unit, [], [])
            elif entry[0] != unit:
                self.ctx.report.reject("inconsistent_unit", 1,
                                       message_position(block.where, i, m))
                self.ctx.warn_once("inconsistent_unit", name, f"slow signal {name!r}: a point "
                                   f"in {unit!r} after points in {entry[0]!r}; not used")
                continue
            entry[1].append(p.stamp_ns)
            entry[2].append(p.value)
            self.ctx.report.decoded += 1

    def finish(self) -> None:
        """Hand each signal to the builder."""
        for name, (unit, stamps, values) in self.points.items():
            v = np.asarray(values, np.float64)
            if self.spec is not None:
                with np.errstate(over="ignore", invalid="ignore"):  # Inf kept as received
                    v = v * self.spec.scale + self.spec.offset
            self.ctx.builder.add_slow(name, unit, np.asarray(stamps, np.float64) * 1e-9, v)


class ScalarHandler(DecodingHandler):
    """A ROS 2 message with one numeric field: a slow signal named after the topic.

    Its time is the MCAP log time; its unit is the channel metadata's ``unit`` (or none).
    A chunk whose messages share one CDR layout is read at once
    (:meth:`~rigtools.ingest.mcap.cdr.Ros2BlockDecoder.scalar_many`).
    """

    def __init__(self, ctx: HandlerContext, channel: ChannelRecord, decoder: Decoder) -> None:
        super().__init__(ctx, channel, decoder)
        self.decode_many = decoder.decode_many
        self.t: list[np.ndarray] = []  # log times (ns, uint64), per block
        self.v: list[np.ndarray] = []  # float64, per block

    def add(self, block: MessageBlock) -> None:
        """Collect log times and values."""
        if block.buf is not None and block.start is not None and block.end is not None \
                and self.decode_many is not None:
            values: np.ndarray | None = self.decode_many(block.buf, block.start, block.end)
            if values is not None:
                self.v.append(values)
                # a copy: a strided view (channels taking turns) would pin the chunk's column
                self.t.append(np.array(block.log_time, np.uint64))
                self.ctx.report.decoded += int(values.shape[0])
                return
        t: list[int] = []
        v: list[float] = []
        for _i, m, value in self._decoded(block):
            v.append(value)
            t.append(m[2])
        if v:
            self.v.append(np.asarray(v, np.float64))
            self.t.append(np.asarray(t, np.uint64))
            self.ctx.report.decoded += len(v)

    def finish(self) -> None:
        """Hand the signal to the builder."""
        if self.v:
            unit = self.channel.metadata.get("unit", "")
            self.ctx.builder.add_slow(self.channel.topic, unit,
                                      np.concatenate(self.t).astype(np.float64) * 1e-9,
                                      np.concatenate(self.v))


def numeric_array(value: Any) -> np.ndarray | None:
    """``value`` as a flat float64 array when it is a number or an array of numbers."""
    if isinstance(value, str | bytes):
        return None
    try:
        arr = np.asarray(value)
    except (TypeError, ValueError, OverflowError, RecursionError):
        return None
    if arr.dtype.kind not in "biuf":  # strings, objects (nested messages, huge integers)
        return None
    return arr.astype(np.float64).ravel()


@dataclass
class _FieldTally:
    """What the messages of a topic held under one mapped field."""

    found: int = 0  # messages that have the field
    usable: int = 0  # ... and a value of the kind the entry needs
    missing: str = ""  # the first "no field" text
    unusable: str = ""  # the first unusable value


class MappedHandler(DecodingHandler):
    """Any decodable message: the mapping's dotted fields become uniform or slow signals.

    A message that lacks one of the mapped fields is counted ``missing_field``, one whose
    field is not numeric (or not a scalar, for a slow signal) ``decode_error``, each with its
    position; the other messages are read.

    Parameters
    ----------
    ctx : HandlerContext
    channel : ChannelRecord
    decoder : Decoder
        Usually of kind ``"generic"`` (the whole decoded message).
    specs : list of UniformSpec or SlowSpec
        The mapping's entries for the topic, each naming a field path.

    Raises
    ------
    MappingError
        From :meth:`finish`: a field path none of the topic's messages has, or whose value
        is in none of them numeric (a scalar, for a slow signal); it names the mapping, the
        recording and the topic.
    """

    def __init__(self, ctx: HandlerContext, channel: ChannelRecord, decoder: Decoder,
                 specs: list[UniformSpec | SlowSpec]) -> None:
        super().__init__(ctx, channel, decoder)
        self.specs = specs
        self.decode_many = decoder.decode_many
        self.paths = [spec.field or "" for spec in specs]
        self.scalar = [isinstance(spec, SlowSpec) for spec in specs]
        self.by_log = ctx.clock == "log_time"
        self.stamps: list[np.ndarray] = []  # float64 (ns), per block: the placing clock
        self.others: list[np.ndarray] = []  # float64 (ns), per block: the other (NaN: none)
        self.cols: list[list[np.ndarray]] = [[] for _ in specs]  # flat float64, per block
        self.counts: list[list[np.ndarray]] = [[] for _ in specs]  # values per message
        self.tally = [_FieldTally() for _ in specs]
        self.n_payloads = 0

    def _stamp(self, logs: np.ndarray, header: np.ndarray | None) -> None:
        """Keep a block's stamps (ns, float64; ``header`` NaN where a message has none)."""
        if header is None:
            self.stamps.append(logs)
            self.others.append(np.full(logs.shape[0], np.nan))
            return
        if self.by_log:
            self.stamps.append(logs)
            self.others.append(header)
            return
        none = np.isnan(header)
        if none.any():  # no header stamp: the log time places the message
            header = np.where(none, logs, header)
            logs = np.where(none, np.nan, logs)
        self.stamps.append(header)
        self.others.append(logs)

    def add(self, block: MessageBlock) -> None:
        """Collect each mapped field and the message's stamps (header stamp and log time).

        The context's ``clock`` decides which places the message: ``"header"``, the header
        stamp (the log time for a message without one), ``"log_time"``, the log time; the
        other is kept as the channel's second clock.

        A chunk of ROS 2 messages of one layout is read at once
        (:meth:`~rigtools.ingest.mcap.cdr.Ros2BlockDecoder.columns`), with the same values.
        """
        if block.buf is not None and block.start is not None and block.end is not None \
                and self.decode_many is not None:
            cols: Ros2Columns | None = self.decode_many(block.buf, block.start, block.end,
                                                        self.paths, self.scalar)
            if cols is not None:
                m = len(block)
                self.n_payloads += m
                for tally in self.tally:
                    tally.found += m
                    tally.usable += m
                header = None if cols.stamp_ns is None else cols.stamp_ns.astype(np.float64)
                self._stamp(block.log_time.astype(np.float64), header)
                for col, counts, vals in zip(self.cols, self.counts, cols.values, strict=True):
                    col.append(vals.reshape(-1))
                    counts.append(np.full(m, vals.shape[1], np.int64))
                self.ctx.report.decoded += m
                return
        stamps: list[float] = []  # header stamps (NaN: none)
        logs: list[int] = []
        rows: list[list[np.ndarray]] = [[] for _ in self.specs]
        for i, m_, obj in self._decoded(block):
            self.n_payloads += 1
            row: list[np.ndarray] = []
            reason = ""
            for spec, tally in zip(self.specs, self.tally, strict=True):
                try:
                    raw = get_field(obj, spec.field or "")
                except KeyError as exc:
                    tally.missing = tally.missing or str(exc).strip("'\"")
                    reason = reason or "missing_field"
                    continue
                tally.found += 1
                arr = numeric_array(raw)
                if arr is None or (isinstance(spec, SlowSpec) and arr.size != 1):
                    tally.unusable = tally.unusable or _short(raw)
                    reason = reason or "decode_error"
                    continue
                tally.usable += 1
                row.append(arr)
            if reason:
                where = message_position(block.where, i, m_)
                self.ctx.report.reject(reason, 1, where)
                self.ctx.warn_once(reason, self.channel.id, f"{self.ctx.path}: topic "
                                   f"{self.channel.topic!r}: a message at {where} lacks a "
                                   "mapped field or holds no number there; such messages are "
                                   f"counted as {reason}")
                continue
            stamp = message_stamp_ns(obj)
            stamps.append(np.nan if stamp is None else stamp)
            logs.append(m_[2])
            for col, val in zip(rows, row, strict=True):
                col.append(val)
            self.ctx.report.decoded += 1
        if not stamps:
            return
        header = np.asarray(stamps, np.float64)
        self._stamp(np.asarray(logs, np.uint64).astype(np.float64),
                    None if np.isnan(header).all() else header)
        for col, counts, arrays in zip(self.cols, self.counts, rows, strict=True):
            col.append(np.concatenate(arrays))
            counts.append(np.asarray([a.size for a in arrays], np.int64))

    def _check(self) -> None:
        """Refuse a mapping whose field no message of the topic has (or holds usably)."""
        where = f"topic {self.channel.topic!r} of {self.ctx.path}"
        for spec, tally in zip(self.specs, self.tally, strict=True):
            if self.n_payloads and not tally.found:
                raise MappingError(self.ctx.mapping_source, where,
                                   "a field path that exists in the messages", repr(spec.field),
                                   f"none of the {self.n_payloads} decoded messages has it "
                                   f"({tally.missing})")
            if tally.found and not tally.usable:
                what = "a scalar numeric field for a slow signal" \
                    if isinstance(spec, SlowSpec) else "a numeric field"
                raise MappingError(self.ctx.mapping_source, where, what,
                                   f"{spec.field!r} = {tally.unusable}",
                                   f"in all {tally.found} messages that have it")

    def finish(self) -> None:
        """Hand each mapped field to the builder as the signal its entry names."""
        self._check()
        if not self.stamps:
            return
        t = np.concatenate(self.stamps) * 1e-9
        t_other = np.concatenate(self.others) * 1e-9
        other_clock = "header" if self.by_log else "log_time"
        for spec, arrays, counts_parts in zip(self.specs, self.cols, self.counts, strict=True):
            unit = spec.unit if spec.unit is not None else self.channel.metadata.get("unit", "")
            with np.errstate(over="ignore", invalid="ignore"):  # Inf kept, counted later
                values = np.concatenate(arrays) * spec.scale + spec.offset
            if isinstance(spec, SlowSpec):
                self.ctx.builder.add_slow(spec.name, unit, t, values)
                continue
            rate = spec.sample_rate_Hz
            counts = np.concatenate(counts_parts)
            idx0 = indices_from_stamps(t, rate)
            idx0 -= idx0.min()
            starts = np.cumsum(counts) - counts
            index = np.arange(int(counts.sum()), dtype=np.int64)
            index += np.repeat(idx0 - starts, counts)
            keep = counts > 0
            self.ctx.builder.add_samples(spec.channel, unit, rate, index, values,
                                         stamp_index=idx0[keep], stamps_s=t[keep])
            if counts.size and bool(np.all(counts == 1)):  # one sample per message
                self.ctx.builder.note_carrier(spec.channel, f"topic {self.channel.topic!r}", 1)
            self.ctx.builder.add_other_clock(spec.channel, other_clock, idx0[keep],
                                             t_other[keep])


def _short(value: Any, limit: int = 40) -> str:
    try:
        text = repr(value)
    except RecursionError:
        return "a deeply nested value"
    return text if len(text) <= limit else text[: limit - 3] + "..."

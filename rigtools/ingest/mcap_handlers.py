"""Per-channel handlers of the MCAP ingest: decoded messages in, builder input out.

The ingest (:func:`rigtools.ingest.mcap.ingest`) gives each channel one handler, chosen from
the channel's :class:`~rigtools.ingest.mcap_decoders.Decoder` and the mapping. A handler
receives the channel's messages block by block (:meth:`ChannelHandler.add`: a
:class:`~rigtools.ingest.mcap_container.MessageBlock` of the channel's messages of one chunk),
decodes them as they come and hands what it gathered to the
:class:`~rigtools.ingest.builder.RecordingBuilder` at the end of the file
(:meth:`ChannelHandler.finish`), once names and time bases can be settled over the whole file.

==========================  =====================================================  ===========
handler                     what it makes                                          when
==========================  =====================================================  ===========
:class:`BatchHandler`       a uniform channel indexed by the batches' counters     at the end
:class:`ImuHandler`         ``<topic>/linear_acceleration.x|y|z`` (m/s^2)          at the end
:class:`SlowValueHandler`   slow signals named by the payload or the mapping       at the end
:class:`ScalarHandler`      a slow signal named after the topic                    at the end
:class:`MappedHandler`      the mapping's dotted fields, as uniform or slow        at the end
:class:`RejectHandler`      nothing: counts every message under one reason         per block
==========================  =====================================================  ===========

A payload that does not decode is counted as ``decode_error`` (first position: the chunk and
the message record's offset in it), and the channel goes on. Besides, the handlers count

=====================  ======================================================================
reason                 what happened
=====================  ======================================================================
``empty_batch``        an AccelBatch with no values (it carries nothing to place)
``missing_field``      a message lacks a field the mapping names (the field is in others)
``no_sample_rate``     too few distinct Imu stamps to estimate a rate
``inconsistent_unit``  a slow point in another unit than the earlier points of its signal
=====================  ======================================================================

AccelBatch channels named alike on several topics are kept apart as ``<channel>@<topic>``;
a counter that restarts is resynchronised from the stamps
(:func:`~rigtools.ingest.mcap_timing.resync_counter_restarts`); Imu messages are laid on a
grid fitted to their stamps (:func:`~rigtools.ingest.mcap_timing.stamp_grid`).
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from rigtools.errors import MappingError
from rigtools.ingest.builder import RecordingBuilder
from rigtools.ingest.layout import SlowSpec, UniformSpec
from rigtools.ingest.mcap_container import MessageBlock, ScannedMessage
from rigtools.ingest.mcap_decoders import (
    AccelBatchColumns,
    Decoder,
    PayloadDecodeError,
    get_field,
    message_stamp_ns,
)
from rigtools.ingest.mcap_records import (
    MESSAGE_HEADER_BYTES,
    RECORD_HEADER_BYTES,
    ChannelRecord,
)
from rigtools.ingest.mcap_timing import estimate_rate, resync_counter_restarts, stamp_grid
from rigtools.ingest.recording import IngestReport
from rigtools.ingest.timebase import indices_from_stamps

__all__ = [
    "MIN_SLAB_VALUES",
    "SLAB_VALUES",
    "BatchHandler",
    "ChannelHandler",
    "DecodingHandler",
    "HandlerContext",
    "ImuHandler",
    "MappedHandler",
    "RejectHandler",
    "ScalarHandler",
    "SlowValueHandler",
    "estimate_rate",
    "message_position",
]


@dataclass
class HandlerContext:
    """What every handler of one ingest shares.

    Attributes
    ----------
    path : str
        Source path, for messages.
    builder : RecordingBuilder
        Receives uniform channels and slow signals.
    report : IngestReport
        Receives the tallies and warnings.
    mapping_source : str
        Where the mapping came from, for :class:`~rigtools.errors.MappingError`.
    """

    path: str
    builder: RecordingBuilder
    report: IngestReport
    mapping_source: str
    _warned: set[tuple[str, object]] = field(default_factory=set)

    def warn_once(self, reason: str, key: object, text: str) -> None:
        """Warn with ``text`` the first time ``(reason, key)`` comes up."""
        if (reason, key) not in self._warned:
            self._warned.add((reason, key))
            self.report.warn(text)


class ChannelHandler:
    """Turns the messages of one channel into builder input; subclasses per payload kind.

    Parameters
    ----------
    ctx : HandlerContext
    channel : ChannelRecord
    """

    def __init__(self, ctx: HandlerContext, channel: ChannelRecord) -> None:
        self.ctx = ctx
        self.channel = channel

    def add(self, block: MessageBlock) -> None:
        """Take one block of the channel's messages (in file order).

        ``block.where`` tells where it was found, for tallies; ``block.buf`` is the block's
        common buffer (a chunk's uncompressed data) when it has one.
        """
        raise NotImplementedError

    def finish(self) -> None:
        """Hand anything collected over the whole file to the builder."""


class RejectHandler(ChannelHandler):
    """A channel none of whose messages is used: each counts under ``reason``."""

    def __init__(self, ctx: HandlerContext, channel: ChannelRecord, reason: str) -> None:
        super().__init__(ctx, channel)
        self.reason = reason

    def add(self, block: MessageBlock) -> None:
        """Count the block's messages."""
        self.ctx.report.reject(self.reason, len(block), block.where)


#: Bytes of a Message record ahead of its payload (record header and message header).
_PAYLOAD_OFFSET = RECORD_HEADER_BYTES + MESSAGE_HEADER_BYTES
#: Restarts warned about one by one, per channel; the rest are summed up.
_MAX_RESTART_WARNINGS = 5


def message_position(where: str, i: int, m: ScannedMessage) -> str:
    """Where message ``m`` (the ``i``-th of a block found at ``where``) lies, for tallies.

    ``"chunk at byte 1234 +567"`` (the chunk's position in the file, the message record's
    offset in its uncompressed records) for a chunk's message; for messages found outside
    chunks, the block's position and the message's rank in it.
    """
    if m[5] >= 0:
        return f"chunk at {where} +{m[5] - _PAYLOAD_OFFSET}"
    return f"{where}, message {i + 1} from there"


class DecodingHandler(ChannelHandler):
    """A handler that decodes each payload with its channel's decoder."""

    def __init__(self, ctx: HandlerContext, channel: ChannelRecord, decoder: Decoder) -> None:
        super().__init__(ctx, channel)
        self.decode = decoder.decode

    def _decoded(self, block: MessageBlock) -> Iterator[tuple[int, ScannedMessage, Any]]:
        """Each message (rank in the block, message, decoded payload); failures are counted.

        Besides :class:`PayloadDecodeError`, a payload whose numbers overflow or whose
        nesting exhausts the recursion limit counts as ``decode_error``: no such exception
        leaves the reader.
        """
        decode = self.decode
        for i, m in enumerate(block.messages()):
            try:
                payload = decode(m[4])
            except (PayloadDecodeError, OverflowError, RecursionError) as exc:
                self._decode_error(exc, message_position(block.where, i, m))
                continue
            yield i, m, payload

    def _decode_error(self, exc: Exception, where: str) -> None:
        self.ctx.report.reject("decode_error", 1, where)
        self.ctx.warn_once("decode_error", self.channel.id,
                           f"{self.ctx.path}: topic {self.channel.topic!r}: payload does not "
                           f"decode ({exc}) at {where}; such messages are counted as "
                           "decode_error")


@dataclass
class _BatchAcc:
    """Per-message decoded batches of one (channel, unit, rate), within one chunk."""

    firsts: list[int] = field(default_factory=list)
    stamps: list[int] = field(default_factory=list)
    counts: list[int] = field(default_factory=list)
    values: list[np.ndarray] = field(default_factory=list)


#: Samples per slab a :class:`BatchHandler` cuts its decoded values from (8 MiB of float32);
#: the first slab of a channel is smaller when its first block is (32 blocks' worth, at least
#: :data:`MIN_SLAB_VALUES`); a block larger than a slab gets its own.
SLAB_VALUES = 1 << 21
MIN_SLAB_VALUES = 1 << 16

#: 2-D blocks for the builder: row counters (int64), float32 rows, row stamps (ns, uint64).
_Blocks = list[tuple[np.ndarray, np.ndarray, np.ndarray]]
#: What the payloads of a batch name: channel, unit, rate.
_BatchKey = tuple[str, str, float]


class BatchHandler(DecodingHandler):
    """rigtools.AccelBatch: the sample counter gives the index; one builder block per chunk.

    The blocks are kept until :meth:`finish` (the builder would keep them as long): only
    then are the channel names known to be unique across topics
    (:meth:`rename_shared`) and a counter restart can be told from a late or corrupt batch
    by the batches after it.

    Parameters
    ----------
    ctx : HandlerContext
    channel : ChannelRecord
    decoder : Decoder
        Of kind ``"batch"``; its ``decode_many`` (when it has one) decodes a whole chunk.
    spec : UniformSpec or None
        The mapping's entry for the topic: channel name, unit, rate and conversion.
    """

    def __init__(self, ctx: HandlerContext, channel: ChannelRecord, decoder: Decoder,
                 spec: UniformSpec | None) -> None:
        super().__init__(ctx, channel, decoder)
        self.decode_many = decoder.decode_many
        self.spec = spec
        self.rate_warned = False
        self._slab: np.ndarray | None = None
        self._slab_used = 0
        self._blocks: list[tuple[_BatchKey, np.ndarray, np.ndarray, np.ndarray]] = []
        self._renamed: dict[str, str] = {}

    def _values_out(self, m: int, k: int) -> np.ndarray:
        """Room for ``m`` rows of ``k`` float32 values, cut from the channel's current slab.

        The builder keeps every block until the end of the file; one large allocation per
        :data:`SLAB_VALUES` samples instead of one per chunk saves the page faults of many
        fresh buffers (arrays of 4 MiB and more are backed by huge pages where the system
        offers them). A slab lives as long as any block cut from it; its untouched tail costs
        address space only.
        """
        n = m * k
        slab = self._slab
        if slab is None or slab.shape[0] - self._slab_used < n:
            size = SLAB_VALUES if slab is not None else \
                min(SLAB_VALUES, max(MIN_SLAB_VALUES, 32 * n))
            slab = self._slab = np.empty(max(n, size), np.float32)
            self._slab_used = 0
        out = slab[self._slab_used : self._slab_used + n].reshape(m, k)
        self._slab_used += n
        return out

    def add(self, block: MessageBlock) -> None:
        """Decode a block (all at once when it allows) and keep it for :meth:`finish`."""
        if block.buf is not None and block.start is not None and block.end is not None \
                and self.decode_many is not None and len(block) > 1:
            cols: AccelBatchColumns | None = self.decode_many(block.buf, block.start, block.end,
                                                              self._values_out)
            if cols is not None:
                self.ctx.report.decoded += len(block)
                self._keep((cols.channel, cols.unit, cols.sample_rate_Hz),
                           [(cols.first_sample_index, cols.values, cols.stamp_ns)])
                return
        accs: dict[_BatchKey, _BatchAcc] = {}
        n_ok = 0
        for i, m, b in self._decoded(block):
            if b.values.shape[0] == 0:
                self.ctx.report.reject("empty_batch", 1, message_position(block.where, i, m))
                continue
            n_ok += 1
            key = (b.channel, b.unit, b.sample_rate_Hz)
            acc = accs.get(key)
            if acc is None:
                acc = accs[key] = _BatchAcc()
            acc.firsts.append(b.first_sample_index)
            acc.stamps.append(b.stamp_ns)
            acc.counts.append(b.values.shape[0])
            acc.values.append(b.values)
        self.ctx.report.decoded += n_ok
        for key, acc in accs.items():
            blocks = _equal_width_runs(acc)
            acc.values.clear()
            self._keep(key, blocks)

    def _keep(self, key: _BatchKey, blocks: _Blocks) -> None:
        spec = self.spec
        if spec is not None and not self.rate_warned and \
                not math.isclose(key[2], spec.sample_rate_Hz, rel_tol=1e-9):
            self.rate_warned = True
            self.ctx.report.warn(f"topic {self.channel.topic!r}: batches state "
                                 f"{key[2]} Hz, the mapping {spec.sample_rate_Hz} Hz; the "
                                 "mapping's rate is used")
        for starts, values, stamps_ns in blocks:
            self._blocks.append((key, starts, values, stamps_ns))

    def _name(self, key: _BatchKey) -> str:
        """The channel a batch goes to, before :meth:`rename_shared`."""
        if self.spec is not None:
            return self.spec.channel
        return key[0] or self.channel.topic.lstrip("/") or f"channel_{self.channel.id}"

    def channel_names(self) -> set[str]:
        """The channels the payloads name (the mapping's, when it has an entry)."""
        return {self._name(key) for key in dict.fromkeys(b[0] for b in self._blocks)}

    def rename_shared(self, shared: set[str]) -> None:
        """Send the payload-named channels in ``shared`` to ``<channel>@<topic>``.

        ``shared``: names that payloads on other topics give too. A mapping's channel names
        stay as the mapping says.
        """
        if self.spec is None:
            self._renamed = {name: f"{name}@{self.channel.topic}"
                             for name in self.channel_names() & shared}

    def finish(self) -> None:
        """Resynchronise counter restarts and hand every block to the builder."""
        if not self._blocks:
            return
        spec = self.spec
        by_key: dict[_BatchKey, list[int]] = {}
        for bi, (key, *_rest) in enumerate(self._blocks):
            by_key.setdefault(key, []).append(bi)
        for key, bis in by_key.items():
            self._resync(key, bis)
        conversion: tuple[tuple[float, float], ...] = ()
        if spec is not None and (spec.scale != 1.0 or spec.offset != 0.0):
            conversion = ((spec.scale, spec.offset),)
        blocks, self._blocks = self._blocks, []
        for key, starts, values, stamps_ns in blocks:
            name = self._name(key)
            name = self._renamed.get(name, name)
            unit, rate = key[1], key[2]
            if spec is not None:
                rate = spec.sample_rate_Hz
                unit = spec.unit if spec.unit is not None else unit
            # the stamp of values[0] of each row, on the row's counter: places index 0 on the
            # logger clock (the builder drops both if the block's unit or rate differ)
            self.ctx.builder.add_samples(name, unit, rate, starts, values, stamp_index=starts,
                                         stamps_s=stamps_ns.astype(np.float64) * 1e-9,
                                         conversion=conversion)

    def _resync(self, key: _BatchKey, bis: list[int]) -> None:
        """Find counter restarts among the rows of one payload channel and move them."""
        parts = [self._blocks[bi] for bi in bis]
        starts = np.concatenate([p[1] for p in parts]) if len(parts) > 1 else parts[0][1]
        stamps = np.concatenate([p[3] for p in parts]) if len(parts) > 1 else parts[0][3]
        rate = self.spec.sample_rate_Hz if self.spec is not None else key[2]
        if starts.shape[0] < 2:
            return
        widths = np.concatenate([np.full(p[1].shape[0], p[2].shape[1], np.int64)
                                 for p in parts])
        new, restarts = resync_counter_restarts(starts, stamps, widths, rate)
        if not restarts:
            return
        name = self._name(key)
        name = self._renamed.get(name, name)
        lo = 0
        for bi, p in zip(bis, parts, strict=True):
            m = p[1].shape[0]
            self._blocks[bi] = (p[0], new[lo : lo + m], p[2], p[3])
            lo += m
        for r in restarts:
            self.ctx.builder.mark_restart(name, r.index)
        for r in restarts[:_MAX_RESTART_WARNINGS]:
            self.ctx.report.warn(
                f"{self.ctx.path}: topic {self.channel.topic!r}, channel {name!r}: the sample "
                f"counter went back to {r.counter} (after index {r.previous_index}) while the "
                f"stamps went on (stamp_ns {r.stamp_ns}): a counter restart, resynchronised "
                f"from the stamps to continue at index {r.index}; no sample dropped")
        if len(restarts) > _MAX_RESTART_WARNINGS:
            self.ctx.report.warn(
                f"{self.ctx.path}: topic {self.channel.topic!r}, channel {name!r}: "
                f"{len(restarts)} counter restarts in all, each resynchronised from the stamps")


def _equal_width_runs(acc: _BatchAcc) -> _Blocks:
    """Runs of consecutive batches of equal width as 2-D blocks, in arrival order.

    Row starts are the batches' counters; empty batches add nothing.
    """
    firsts = np.asarray(acc.firsts, np.int64)
    stamps = np.asarray(acc.stamps, np.uint64)
    counts = acc.counts
    blocks: _Blocks = []
    i = 0
    while i < len(counts):
        j = i + 1
        while j < len(counts) and counts[j] == counts[i]:
            j += 1
        if counts[i]:
            vals = np.concatenate(acc.values[i:j]).reshape(j - i, counts[i])
            blocks.append((firsts[i:j], vals, stamps[i:j]))
        i = j
    return blocks


class ImuHandler(DecodingHandler):
    """sensor_msgs/msg/Imu: three channels ``<topic>/linear_acceleration.x|y|z`` (m/s^2).

    The header stamps (the MCAP log times when every header stamp is zero) give the rate
    and each sample's index: :func:`~rigtools.ingest.mcap_timing.stamp_grid` fits a grid
    to them, tolerant of stamp jitter (the message order when no message is missing, a
    fitted grid otherwise), and the rate is the fitted one, snapped to a value of 3
    significant digits only when within 0.1 %.
    """

    def __init__(self, ctx: HandlerContext, channel: ChannelRecord, decoder: Decoder) -> None:
        super().__init__(ctx, channel, decoder)
        self.rows: list[tuple[int, float, float, float]] = []
        self.log_times: list[int] = []

    def add(self, block: MessageBlock) -> None:
        """Collect header stamps and accelerations."""
        rows, logs = self.rows, self.log_times
        n0 = len(rows)
        for _i, m, sample in self._decoded(block):
            rows.append(sample)
            logs.append(m[2])
        self.ctx.report.decoded += len(rows) - n0

    def finish(self) -> None:
        """Hand the three axes to the builder, on the grid fitted to the stamps."""
        if not self.rows:
            return
        topic = self.channel.topic
        arr = np.asarray(self.rows, np.float64)
        stamps_ns = np.asarray([r[0] for r in self.rows], np.int64)
        if not np.any(stamps_ns):
            self.ctx.report.warn(f"topic {topic!r}: Imu header stamps are all zero; the "
                                 "MCAP log times are used instead")
            stamps_ns = np.asarray(self.log_times, np.uint64).astype(np.int64)
        t = stamps_ns.astype(np.float64) * 1e-9
        grid = stamp_grid(stamps_ns)
        if grid is None:
            self.ctx.report.reject("no_sample_rate", len(self.rows), f"topic {topic!r}")
            self.ctx.report.warn(f"topic {topic!r}: too few distinct Imu stamps to estimate "
                                 "a sample rate; give it in a mapping")
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
        for k, axis in enumerate("xyz", start=1):
            self.ctx.builder.add_samples(f"{topic}/linear_acceleration.{axis}", "m/s^2", rate,
                                         index, arr[:, k], stamp_index=index, stamps_s=t)


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
    """

    def __init__(self, ctx: HandlerContext, channel: ChannelRecord, decoder: Decoder) -> None:
        super().__init__(ctx, channel, decoder)
        self.t: list[int] = []
        self.v: list[float] = []

    def add(self, block: MessageBlock) -> None:
        """Collect log times and values."""
        for _i, m, value in self._decoded(block):
            self.v.append(value)
            self.t.append(m[2])
            self.ctx.report.decoded += 1

    def finish(self) -> None:
        """Hand the signal to the builder."""
        if self.v:
            unit = self.channel.metadata.get("unit", "")
            self.ctx.builder.add_slow(self.channel.topic, unit,
                                      np.asarray(self.t, np.float64) * 1e-9,
                                      np.asarray(self.v, np.float64))


def _numeric(value: Any) -> np.ndarray | None:
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
        self.stamps: list[int] = []
        self.cols: list[list[np.ndarray]] = [[] for _ in specs]
        self.tally = [_FieldTally() for _ in specs]
        self.n_payloads = 0

    def add(self, block: MessageBlock) -> None:
        """Collect each mapped field and the message's stamp (header stamp, else log time)."""
        for i, m, obj in self._decoded(block):
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
                arr = _numeric(raw)
                if arr is None or (isinstance(spec, SlowSpec) and arr.size != 1):
                    tally.unusable = tally.unusable or _short(raw)
                    reason = reason or "decode_error"
                    continue
                tally.usable += 1
                row.append(arr)
            if reason:
                where = message_position(block.where, i, m)
                self.ctx.report.reject(reason, 1, where)
                self.ctx.warn_once(reason, self.channel.id, f"{self.ctx.path}: topic "
                                   f"{self.channel.topic!r}: a message at {where} lacks a "
                                   "mapped field or holds no number there; such messages are "
                                   f"counted as {reason}")
                continue
            stamp = message_stamp_ns(obj)
            self.stamps.append(m[2] if stamp is None else stamp)
            for col, val in zip(self.cols, row, strict=True):
                col.append(val)
            self.ctx.report.decoded += 1

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
        t = np.asarray(self.stamps, np.float64) * 1e-9
        for spec, arrays in zip(self.specs, self.cols, strict=True):
            unit = spec.unit if spec.unit is not None else self.channel.metadata.get("unit", "")
            with np.errstate(over="ignore", invalid="ignore"):  # Inf kept, counted later
                values = np.concatenate(arrays) * spec.scale + spec.offset
            if isinstance(spec, SlowSpec):
                self.ctx.builder.add_slow(spec.name, unit, t, values)
                continue
            rate = spec.sample_rate_Hz
            counts = np.asarray([a.size for a in arrays], np.int64)
            idx0 = indices_from_stamps(t, rate)
            idx0 -= idx0.min()
            starts = np.cumsum(counts) - counts
            index = np.arange(int(counts.sum()), dtype=np.int64)
            index += np.repeat(idx0 - starts, counts)
            keep = counts > 0
            self.ctx.builder.add_samples(spec.channel, unit, rate, index, values,
                                         stamp_index=idx0[keep], stamps_s=t[keep])


def _short(value: Any, limit: int = 40) -> str:
    try:
        text = repr(value)
    except RecursionError:
        return "a deeply nested value"
    return text if len(text) <= limit else text[: limit - 3] + "..."

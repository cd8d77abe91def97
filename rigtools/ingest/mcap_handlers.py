"""Per-channel handlers of the MCAP ingest: decoded messages in, builder input out.

The ingest (:func:`rigtools.ingest.mcap.ingest`) gives each channel one handler, chosen from
the channel's :class:`~rigtools.ingest.mcap_decoders.Decoder` and the mapping. A handler
receives the channel's messages block by block (:meth:`ChannelHandler.add`: a
:class:`~rigtools.ingest.mcap_container.MessageBlock` of the channel's messages of one chunk)
and hands what it gathered to the :class:`~rigtools.ingest.builder.RecordingBuilder`, per
block or at the end of the file (:meth:`ChannelHandler.finish`).

==========================  =====================================================  ===========
handler                     what it makes                                          when
==========================  =====================================================  ===========
:class:`BatchHandler`       a uniform channel indexed by the batches' counters     per block
:class:`ImuHandler`         ``<topic>/linear_acceleration.x|y|z`` (m/s^2)          at the end
:class:`SlowValueHandler`   slow signals named by the payload or the mapping       at the end
:class:`ScalarHandler`      a slow signal named after the topic                    at the end
:class:`MappedHandler`      the mapping's dotted fields, as uniform or slow        at the end
:class:`RejectHandler`      nothing: counts every message under one reason         per block
==========================  =====================================================  ===========

A payload that does not decode is counted as ``decode_error``; the channel goes on.
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
from rigtools.ingest.mcap_records import ChannelRecord
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


class DecodingHandler(ChannelHandler):
    """A handler that decodes each payload with its channel's decoder."""

    def __init__(self, ctx: HandlerContext, channel: ChannelRecord, decoder: Decoder) -> None:
        super().__init__(ctx, channel)
        self.decode = decoder.decode

    def _decoded(self, block: MessageBlock) -> Iterator[tuple[ScannedMessage, Any]]:
        """Each message with its decoded payload; one that does not decode is counted."""
        decode = self.decode
        where = block.where
        for m in block.messages():
            try:
                payload = decode(m[4])
            except PayloadDecodeError as exc:
                self._decode_error(exc, where)
                continue
            yield m, payload

    def _decode_error(self, exc: Exception, where: str) -> None:
        self.ctx.report.reject("decode_error", 1, where)
        self.ctx.warn_once("decode_error", self.channel.id,
                           f"{self.ctx.path}: topic {self.channel.topic!r}: payload does not "
                           f"decode ({exc}); such messages are counted as decode_error")


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


class BatchHandler(DecodingHandler):
    """rigtools.AccelBatch: the sample counter gives the index; one builder block per chunk.

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
        """Decode a block (all at once when it allows) and hand it to the builder."""
        if block.buf is not None and block.start is not None and block.end is not None \
                and self.decode_many is not None and len(block) > 1:
            cols: AccelBatchColumns | None = self.decode_many(block.buf, block.start, block.end,
                                                              self._values_out)
            if cols is not None:
                self.ctx.report.decoded += len(block)
                self._flush(cols.channel, cols.unit, cols.sample_rate_Hz,
                            [(cols.first_sample_index, cols.values, cols.stamp_ns)])
                return
        accs: dict[tuple[str, str, float], _BatchAcc] = {}
        n_ok = 0
        for _m, b in self._decoded(block):
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
        for (name, unit, rate), acc in accs.items():
            blocks = _equal_width_runs(acc)
            acc.values.clear()
            self._flush(name, unit, rate, blocks)

    def _flush(self, name: str, unit: str, rate: float, blocks: _Blocks) -> None:
        """Hand 2-D blocks (row counters, float32 rows, row stamps in ns) to the builder."""
        spec = self.spec
        conversion: tuple[tuple[float, float], ...] = ()
        if spec is not None:
            if not self.rate_warned and not math.isclose(rate, spec.sample_rate_Hz,
                                                         rel_tol=1e-9):
                self.rate_warned = True
                self.ctx.report.warn(f"topic {self.channel.topic!r}: batches state "
                                     f"{rate} Hz, the mapping {spec.sample_rate_Hz} Hz; the "
                                     "mapping's rate is used")
            name, rate = spec.channel, spec.sample_rate_Hz
            unit = spec.unit if spec.unit is not None else unit
            if spec.scale != 1.0 or spec.offset != 0.0:
                conversion = ((spec.scale, spec.offset),)
        elif not name:
            name = self.channel.topic.lstrip("/") or f"channel_{self.channel.id}"
        for starts, values, stamps_ns in blocks:
            # the stamp of values[0] of each row, on the row's counter: places index 0 on the
            # logger clock (the builder drops both if the block's unit or rate differ)
            self.ctx.builder.add_samples(name, unit, rate, starts, values, stamp_index=starts,
                                         stamps_s=stamps_ns.astype(np.float64) * 1e-9,
                                         conversion=conversion)


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

    The sample rate is estimated from the header stamps (:func:`estimate_rate`), which place
    each sample on the grid; the MCAP log times stand in when every header stamp is zero.
    """

    def __init__(self, ctx: HandlerContext, channel: ChannelRecord, decoder: Decoder) -> None:
        super().__init__(ctx, channel, decoder)
        self.rows: list[tuple[int, float, float, float]] = []
        self.log_times: list[int] = []

    def add(self, block: MessageBlock) -> None:
        """Collect header stamps and accelerations."""
        rows, logs = self.rows, self.log_times
        n0 = len(rows)
        for m, sample in self._decoded(block):
            rows.append(sample)
            logs.append(m[2])
        self.ctx.report.decoded += len(rows) - n0

    def finish(self) -> None:
        """Hand the three axes to the builder, on the grid of the estimated rate."""
        if not self.rows:
            return
        topic = self.channel.topic
        arr = np.asarray(self.rows, np.float64)
        stamps_ns = np.asarray([r[0] for r in self.rows], np.int64)
        if not np.any(stamps_ns):
            self.ctx.report.warn(f"topic {topic!r}: Imu header stamps are all zero; the "
                                 "MCAP log times are used instead")
            stamps_ns = np.asarray(self.log_times, np.int64)
        t = stamps_ns.astype(np.float64) * 1e-9
        rate = estimate_rate(np.sort(stamps_ns))
        if rate is None:
            self.ctx.report.reject("no_sample_rate", len(self.rows), f"topic {topic!r}")
            self.ctx.report.warn(f"topic {topic!r}: too few distinct Imu stamps to estimate "
                                 "a sample rate; give it in a mapping")
            return
        self.ctx.report.warn(
            f"topic {topic!r}: sample rate {rate:g} Hz estimated from the median Imu header "
            "stamp interval; give sample_rate_Hz in a mapping to fix it"
        )
        index = indices_from_stamps(t, rate)
        index -= index.min()
        for k, axis in enumerate("xyz", start=1):
            self.ctx.builder.add_samples(f"{topic}/linear_acceleration.{axis}", "m/s^2", rate,
                                         index, arr[:, k], stamp_index=index, stamps_s=t)


def estimate_rate(sorted_stamps_ns: np.ndarray) -> float | None:
    """Sample rate (Hz) from stamps: 1 / the median positive interval, to 3 significant digits.

    Parameters
    ----------
    sorted_stamps_ns : numpy.ndarray
        Stamps in ascending order (ns).

    Returns
    -------
    float or None
        None when no two stamps differ.

    Examples
    --------
    >>> estimate_rate(np.array([0, 2_500_000, 5_000_000, 7_600_000]))
    400.0
    """
    d = np.diff(sorted_stamps_ns)
    d = d[d > 0]
    if d.size == 0:
        return None
    fs = 1e9 / float(np.median(d))
    digits = 2 - math.floor(math.log10(fs))
    return float(round(fs, digits))


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
        where = block.where
        for _m, p in self._decoded(block):
            name = spec.name if spec is not None else p.name
            unit = spec.unit if spec is not None and spec.unit is not None else p.unit
            entry = self.points.get(name)
            if entry is None:
                entry = self.points[name] = (unit, [], [])
            elif entry[0] != unit:
                self.ctx.report.reject("inconsistent_unit", 1, where)
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
        for m, value in self._decoded(block):
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


class MappedHandler(DecodingHandler):
    """Any decodable message: the mapping's dotted fields become uniform or slow signals.

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
        From :meth:`add` or :meth:`finish`: a field path the messages do not have, a
        non-numeric field, or an array field mapped to a slow signal.
    """

    def __init__(self, ctx: HandlerContext, channel: ChannelRecord, decoder: Decoder,
                 specs: list[UniformSpec | SlowSpec]) -> None:
        super().__init__(ctx, channel, decoder)
        self.specs = specs
        self.stamps: list[int] = []
        self.cols: list[list[Any]] = [[] for _ in specs]

    def add(self, block: MessageBlock) -> None:
        """Collect each mapped field and the message's stamp (header stamp, else log time)."""
        for m, obj in self._decoded(block):
            row = []
            for spec in self.specs:
                try:
                    row.append(get_field(obj, spec.field or ""))
                except KeyError as exc:
                    raise MappingError(self.ctx.mapping_source, f"topic {self.channel.topic!r}",
                                       "a field path that exists in the messages",
                                       repr(spec.field), str(exc)) from None
            stamp = message_stamp_ns(obj)
            self.stamps.append(m[2] if stamp is None else stamp)
            for col, val in zip(self.cols, row, strict=True):
                col.append(val)
            self.ctx.report.decoded += 1

    def _numbers(self, spec: UniformSpec | SlowSpec, vals: list[Any]) -> list[np.ndarray]:
        try:
            out = [np.asarray(v, np.float64).ravel() for v in vals]
        except (TypeError, ValueError):
            raise MappingError(self.ctx.mapping_source, f"topic {self.channel.topic!r}",
                               "a numeric field", f"{spec.field!r} = {vals[0]!r}") from None
        return out

    def finish(self) -> None:
        """Hand each mapped field to the builder as the signal its entry names."""
        if not self.stamps:
            return
        t = np.asarray(self.stamps, np.float64) * 1e-9
        for spec, vals in zip(self.specs, self.cols, strict=True):
            arrays = self._numbers(spec, vals)
            unit = spec.unit if spec.unit is not None else self.channel.metadata.get("unit", "")
            if isinstance(spec, SlowSpec):
                if any(a.size != 1 for a in arrays):
                    raise MappingError(self.ctx.mapping_source, f"topic {self.channel.topic!r}",
                                       "a scalar field for a slow signal", repr(spec.field))
                v = np.concatenate(arrays) * spec.scale + spec.offset
                self.ctx.builder.add_slow(spec.name, unit, t, v)
                continue
            rate = spec.sample_rate_Hz
            counts = np.asarray([a.size for a in arrays], np.int64)
            idx0 = indices_from_stamps(t, rate)
            idx0 -= idx0.min()
            starts = np.cumsum(counts) - counts
            index = np.arange(int(counts.sum()), dtype=np.int64)
            index += np.repeat(idx0 - starts, counts)
            values = np.concatenate(arrays) * spec.scale + spec.offset
            keep = counts > 0
            self.ctx.builder.add_samples(spec.channel, unit, rate, index, values,
                                         stamp_index=idx0[keep], stamps_s=t[keep])

"""Per-channel handlers of the MCAP ingest: decoded messages in, builder input out.

The ingest (:func:`rigtools.ingest.mcap.ingest`) gives each channel one handler, chosen from
the channel's :class:`~rigtools.ingest.mcap.decoders.Decoder` and the mapping. A handler
receives the channel's messages block by block (:meth:`ChannelHandler.add`: a
:class:`~rigtools.ingest.mcap.container.MessageBlock` of the channel's messages of one chunk),
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
(:func:`~rigtools.ingest.mcap.timing.resync_counter_restarts`); Imu messages are laid on a
grid fitted to their stamps (:func:`~rigtools.ingest.mcap.timing.stamp_grid`).

Per-sample ROS 2 streams (one ``sensor_msgs/msg/Imu`` or small message per sample) are read
a chunk at a time when the chunk's messages share one CDR layout
(:mod:`rigtools.ingest.mcap.cdr`): :class:`ImuHandler`, :class:`ScalarHandler` and
:class:`MappedHandler` take the block's fields as arrays and fall back to decoding message by
message, with the same values, for any chunk that breaks the layout.

Two clocks: a ROS 2 message with a header has its header stamp and its MCAP log time. The
context's ``clock`` (``"header"``, the default, or ``"log_time"``; ``read(mcap_clock=...)``)
chooses which places an Imu or mapped uniform channel (and times a mapped slow field); the
other is handed to the builder as the channel's second clock, whose statistics and median
offset land in ``report.timebase[f"{channel}@{clock}"]``. Topic scalars without a header
(``std_msgs/msg/Float64``) have the log time only.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from rigtools.ingest.layout import UniformSpec
from rigtools.ingest.mcap.decoders import AccelBatchColumns, Decoder
from rigtools.ingest.mcap.handler_base import (
    ChannelHandler,
    DecodingHandler,
    HandlerContext,
    RejectHandler,
    message_position,
)
from rigtools.ingest.mcap.records import ChannelRecord
from rigtools.ingest.mcap.signal_handlers import (
    ImuHandler,
    MappedHandler,
    ScalarHandler,
    SlowValueHandler,
)
from rigtools.ingest.mcap.timing import estimate_rate, resync_counter_restarts
from rigtools.ingest.mcap.walk import MessageBlock

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


#: Restarts warned about one by one, per channel; the rest are summed up.
_MAX_RESTART_WARNINGS = 5


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


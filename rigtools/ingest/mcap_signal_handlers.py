"""The MCAP handlers of Imu, slow-value, scalar and mapped (generic) channels.

See :mod:`rigtools.ingest.mcap_handlers` for what each makes and the reasons they count.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from rigtools.errors import MappingError
from rigtools.ingest.layout import SlowSpec, UniformSpec
from rigtools.ingest.mcap_decoders import Decoder, get_field, message_stamp_ns
from rigtools.ingest.mcap_handler_base import (
    DecodingHandler,
    HandlerContext,
    message_position,
)
from rigtools.ingest.mcap_records import ChannelRecord
from rigtools.ingest.mcap_timing import stamp_grid
from rigtools.ingest.mcap_walk import MessageBlock
from rigtools.ingest.timebase import indices_from_stamps

__all__ = [
    "ImuHandler",
    "MappedHandler",
    "ScalarHandler",
    "SlowValueHandler",
]


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

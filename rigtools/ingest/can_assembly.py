"""From streams of CAN frame batches to channels and slow signals, vectorised.

Each batch is split by (identifier, extended flag) with one ``argsort``; every message the
layout uses is decoded with :func:`rigtools.ingest.dbc.decode_signal` over all its frames of
the batch at once. Frames are never dropped silently: each one either contributes data or is
counted in the :class:`~rigtools.ingest.recording.IngestReport` under a reason:

``id_not_in_dbc``            identifier absent from the DBC
``message_not_in_layout``    in the DBC, but no channel or slow signal of the layout uses it
``dlc_shorter_than_dbc``     payload shorter than the DBC message length
``duplicate_frame``          same sample counter as an earlier frame of the channel
``counter_backwards``        sample counter below one already seen (late or reordered frame)

(error and remote frames are counted by the readers, which see them first).
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, field

import numpy as np

from rigtools.ingest.builder import RecordingBuilder
from rigtools.ingest.dbc import decode_signal, multiplex_mask
from rigtools.ingest.frames import CanFrameBatch
from rigtools.ingest.layout import CanLayout, CanUniform
from rigtools.ingest.recording import IngestReport
from rigtools.ingest.timebase import unwrap_counter

__all__ = ["assemble_can"]


@dataclass
class _UniformAcc:
    spec: CanUniform
    counters: list[np.ndarray] = field(default_factory=list)
    stamps: list[np.ndarray] = field(default_factory=list)
    values: list[np.ndarray] = field(default_factory=list)
    positions: list[np.ndarray] = field(default_factory=list)
    position_unit: str = "byte"


def assemble_can(
    batches: Iterable[CanFrameBatch],
    layout: CanLayout,
    builder: RecordingBuilder,
    report: IngestReport,
) -> None:
    """Decode every batch into ``builder`` following ``layout``; tally every frame."""
    known = {(int(m.frame_id), bool(m.is_extended_frame)) for m in layout.db.messages}
    used = layout.messages_used()
    uniform_by_key: dict[tuple[int, bool], list[_UniformAcc]] = {}
    accs: list[_UniformAcc] = []
    for u in layout.uniform:
        acc = _UniformAcc(u)
        accs.append(acc)
        key = (int(u.message.frame_id), bool(u.message.is_extended_frame))
        uniform_by_key.setdefault(key, []).append(acc)
    slow_by_key: dict[tuple[int, bool], list] = {}
    for s in layout.slow:
        key = (int(s.message.frame_id), bool(s.message.is_extended_frame))
        slow_by_key.setdefault(key, []).append(s)

    for batch in batches:
        n = len(batch)
        if n == 0:
            continue
        key_arr = batch.arbitration_id.astype(np.int64) | (batch.is_extended.astype(np.int64) << 32)
        order = np.argsort(key_arr, kind="stable")
        sorted_keys = key_arr[order]
        starts = np.flatnonzero(np.r_[True, sorted_keys[1:] != sorted_keys[:-1]])
        ends = np.r_[starts[1:], n]
        for a, b in zip(starts, ends, strict=True):
            k = int(sorted_keys[a])
            key = (k & 0xFFFFFFFF, bool(k >> 32))
            rows = order[a:b]
            if key not in known:
                report.reject("id_not_in_dbc", b - a, batch.where(int(rows[0])))
                continue
            message = used.get(key)
            if message is None:
                report.reject("message_not_in_layout", b - a, batch.where(int(rows[0])))
                continue
            short = batch.length[rows] < int(message.length)
            if short.any():
                report.reject("dlc_shorter_than_dbc", int(short.sum()),
                              batch.where(int(rows[np.argmax(short)])))
                rows = rows[~short]
                if rows.size == 0:
                    continue
            data = batch.data[rows]
            stamps = batch.timestamp_s[rows]
            report.decoded += int(rows.size)
            for acc in uniform_by_key.get(key, ()):
                _decode_uniform(acc, data, stamps, batch.position[rows], batch.position_unit)
            for s in slow_by_key.get(key, ()):
                vals = decode_signal(data, s.signal)
                t = stamps
                mask = multiplex_mask(data, message, s.signal)
                if mask is not None:
                    vals, t = vals[mask], t[mask]
                if s.spec.scale != 1.0 or s.spec.offset != 0.0:
                    vals = vals * s.spec.scale + s.spec.offset
                builder.add_slow(s.spec.name, s.unit, t, vals)

    for acc in accs:
        _finish_uniform(acc, builder, report)


def _decode_uniform(
    acc: _UniformAcc, data: np.ndarray, stamps: np.ndarray, positions: np.ndarray, unit: str
) -> None:
    u = acc.spec
    cols = [decode_signal(data, s) for s in u.samples]
    vals = np.stack(cols, axis=1) if len(cols) > 1 else cols[0][:, None]
    if u.spec.scale != 1.0 or u.spec.offset != 0.0:
        vals = vals * u.spec.scale + u.spec.offset
    acc.values.append(vals)
    acc.stamps.append(stamps)
    acc.positions.append(positions)
    acc.position_unit = unit
    if u.counter is not None:
        acc.counters.append(decode_signal(data, u.counter).astype(np.int64))


def _finish_uniform(acc: _UniformAcc, builder: RecordingBuilder, report: IngestReport) -> None:
    u = acc.spec
    if not acc.values:
        return
    k = len(u.samples)
    fs = u.spec.sample_rate_Hz
    frame_rate = fs / k
    stamps = np.concatenate(acc.stamps)
    positions = np.concatenate(acc.positions)
    if u.counter is not None:
        counters = np.concatenate(acc.counters)
        raw_max = (1 << int(u.counter.length))
        scale = float(u.counter.scale)
        if scale != 1.0 or u.counter.offset != 0:
            counters = np.round((counters - float(u.counter.offset)) / scale).astype(np.int64)
        un = unwrap_counter(counters, raw_max, stamps, frame_rate)
        if un.n_duplicate:
            first = positions[np.flatnonzero(~un.keep)[0]]
            report.reject("duplicate_frame", un.n_duplicate,
                          f"{acc.position_unit} {int(first)} (channel {u.spec.channel!r})")
        if un.n_backwards:
            report.reject("counter_backwards", un.n_backwards, f"channel {u.spec.channel!r}")
        if un.restarts.size:
            report.warn(
                f"channel {u.spec.channel!r}: sample counter restarted {un.restarts.size} time(s) "
                f"(first at {acc.position_unit} {int(positions[un.restarts[0]])}); "
                "resynchronised from the logger clock"
            )
        ticks = un.ticks
        keep = un.keep
    else:
        t0 = stamps.min()
        ticks = np.round((stamps - t0) * frame_rate).astype(np.int64)
        keep = np.ones(ticks.size, bool)
        report.warn(f"channel {u.spec.channel!r}: no sample counter; time base from logger stamps")
    values = np.concatenate(acc.values)
    acc.values.clear()
    if not keep.all():
        ticks, values, stamps = ticks[keep], values[keep], stamps[keep]
    index = (ticks[:, None] * k + np.arange(k, dtype=np.int64)).ravel()
    builder.add_samples(
        u.spec.channel,
        u.unit,
        fs,
        index,
        values.ravel(),
        stamp_index=ticks * k + (k - 1),
        stamps_s=stamps,
    )

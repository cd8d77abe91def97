"""From streams of CAN frame batches to channels and slow signals, vectorised.

Each batch is split by (identifier, extended flag) in one compiled pass
(:func:`~rigtools.ingest.can.grouping.group_by_message`); every message the
layout uses is decoded with :func:`rigtools.ingest.can.dbc.decode_signal` over all its frames of
the batch at once. Frames are never dropped silently: each one either contributes data or is
counted in the :class:`~rigtools.ingest.recording.IngestReport` under a reason:

``id_not_in_dbc``            identifier absent from the DBC
``message_not_in_layout``    in the DBC, but no channel or slow signal of the layout uses it
``dlc_shorter_than_dbc``     payload shorter than the DBC message length
``duplicate_frame``          same sample counter as an earlier frame of the message
``counter_outlier``          a sample counter that disagrees with both neighbouring frames

(error and remote frames are counted by the readers, which see them first). A frame counts
once whatever number of channels it feeds: a message that carries three channels and arrives
twice is one ``duplicate_frame``, not three, and it is not counted ``decoded`` as well. The
builder learns which message carries each channel (:meth:`~rigtools.ingest.builder.
RecordingBuilder.note_carrier`), so the gaps its channels share are counted once in frames
(:func:`rigtools.ingest.losses.loss_tally`).
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass, field

import numpy as np

from rigtools.ingest.builder import MAX_CLOCK_POINTS, RecordingBuilder
from rigtools.ingest.can.dbc import decode_signal, multiplex_mask, signal_raw
from rigtools.ingest.can.frames import CanFrameBatch, take_rows
from rigtools.ingest.can.grouping import group_by_message
from rigtools.ingest.can.layout_hint import fast_message_warning
from rigtools.ingest.layout import CanLayout, CanUniform
from rigtools.ingest.recording import IngestReport
from rigtools.ingest.timebase import unwrap_counter

__all__ = ["assemble_can"]


@dataclass
class _UniformAcc:
    spec: CanUniform
    counters: list[np.ndarray] = field(default_factory=list)
    # Logger stamps per batch as (float64 base, float32 offsets): 4 bytes a frame, and
    # sub-microsecond precision over a batch's few seconds.
    stamps: list[tuple[float, np.ndarray]] = field(default_factory=list)
    raws: list[np.ndarray] = field(default_factory=list)
    conversion: tuple[tuple[float, float], ...] = ()


def assemble_can(
    batches: Iterable[CanFrameBatch],
    layout: CanLayout,
    builder: RecordingBuilder,
    report: IngestReport,
) -> None:
    """Decode every batch into ``builder`` following ``layout``; tally every frame.

    A message of the layout seen on more than one bus channel gives one channel per bus,
    named ``<channel>@bus<n>`` (python-can channel numbering): two sensor sets with the same
    layout on can0 and can1 are two sets of channels, never one interleaved channel.
    """
    known = {(int(m.frame_id), bool(m.is_extended_frame)) for m in layout.db.messages}
    used = layout.messages_used()
    uniform_by_key: dict[tuple[int, bool], list[int]] = {}
    for i, u in enumerate(layout.uniform):
        key = (int(u.message.frame_id), bool(u.message.is_extended_frame))
        uniform_by_key.setdefault(key, []).append(i)
    slow_by_key: dict[tuple[int, bool], list[int]] = {}
    for i, s in enumerate(layout.slow):
        key = (int(s.message.frame_id), bool(s.message.is_extended_frame))
        slow_by_key.setdefault(key, []).append(i)
    accs: dict[tuple[int, int], _UniformAcc] = {}  # (uniform index, bus) -> samples so far
    slow_parts: dict[tuple[int, int], list[tuple[np.ndarray, np.ndarray]]] = {}

    for batch in batches:
        n = len(batch)
        if n == 0:
            continue
        # rows of message c: order[bounds[c]:bounds[c+1]], messages by first appearance
        order, bounds, uniques = group_by_message(batch.arbitration_id, batch.is_extended)
        for code in range(len(uniques)):
            a, b = int(bounds[code]), int(bounds[code + 1])
            k = int(uniques[code])
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
            report.decoded += int(rows.size)
            bus_of_rows = batch.channel[rows]
            buses = ([int(bus_of_rows[0])] if np.all(bus_of_rows == bus_of_rows[0])
                     else np.unique(bus_of_rows).tolist())
            for bus in buses:
                bus_rows = rows if len(buses) == 1 else rows[bus_of_rows == bus]
                data = take_rows(batch.data, bus_rows)
                stamps = batch.timestamp_s[bus_rows]
                uniform = uniform_by_key.get(key, ())
                if uniform:
                    # one copy of the stamps and of each counter for the message's channels
                    base = float(stamps[0])
                    stamp_part = (base, (stamps - base).astype(np.float32))
                    counters: dict[tuple[object, ...], np.ndarray] = {}
                for ui in uniform:
                    acc = accs.get((ui, bus))
                    if acc is None:
                        acc = accs[(ui, bus)] = _UniformAcc(layout.uniform[ui])
                    _decode_uniform(acc, data, stamp_part, counters)
                for si in slow_by_key.get(key, ()):
                    s = layout.slow[si]
                    vals = decode_signal(data, s.signal)
                    t = stamps
                    mask = multiplex_mask(data, message, s.signal)
                    if mask is not None:
                        vals, t = vals[mask], t[mask]
                    if s.spec.scale != 1.0 or s.spec.offset != 0.0:
                        vals = vals * s.spec.scale + s.spec.offset
                    slow_parts.setdefault((si, bus), []).append((t, vals))

    _finish_messages(accs, layout, set(slow_by_key), builder, report)
    slow_buses = _buses_by_index(slow_parts)
    if layout.description.get("source") == "dbc-attributes":
        _warn_fast_slow_messages(layout, slow_parts, slow_buses, report)
    for (si, bus), parts in slow_parts.items():
        s = layout.slow[si]
        name = _bus_name(s.spec.name, bus, slow_buses[si], report)
        for t, vals in parts:
            builder.add_slow(name, s.unit, t, vals)


def _finish_messages(
    accs: dict[tuple[int, int], _UniformAcc],
    layout: CanLayout,
    slow_keys: set[tuple[int, bool]],
    builder: RecordingBuilder,
    report: IngestReport,
) -> None:
    """Finish the uniform channels message by message; count each frame lost or dropped once.

    The channels fed by one message on one bus received the same frames in the same order:
    a frame one of them drops (a duplicate, a corrupted counter) is counted once for the
    message, and taken off ``report.decoded`` unless the message also feeds slow signals.
    """
    uniform_buses = _buses_by_index(accs)
    groups: dict[tuple[tuple[int, bool], int], list[tuple[int, int]]] = {}
    for ui, bus in accs:
        msg = layout.uniform[ui].message
        groups.setdefault(((int(msg.frame_id), bool(msg.is_extended_frame)), bus),
                          []).append((ui, bus))
    for (key, bus), members in groups.items():
        message = layout.uniform[members[0][0]].message
        several_buses = any(len(uniform_buses[ui]) > 1 for ui, _ in members)
        source = f"message {message.name!r}" + (f" on bus {bus}" if several_buses else "")
        names = [_bus_name(accs[m].spec.spec.channel, bus, uniform_buses[m[0]], report)
                 for m in members]
        who = (f"channel {names[0]!r}" if len(names) == 1 else
               f"{source} (channels {', '.join(map(repr, names))})")
        duplicate: np.ndarray | None = None
        outlier: np.ndarray | None = None
        shared = _shared_timeline([accs[m] for m in members], who, report)
        for m, name in zip(members, names, strict=True):
            acc = accs[m]
            builder.note_carrier(name, source, len(acc.spec.samples))
            dup, out = _finish_uniform(acc, name, who, builder, report, shared)
            duplicate = _either(duplicate, dup)
            outlier = _either(outlier, out)
        n_dup = 0 if duplicate is None else int(np.count_nonzero(duplicate))
        if outlier is not None and duplicate is not None:
            outlier = outlier & ~duplicate
        n_out = 0 if outlier is None else int(np.count_nonzero(outlier))
        report.reject("duplicate_frame", n_dup, source)
        report.reject("counter_outlier", n_out, source)
        if key not in slow_keys:  # those frames contributed nothing
            report.decoded -= n_dup + n_out


def _warn_fast_slow_messages(
    layout: CanLayout,
    slow_parts: dict[tuple[int, int], list[tuple[np.ndarray, np.ndarray]]],
    slow_buses: dict[int, set[int]],
    report: IngestReport,
) -> None:
    """Warn about messages read as slow signals that arrive as fast as sampled channels."""
    by_message: dict[tuple[str, int], dict[str, tuple[list[np.ndarray], list[np.ndarray]]]] = {}
    for (si, bus), parts in slow_parts.items():
        s = layout.slow[si]
        signals = by_message.setdefault((s.message.name, bus), {})
        signals[s.spec.name] = ([t for t, _ in parts], [v for _, v in parts])
    for (message, bus), signals in by_message.items():
        several = any(len(slow_buses[si]) > 1 for si, b in slow_parts
                      if b == bus and layout.slow[si].message.name == message)
        label = f"message {message!r}" + (f" on bus {bus}" if several else "")
        text = fast_message_warning(label, signals, str(layout.description.get("dbc", "")))
        if text is not None:
            report.warn(text)


def _either(a: np.ndarray | None, b: np.ndarray | None) -> np.ndarray | None:
    """Element-wise or of two masks over the same frames (None: no frame set)."""
    if a is None or b is None or a.shape != b.shape:
        return b if a is None else a
    return a | b


def _buses_by_index(d: Mapping[tuple[int, int], object]) -> dict[int, set[int]]:
    out: dict[int, set[int]] = {}
    for i, bus in d:
        out.setdefault(i, set()).add(bus)
    return out


def _bus_name(name: str, bus: int, buses: set[int], report: IngestReport) -> str:
    if len(buses) == 1:
        return name
    report.warn(f"{name!r} arrives on bus channels {sorted(buses)}: kept apart as "
                f"{', '.join(repr(f'{name}@bus{b}') for b in sorted(buses))}")
    return f"{name}@bus{bus}"


def _decode_uniform(
    acc: _UniformAcc, data: np.ndarray, stamp_part: tuple[float, np.ndarray],
    counters: dict[tuple[object, ...], np.ndarray],
) -> None:
    """Decode one channel's samples from the frames ``data`` of its message.

    ``stamp_part`` is the frames' stamps as (base, float32 offsets) and ``counters`` the
    counters decoded so far from these frames, by signal layout: both shared by the channels
    of the message (the arrays are never written to).
    """
    u = acc.spec
    raws, convs = zip(*(signal_raw(data, s) for s in u.samples), strict=True)
    if len(set(convs)) == 1 and len({r.dtype for r in raws}) == 1:
        raw = np.stack(raws, axis=1)  # int16 samples stay int16 until the channel is built
        conv: tuple[tuple[float, float], ...] = (convs[0],)
    else:  # samples with different scalings: convert now
        raw = np.stack([r.astype(np.float64) * c[0] + c[1] for r, c in zip(raws, convs,
                                                                           strict=True)], axis=1)
        conv = ()
    if u.spec.scale != 1.0 or u.spec.offset != 0.0:
        conv = (*conv, (u.spec.scale, u.spec.offset))
    if not acc.raws:
        acc.conversion = conv
    acc.raws.append(raw)
    acc.stamps.append(stamp_part)
    if u.counter is not None:
        c = u.counter
        layout = (int(c.start), int(c.length), str(c.byte_order), bool(c.is_signed),
                  bool(c.is_float))
        got = counters.get(layout)
        if got is None:
            got = counters[layout] = signal_raw(data, c)[0]
        acc.counters.append(got)


#: Odd 64-bit multipliers for :func:`_fingerprints` (one per payload byte, cycled).
_FP_WEIGHTS = np.array([0x9E3779B97F4A7C15, 0xC2B2AE3D27D4EB4F, 0x165667B19E3779F9,
                        0xD6E8FEB86659FD93, 0xFF51AFD7ED558CCD, 0xC4CEB9FE1A85EC53,
                        0x94D049BB133111EB, 0xBF58476D1CE4E5B9], dtype=np.uint64)


def _fingerprints(raws: list[np.ndarray]) -> np.ndarray:
    """One 64-bit fingerprint per frame of the decoded samples (8 bytes a frame).

    Lets the counter unwrapping tell a replayed run (same payloads at the same ticks) from a
    restart; equal payloads give equal fingerprints, different ones almost surely differ.
    """
    out = np.empty(sum(r.shape[0] for r in raws), np.uint64)
    row = 0
    for raw in raws:
        m = raw.shape[0]
        b = np.ascontiguousarray(raw).view(np.uint8).reshape(m, -1).astype(np.uint64)
        w = np.resize(_FP_WEIGHTS, b.shape[1]) + np.arange(b.shape[1], dtype=np.uint64) * 2
        with np.errstate(over="ignore"):
            out[row : row + m] = (b * w).sum(axis=1, dtype=np.uint64)
        row += m
    return out


@dataclass(frozen=True)
class _Timeline:
    """Where the frames of a channel go, in arrival order.

    Shared by the channels of one message read through the same counter (they received the
    same frames). ``ticks`` and ``keep`` per frame; ``restarts`` positions of counter restarts;
    ``duplicate`` and ``outlier`` masks of the frames dropped (None when none is);
    ``clock_index`` and ``clock_stamps`` the sample index and logger stamp of the frames the
    clock check uses.
    """

    ticks: np.ndarray
    keep: np.ndarray
    restarts: np.ndarray
    duplicate: np.ndarray | None
    outlier: np.ndarray | None
    clock_index: np.ndarray
    clock_stamps: np.ndarray


class _PayloadNeededError(Exception):
    """The counter of a shared timeline needs the payloads (a replay to tell from a restart)."""


def _payload_needed() -> np.ndarray:
    raise _PayloadNeededError


def _joined_stamps(acc: _UniformAcc) -> np.ndarray:
    stamps = np.empty(sum(r.size for _, r in acc.stamps))
    row = 0
    for base, rel in acc.stamps:
        np.add(rel, base, out=stamps[row : row + rel.size], dtype=np.float64)
        row += rel.size
    return stamps


def _timeline(acc: _UniformAcc, who: str, report: IngestReport,
              payload: Callable[[], np.ndarray]) -> _Timeline:
    """The placement of one channel's frames by their counter (or their stamps).

    ``payload`` makes the frames' fingerprints when the counter needs them; it may raise
    :class:`_PayloadNeededError`, before anything is reported or released.
    """
    u = acc.spec
    k = len(u.samples)
    frame_rate = u.spec.sample_rate_Hz / k
    stamps = _joined_stamps(acc)
    duplicate: np.ndarray | None = None
    outlier: np.ndarray | None = None
    restarts = np.zeros(0, np.int64)
    if u.counter is not None:
        # Raw counter bits (a DBC scale on a counter is ignored: it counts frames).
        counters = np.concatenate(acc.counters).astype(np.int64)
        un = unwrap_counter(counters, 1 << int(u.counter.length), stamps, frame_rate,
                            payload=payload)
        del counters
        if un.n_outlier:
            outlier = un.outlier
            report.warn(f"{who}: {un.n_outlier} frame(s) carry a sample counter "
                        "that disagrees with both neighbouring frames (corrupted); dropped")
        if un.n_duplicate:
            duplicate = ~un.keep if outlier is None else ~un.keep & ~outlier
        if un.n_reordered:
            report.warn(f"{who}: {un.n_reordered} frame(s) arrived out of order; "
                        "placed by their sample counter")
        if un.clock_jumps:
            report.warn(f"{who}: the logger clock jumped {un.clock_jumps} time(s) "
                        "while the sample counter ran on; the counter was kept")
        if un.restarts.size:
            report.warn(
                f"{who}: sample counter restarted {un.restarts.size} time(s) "
                f"(first at frame {int(un.restarts[0])} of the channel); "
                "resynchronised from the logger clock"
            )
        ticks, keep, restarts = un.ticks, un.keep, un.restarts
    else:
        ticks = np.round((stamps - stamps.min()) * frame_rate).astype(np.int64)
        keep = np.ones(ticks.size, bool)
        report.warn(f"{who}: no sample counter; time base from logger stamps")
    acc.stamps.clear()
    acc.counters.clear()
    # The clock check needs only a sample of the stamps.
    pick = np.flatnonzero(keep)
    if pick.size > MAX_CLOCK_POINTS:
        pick = pick[np.linspace(0, pick.size - 1, MAX_CLOCK_POINTS).astype(np.int64)]
    return _Timeline(ticks, keep, restarts, duplicate, outlier, ticks[pick] * k + (k - 1),
                     stamps[pick])


def _counter_signature(acc: _UniformAcc) -> tuple[object, ...] | None:
    c = acc.spec.counter
    if c is None:
        return None
    return (int(c.start), int(c.length), str(c.byte_order), len(acc.spec.samples),
            float(acc.spec.spec.sample_rate_Hz), sum(r.size for _, r in acc.stamps))


def _shared_timeline(group: list[_UniformAcc], who: str,
                     report: IngestReport) -> _Timeline | None:
    """One timeline for channels of one message read through the same counter, or None.

    Those channels received the same frames in the same order, with the same counters and
    stamps: the counter is unwrapped once. Only when it needs the payloads (a replayed run to
    tell from a restart, which the fingerprints of each channel's own samples decide) is
    each channel unwrapped on its own, as it would be alone.
    """
    if len(group) < 2 or not group[0].raws:
        return None
    sig = _counter_signature(group[0])
    if sig is None or any(_counter_signature(a) != sig for a in group[1:]):
        return None
    try:
        shared = _timeline(group[0], who, report, _payload_needed)
    except _PayloadNeededError:
        return None
    for acc in group[1:]:
        acc.stamps.clear()
        acc.counters.clear()
    return shared


def _finish_uniform(
    acc: _UniformAcc, name: str, who: str, builder: RecordingBuilder, report: IngestReport,
    shared: _Timeline | None = None,
) -> tuple[np.ndarray | None, np.ndarray | None]:
    """Hand one channel's frames to the builder, placed by their counter.

    ``who`` names the channel, or its message and channels when the message feeds several, in
    the warnings; ``shared`` is the timeline of the channel's message when it was made once
    for all its channels. Returns the masks, over the channel's frames in arrival order, of
    the frames dropped as duplicates and as corrupted counters (None when none is).
    """
    if not acc.raws:
        return None, None
    tl = shared
    if tl is None:
        tl = _timeline(acc, who, report, lambda: _fingerprints(acc.raws))
    u = acc.spec
    k = len(u.samples)
    fs = u.spec.sample_rate_Hz
    for r in tl.restarts:
        builder.mark_restart(name, int(tl.ticks[r]) * k)
    row = 0
    raws = acc.raws
    for i in range(len(raws)):
        raw = raws[i]
        raws[i] = None  # type: ignore[call-overload]  # release as we go
        m = raw.shape[0]
        sel = tl.keep[row : row + m]
        t = tl.ticks[row : row + m]
        row += m
        if not sel.all():
            raw, t = raw[sel], t[sel]
        builder.add_samples(name, u.unit, fs, t * k, raw, conversion=acc.conversion)
    raws.clear()
    builder.add_clock(name, tl.clock_index, tl.clock_stamps)
    return tl.duplicate, tl.outlier

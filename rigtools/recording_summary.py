"""What a Recording holds and what was lost, as a JSON-ready summary and as text.

:func:`summary` (channels, rates, durations, slow signals, metadata, the ingest report and the
losses counted in frames and in samples, every float finite or None after :func:`json_safe`)
and :func:`format_info`, the table ``rigtools info`` prints and the demo shows for each
format. :func:`loss_warnings` are the lines every subcommand prints about losses;
:func:`unit_of` says whether a rejection count counts samples or frames/messages;
:func:`no_uniform_channel_hint` says what a recording without a uniform channel holds and how
to read its sampled signals. Text only: no command-line parsing, no exit codes.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, Final

import numpy as np

from rigtools.ingest.losses import LossTally, loss_tally
from rigtools.ingest.recording import Recording, counts_samples

__all__ = [
    "FAST_SIGNAL_Hz",
    "format_info",
    "json_safe",
    "loss_warnings",
    "no_uniform_channel_hint",
    "signal_rate_Hz",
    "summary",
    "unit_of",
]

#: A slow signal logged at least this often (Hz) is named as possibly sampled data.
FAST_SIGNAL_Hz: Final = 1000.0
#: Gap lines listed one by one in ``info``.
MAX_GAP_LINES: Final = 20


def unit_of(reason: str, units: str) -> str:
    """What a rejection count counts: samples for sample-level reasons, else ``units``."""
    return "samples" if counts_samples(reason) else units


def summary(rec: Recording) -> dict[str, Any]:
    """JSON-ready summary of a recording."""
    rep = rec.report
    return {
        "source": rec.provenance.source_path,
        "sha256": rec.provenance.source_sha256,
        "reader": rec.provenance.reader,
        "duration_s": rec.duration_s,
        "channels": [
            {
                "name": c.name,
                "unit": c.unit,
                "sample_rate_Hz": c.sample_rate_Hz,
                "n_samples": len(c),
                "n_valid": int(np.count_nonzero(c.valid)),
                "duration_s": c.duration_s,
                "start_time_s": c.start_time_s,
            }
            for c in rec.channels.values()
        ],
        "slow": [
            {
                "name": s.name,
                "unit": s.unit,
                "n_points": len(s),
                "rate_Hz": signal_rate_Hz(s.time_s),
                "min": _finite_or_none(s.values, np.min),
                "max": _finite_or_none(s.values, np.max),
            }
            for s in rec.slow.values()
        ],
        "metadata": rec.metadata.to_dict(),
        "report": rep.to_dict(),
        "losses": loss_tally(rec).to_dict(),
    }


def json_safe(obj: Any) -> Any:
    """Non-finite floats to None, recursively (strict JSON has no NaN or Infinity)."""
    if isinstance(obj, float):
        return obj if np.isfinite(obj) else None
    if isinstance(obj, dict):
        return {k: json_safe(v) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [json_safe(v) for v in obj]
    return obj


def _finite_or_none(values: np.ndarray, reduce: Callable[[np.ndarray], Any]) -> float | None:
    """Extreme of the finite values, or None (JSON has no NaN)."""
    finite = values[np.isfinite(values)]
    return float(reduce(finite)) if finite.size else None


def signal_rate_Hz(time_s: np.ndarray) -> float | None:  # noqa: N802 (unit in the name)
    """Usual rate of a slow signal (Hz): one over the median positive step of its times.

    The times of a :class:`~rigtools.ingest.recording.SlowSignal` are non-decreasing.
    """
    t = np.asarray(time_s, np.float64)
    t = t[np.isfinite(t)]
    if t.size < 2:
        return None
    d = np.diff(t)
    d = d[d > 0]
    return float(1.0 / np.median(d)) if d.size else None


def _fast_signals(rec: Recording) -> list[tuple[str, float]]:
    out = []
    for s in rec.slow.values():
        r = signal_rate_Hz(s.time_s)
        if r is not None and r >= FAST_SIGNAL_Hz:
            out.append((s.name, r))
    return out


def no_uniform_channel_hint(rec: Recording) -> str:
    """What a recording without a uniform channel holds, and how to read its sampled signals.

    Names the slow signals logged at :data:`FAST_SIGNAL_Hz` or more (sampled data read as
    slow signals, e.g. a DBC without rigtools' attributes) and points to a mapping file
    (``--map``, ``data_schemas/channel_mapping.schema.json``).
    """
    fast = _fast_signals(rec)
    n = len(rec.slow)
    found = f"no uniform channel, only {n} slow signal(s)" if n else "no uniform channel"
    if fast:
        rate = max(r for _, r in fast)
        shown = ", ".join(name for name, _ in fast[:8]) + (", ..." if len(fast) > 8 else "")
        found += (f", of which {len(fast)} arrive at up to {rate / 1e3:.3g} kHz as sampled "
                  f"data does ({shown})")
    layout = rec.provenance.layout
    if layout.get("source") == "dbc-attributes":
        why = (f"the DBC {layout.get('dbc', '')} marks no message as a uniform channel "
               "(message attributes RigSampleRate, RigChannel, RigCounter); ")
        entry = ("message, samples (the signals of consecutive samples), counter (the "
                 "frame-counter signal), sample_rate_Hz")
    elif rec.provenance.reader == "mcap":
        why = "no topic holds a message type rigtools reads as samples; "
        entry = "topic, field (dotted path), sample_rate_Hz"
    else:
        why = ""
        entry = ("message, samples and counter (CAN) or topic and field (MCAP), "
                 "sample_rate_Hz")
    return (f"the recording holds {found}; {why}to read sampled signals as uniform channels, "
            f"write a mapping file (TOML) with one [[uniform]] entry per channel ({entry}, "
            "unit; schema: data_schemas/channel_mapping.schema.json) and pass it with --map")


def _plural(n: int, word: str) -> str:
    return f"{n} {word}" + ("" if n == 1 else "s")


def _sources_text(tally: LossTally) -> str:
    parts = []
    for source, (gaps, lost) in tally.by_source.items():
        chans = {c for fg in tally.frame_gaps if fg.source == source for c in fg.channels}
        feeds = f", feeding {_plural(len(chans), 'channel')}" if len(chans) > 1 else ""
        parts.append(f"{source}: {lost} in {gaps}{feeds}")
    return "; ".join(parts)


def loss_warnings(rec: Recording) -> list[str]:
    """One line per kind of loss: rejections by reason, frames lost, samples missing.

    Frames (or messages) and samples are counted apart, each named: a lost frame of a message
    that feeds three channels is one frame lost, and one gap (of its samples) in each of the
    three channels.
    """
    rep = rec.report
    lines = []
    for reason, n in sorted(rep.rejected.items()):
        where = rep.first_position.get(reason)
        at = f" (first at {where})" if where else ""
        lines.append(f"{n} {unit_of(reason, rep.units)} rejected: {reason}{at}")
    if rep.gaps:
        tally = loss_tally(rec)
        if tally.frame_gaps:
            lines.append(f"{tally.n_frames_lost} {rep.units} lost in "
                         f"{len(tally.frame_gaps)} gap(s) ({_sources_text(tally)})")
        n_ch = len(tally.by_channel)
        over = f" over {n_ch} channels" if n_ch > 1 else ""
        lines.append(f"{tally.n_sample_gaps} gap(s) in sample counters, "
                     f"{tally.n_samples_missing} sample(s) missing{over}")
    return lines + list(rep.warnings)


def format_info(rec: Recording) -> str:
    """Human-readable summary: columns as wide as the longest channel or signal name."""
    s = summary(rec)
    rep = rec.report
    lines = [
        f"source    {s['source']}",
        f"sha256    {s['sha256']}",
        f"reader    {s['reader']}",
        f"duration  {s['duration_s']:.3f} s",
    ]
    md = rec.metadata
    if md.run_id or md.rig or md.gear_set or md.conditions:
        cond = ", ".join(f"{k}={v:g}" for k, v in md.conditions.items())
        lines.append(f"run       {md.run_id or '-'}  rig {md.rig or '-'}  gear set "
                     f"{md.gear_set or '-'}  {cond}")
    w = max([28, *(len(c["name"]) + 2 for c in s["channels"]),
             *(len(x["name"]) + 2 for x in s["slow"])])
    u = max([10, *(len(c["unit"]) + 2 for c in s["channels"]),
             *(len(x["unit"]) + 2 for x in s["slow"])])
    lines.append("")
    lines.append(f"{'channel':<{w}}{'unit':<{u}}{'rate Hz':>12}{'samples':>12}{'valid':>12}"
                 f"{'duration s':>12}")
    for c in s["channels"]:
        lines.append(f"{c['name']:<{w}}{c['unit']:<{u}}{c['sample_rate_Hz']:>12g}"
                     f"{c['n_samples']:>12}{c['n_valid']:>12}{c['duration_s']:>12.3f}")
    if s["slow"]:
        lines.append("")
        lines.append(f"{'slow signal':<{w}}{'unit':<{u}}{'points':>12}{'rate Hz':>12}"
                     f"{'min':>12}{'max':>12}")
        for x in s["slow"]:
            lo = "-" if x["min"] is None else f"{x['min']:.4g}"
            hi = "-" if x["max"] is None else f"{x['max']:.4g}"
            rate = "-" if x["rate_Hz"] is None else f"{x['rate_Hz']:.4g}"
            lines.append(f"{x['name']:<{w}}{x['unit']:<{u}}{x['n_points']:>12}{rate:>12}"
                         f"{lo:>12}{hi:>12}")
    lines.append("")
    lines.append(f"decoded   {rep.decoded} {rep.units}")
    if rep.rejected:
        for reason, n in sorted(rep.rejected.items()):
            where = rep.first_position.get(reason, "")
            at = f"  (first at {where})" if where else ""
            lines.append(f"rejected  {n:>10}  {unit_of(reason, rep.units):<9}{reason}{at}")
    else:
        lines.append("rejected  none")
    lines.extend(_gap_lines(rec))
    for name, st in rep.timebase.items():
        if st:
            drift = st.get("drift_ppm")
            lines.append(f"clock     {name}: jitter {st.get('jitter_s', 0) * 1e6:.1f} us, "
                         f"max residual {st.get('max_abs_residual_s', 0) * 1e6:.1f} us"
                         + (f", drift {drift:.1f} ppm" if drift is not None else "")
                         + (f", offset {st['offset_s'] * 1e6:+.1f} us from the channel's clock"
                            if "offset_s" in st else ""))
    return "\n".join(lines)


def _gap_lines(rec: Recording) -> list[str]:
    """The losses in frames (once per source) and in samples (per channel), then the gaps."""
    rep = rec.report
    if not rec.channels:
        fast = " (see the warning about slow signals that arrive fast)" \
            if _fast_signals(rec) else ""
        return [f"gaps      not counted: no uniform channel (gaps are found in the sample "
                f"counters of uniform channels){fast}"]
    if not rep.gaps:
        return ["gaps      none"]
    tally = loss_tally(rec)
    units = rep.units
    lines = []
    if tally.frame_gaps:
        lines.append(f"{'lost':<10}{tally.n_frames_lost} {units} in "
                     f"{len(tally.frame_gaps)} gap(s)")
        for source, (gaps, lost) in tally.by_source.items():
            chans = list(dict.fromkeys(c for fg in tally.frame_gaps if fg.source == source
                                       for c in fg.channels))
            feeds = f", each a gap in {len(chans)} channels" if len(chans) > 1 else ""
            lines.append(f"          {source}: {lost} {units} lost in {gaps} gap(s){feeds}")
    lines.append(f"{'missing':<10}{tally.n_samples_missing} samples in {tally.n_sample_gaps} "
                 f"gap(s) over {_plural(len(tally.by_channel), 'channel')}")
    for name, (gaps, missing) in tally.by_channel.items():
        lines.append(f"          {name}: {missing} sample(s) in {gaps} gap(s)")
    if tally.uncounted:
        lines.append(f"          ({', '.join(tally.uncounted)}: which {units} carried the "
                     f"samples is not known, so the losses are counted in samples only)")
    lines.append(f"gaps      {len(rep.gaps)}")
    for g in rep.gaps[:MAX_GAP_LINES]:
        kind = f" [{g.kind}]" if g.kind != "gap" else ""
        lines.append(f"          {g.channel}: {g.n_missing} sample(s) missing from index "
                     f"{g.start_index} (t = {g.time_s:.6f} s){kind}")
    if len(rep.gaps) > MAX_GAP_LINES:
        lines.append(f"          ... {len(rep.gaps) - MAX_GAP_LINES} more")
    return lines

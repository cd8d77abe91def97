"""What a Recording holds and what was lost, as a JSON-ready summary and as text.

:func:`summary` (channels, rates, durations, slow signals, metadata and the ingest report, every
float finite or None after :func:`json_safe`) and :func:`format_info`, the table ``rigtools
info`` prints and the demo shows for each format. :func:`unit_of` says whether a rejection
count counts samples or frames/messages. Text only: no command-line parsing, no exit codes.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from rigtools.ingest.recording import Recording

__all__ = ["format_info", "json_safe", "summary", "unit_of"]

#: Rejection reasons that count samples or points, not frames or messages.
_SAMPLE_REASONS = ("_sample", "_sample_index", "_timestamp", "inconsistent_channel_layout")


def unit_of(reason: str, units: str) -> str:
    """What a rejection count counts: samples for sample-level reasons, else ``units``."""
    return "samples" if reason.endswith(_SAMPLE_REASONS) else units


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
                "min": _finite_or_none(s.values, np.min),
                "max": _finite_or_none(s.values, np.max),
            }
            for s in rec.slow.values()
        ],
        "metadata": rec.metadata.to_dict(),
        "report": rep.to_dict(),
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


def format_info(rec: Recording) -> str:
    """Human-readable summary."""
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
    lines.append("")
    lines.append(f"{'channel':<28}{'unit':<10}{'rate Hz':>12}{'samples':>12}{'valid':>12}"
                 f"{'duration s':>12}")
    for c in s["channels"]:
        lines.append(f"{c['name']:<28}{c['unit']:<10}{c['sample_rate_Hz']:>12g}"
                     f"{c['n_samples']:>12}{c['n_valid']:>12}{c['duration_s']:>12.3f}")
    if s["slow"]:
        lines.append("")
        lines.append(f"{'slow signal':<28}{'unit':<10}{'points':>12}{'min':>12}{'max':>12}")
        for x in s["slow"]:
            lo = "-" if x["min"] is None else f"{x['min']:.4g}"
            hi = "-" if x["max"] is None else f"{x['max']:.4g}"
            lines.append(f"{x['name']:<28}{x['unit']:<10}{x['n_points']:>12}{lo:>12}{hi:>12}")
    lines.append("")
    lines.append(f"decoded   {rep.decoded} {rep.units}")
    if rep.rejected:
        for reason, n in sorted(rep.rejected.items()):
            where = rep.first_position.get(reason, "")
            at = f"  (first at {where})" if where else ""
            lines.append(f"rejected  {n:>10}  {unit_of(reason, rep.units):<9}{reason}{at}")
    else:
        lines.append("rejected  none")
    if rep.gaps:
        lines.append(f"gaps      {len(rep.gaps)}")
        for g in rep.gaps[:20]:
            kind = f" [{g.kind}]" if g.kind != "gap" else ""
            lines.append(f"          {g.channel}: {g.n_missing} sample(s) missing from index "
                         f"{g.start_index} (t = {g.time_s:.6f} s){kind}")
        if len(rep.gaps) > 20:
            lines.append(f"          ... {len(rep.gaps) - 20} more")
    else:
        lines.append("gaps      none")
    for name, st in rep.timebase.items():
        if st:
            drift = st.get("drift_ppm")
            lines.append(f"clock     {name}: jitter {st.get('jitter_s', 0) * 1e6:.1f} us, "
                         f"max residual {st.get('max_abs_residual_s', 0) * 1e6:.1f} us"
                         + (f", drift {drift:.1f} ppm" if drift is not None else "")
                         + (f", offset {st['offset_s'] * 1e6:+.1f} us from the channel's clock"
                            if "offset_s" in st else ""))
    return "\n".join(lines)

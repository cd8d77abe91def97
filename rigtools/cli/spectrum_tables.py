"""What ``rigtools spectrum`` prints: the text table, the JSON document and the CSV table.

All three hold the same three kinds of record of a
:class:`~rigtools.analysis.recording.RecordingAnalysis`:

* **channels**: unit, rate, Welch windows, degrees of freedom, RMS in the time domain and
  from the PSD, quality flags, and why a channel was not analysed;
* **lines**: the PSD peaks that are not modes (mesh harmonics and their sidebands, shaft
  harmonics, tones, unresolved peaks), with frequency, prominence, kind and order;
* **modes**: the structural peaks' SDOF fits, ``{channel, f_n_Hz, f_n_sd_Hz, zeta, zeta_sd,
  response, kind, flags}``.

JSON (:func:`spectrum_document`): one object, ``{"source", "welch", "mesh_frequency_Hz",
"settings", "channels": [...], "lines": [...], "modes": [...]}``; values not known are
``null`` (strict JSON: no NaN).

CSV (:func:`spectrum_csv`): one header line and one row per record, the columns
:data:`CSV_COLUMNS`; ``record`` says which kind of record a row is (``channel``, ``line``,
``mode``), cells that do not apply to it are empty, and ``flags`` are ``;``-separated.

Text (:func:`format_spectrum`): a channel table and a peak table whose columns are as wide as
their longest entry (a channel named ``/imu/linear_acceleration.x`` keeps its unit apart).
"""

from __future__ import annotations

import csv
import io
import math
from collections.abc import Sequence
from typing import Any, Final

from rigtools.analysis.peak_results import ModalEstimate, Peak
from rigtools.analysis.recording import ChannelAnalysis, RecordingAnalysis

__all__ = [
    "CSV_COLUMNS",
    "channel_flags",
    "channel_records",
    "format_spectrum",
    "line_label",
    "line_records",
    "mode_flags",
    "mode_records",
    "spectrum_csv",
    "spectrum_document",
]

#: Columns of :func:`spectrum_csv`, in order, and what each holds.
CSV_COLUMNS: Final[dict[str, str]] = {
    "record": "channel, line or mode",
    "channel": "channel name",
    "unit": "channel unit (channel rows)",
    "sample_rate_Hz": "nominal sample rate (Hz; channel rows)",
    "n_windows": "Welch windows averaged (channel rows)",
    "dof": "equivalent degrees of freedom of the PSD (channel rows)",
    "rms_time": "RMS of the detrended valid samples (unit; channel rows)",
    "rms_psd": "RMS from the PSD (unit; channel rows)",
    "f_Hz": "peak frequency (Hz; line rows)",
    "f_sd_Hz": "standard uncertainty of f_Hz (Hz; line rows)",
    "prominence_dB": "prominence of the peak on the log PSD (dB; line and mode rows)",
    "kind": "peak kind: structural (mode rows), mesh_harmonic, mesh_sideband, "
            "shaft_harmonic, tonal, unresolved (line rows)",
    "order": "mesh (or shaft) harmonic order k (line rows)",
    "sideband": "signed sideband order j (line rows)",
    "f_n_Hz": "natural frequency from the SDOF fit (Hz; mode rows)",
    "f_n_sd_Hz": "standard uncertainty of f_n_Hz (Hz; mode rows)",
    "zeta": "damping ratio from the SDOF fit (mode rows)",
    "zeta_sd": "standard uncertainty of zeta (mode rows)",
    "response": "SDOF response fitted: displacement, velocity or acceleration (mode rows)",
    "flags": "';'-separated flags: of the channel (channel rows) or of the fit (mode rows)",
    "error": "why the channel was not analysed (channel rows)",
}

#: Least width of the channel column of the text tables.
MIN_NAME_WIDTH: Final = 16


def _num(v: Any) -> float | None:
    """A finite float, or None."""
    try:
        f = float(v)
    except (TypeError, ValueError):
        return None
    return f if math.isfinite(f) else None


def channel_flags(ca: ChannelAnalysis) -> list[str]:
    """Quality flags of a channel: gaps, clipping, dropped segments, too short, few averages."""
    q = ca.quality
    out = []
    if q.n_invalid:
        out.append(f"gaps({q.n_invalid} invalid)")
    if q.clipped:
        out.append("clipped")
    if q.n_segments_dropped:
        out.append(f"segments_dropped({q.n_segments_dropped})")
    if q.constant:
        out.append("constant")
    if q.too_short:
        out.append("too_short")
    if ca.spectrum is not None and ca.peaks is None:
        out.append("peaks_failed")
    if ca.spectrum is not None and q.low_dof:
        out.append("low_dof")  # few Welch averages: damping less reliable
    return out


def mode_flags(ca: ChannelAnalysis, pk: Peak) -> list[str]:
    """Why a mode's estimate may not be trusted: the fit's flags, few averages, masked lines."""
    m = pk.mode
    if m is None:
        return ["not_fitted"]
    out = list(m.fit.flags)
    if m.low_dof:
        out.append("low_dof")
    if ca.peaks is not None:
        index = next((i for i, p in enumerate(ca.peaks.structural) if p is pk), None)
        if index is not None and ca.peaks.lines_on(index):
            out.append("lines_masked")
    if ca.quality.clipped:
        out.append("clipped")
    return list(dict.fromkeys(out))


def line_label(pk: Peak) -> str:
    """How a line is named on the plot and in the text table: ``2x mesh``, ``3x shaft``, ..."""
    loc = pk.location
    if pk.kind == "mesh_harmonic" and loc.harmonic is not None:
        return f"{loc.harmonic}x mesh"
    if pk.kind == "mesh_sideband" and loc.harmonic is not None and loc.sideband is not None:
        return f"{loc.harmonic}x mesh {loc.sideband:+d} shaft"
    if pk.kind == "shaft_harmonic" and loc.harmonic is not None:
        return f"{loc.harmonic}x shaft"
    return ""


def channel_records(analysis: RecordingAnalysis) -> list[dict[str, Any]]:
    """One record per channel (JSON-ready)."""
    out = []
    for ca in analysis.channels.values():
        ok = ca.spectrum is not None and ca.rms is not None
        out.append({
            "channel": ca.name,
            "unit": ca.unit,
            "sample_rate_Hz": _num(ca.sample_rate_Hz),
            "n_windows": int(ca.quality.n_windows) if ok else None,
            "dof": _num(ca.quality.dof) if ok else None,
            "rms_time": _num(ca.rms.rms_time) if ca.rms is not None else None,
            "rms_psd": _num(ca.rms.rms_parseval) if ca.rms is not None else None,
            "flags": channel_flags(ca),
            "error": ca.error,
        })
    return out


def _structural(ca: ChannelAnalysis) -> list[Peak]:
    return [] if ca.peaks is None else [p for p in ca.peaks.peaks if p.kind == "structural"]


def line_records(analysis: RecordingAnalysis) -> list[dict[str, Any]]:
    """One record per line (a PSD peak that is not a mode), JSON-ready."""
    out = []
    for ca in analysis.channels.values():
        if ca.peaks is None:
            continue
        structural = ca.peaks.structural
        for pk in ca.peaks.peaks:
            if pk.kind == "structural":
                continue
            on: ModalEstimate | None = None
            if pk.on_mode is not None and 0 <= pk.on_mode < len(structural):
                on = structural[pk.on_mode].mode
            out.append({
                "channel": ca.name,
                "f_Hz": _num(pk.f_Hz),
                "f_sd_Hz": _num(pk.f_std_Hz),
                "psd_per_Hz": _num(pk.psd_per_Hz),
                "prominence_dB": _num(pk.prominence_dB),
                "kind": pk.kind,
                "order": pk.location.harmonic,
                "sideband": pk.location.sideband,
                "label": line_label(pk),
                "on_mode_f_n_Hz": _num(on.f_n_Hz) if on is not None else None,
            })
    return out


def mode_records(analysis: RecordingAnalysis) -> list[dict[str, Any]]:
    """One record per fitted mode (JSON-ready).

    Keys: ``channel, f_n_Hz, f_n_sd_Hz, zeta, zeta_sd, response, kind, flags``.
    """
    out = []
    for ca in analysis.channels.values():
        for pk in _structural(ca):
            m = pk.mode
            out.append({
                "channel": ca.name,
                "f_n_Hz": _num(m.f_n_Hz) if m else None,
                "f_n_sd_Hz": _num(m.f_n_std_Hz) if m else None,
                "zeta": _num(m.zeta) if m else None,
                "zeta_sd": _num(m.zeta_std) if m else None,
                "response": (m.fit.response or m.response) if m else None,
                "kind": pk.kind,
                "flags": mode_flags(ca, pk),
            })
    return out


def _welch(analysis: RecordingAnalysis) -> dict[str, Any] | None:
    first = next((c.spectrum for c in analysis.channels.values() if c.spectrum is not None),
                 None)
    if first is None:
        return None
    return {"nperseg": int(first.nperseg), "noverlap": int(first.noverlap),
            "window": str(first.window) if isinstance(first.window, str | tuple) else "custom",
            "resolution_Hz": _num(first.fs_Hz / first.nperseg)}


def spectrum_document(analysis: RecordingAnalysis, source: str,
                      mesh_note: str | None = None) -> dict[str, Any]:
    """The JSON document of ``rigtools spectrum --json`` (see the module docstring)."""
    settings = {k: v for k, v in analysis.settings.items()
                if isinstance(v, str | int | float | bool | list | type(None))}
    return {
        "source": source,
        "welch": _welch(analysis),
        "mesh_frequency_Hz": _num(analysis.settings.get("mesh_frequency_Hz")),
        "mesh_frequency_note": mesh_note,
        "settings": settings,
        "channels": channel_records(analysis),
        "lines": line_records(analysis),
        "modes": mode_records(analysis),
    }


def _cell(v: Any) -> str:
    if v is None:
        return ""
    if isinstance(v, list):
        return ";".join(str(x) for x in v)
    if isinstance(v, float):
        return repr(v)
    return str(v)


def spectrum_csv(analysis: RecordingAnalysis) -> str:
    """The CSV table of ``rigtools spectrum --csv``: :data:`CSV_COLUMNS`, a row per record."""
    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=list(CSV_COLUMNS), lineterminator="\n",
                       extrasaction="ignore")
    w.writeheader()
    for kind, records in (("channel", channel_records(analysis)),
                          ("line", line_records(analysis)),
                          ("mode", mode_records(analysis))):
        for r in records:
            w.writerow({k: _cell(v) for k, v in {"record": kind, **r}.items()})
    return buf.getvalue()


def _f(v: float | None, fmt: str) -> str:
    return "-" if v is None or not math.isfinite(v) else format(v, fmt)


def _table(header: Sequence[tuple[str, str]], rows: Sequence[Sequence[str]],
           trailing: int = 0) -> list[str]:
    """Columns as wide as their longest cell, two spaces apart.

    ``<`` aligns left, ``>`` right; the last ``trailing`` left-aligned columns are not padded.
    """
    widths = [max(len(h), *(len(r[i]) for r in rows)) if rows else len(h)
              for i, (h, _) in enumerate(header)]

    def line(cells: Sequence[str]) -> str:
        parts = []
        for i, ((_, align), c) in enumerate(zip(header, cells, strict=True)):
            last = i >= len(header) - trailing
            parts.append(c if last and align == "<" else format(c, f"{align}{widths[i]}"))
        return "  ".join(parts).rstrip()

    return [line([h for h, _ in header]), *(line(r) for r in rows)]


def format_spectrum(analysis: RecordingAnalysis, source: str) -> str:
    """The printed tables of a :class:`~rigtools.analysis.recording.RecordingAnalysis`."""
    chans = list(analysis.channels.values())
    welch = _welch(analysis)
    lines = [f"source    {source}"]
    if welch is not None:
        lines.append(f"welch     nperseg {welch['nperseg']} ({welch['resolution_Hz']:.4g} Hz "
                     f"bins), {welch['window']} window, noverlap {welch['noverlap']}")
    lines.append("")
    name_w = max([MIN_NAME_WIDTH, *(len(c.name) for c in chans)])
    rows = []
    for r, ca in zip(channel_records(analysis), chans, strict=True):
        flags = ",".join(r["flags"]) or "-"
        if r["error"]:
            flags += f": {r['error']}"
        rows.append([ca.name.ljust(name_w), ca.unit, f"{ca.sample_rate_Hz:g}",
                     "-" if r["n_windows"] is None else str(r["n_windows"]),
                     _f(r["dof"], ".1f"), _f(r["rms_time"], ".4g"), _f(r["rms_psd"], ".4g"),
                     flags])
    lines += _table([("channel", "<"), ("unit", "<"), ("rate Hz", ">"), ("windows", ">"),
                     ("dof", ">"), ("RMS time", ">"), ("RMS PSD", ">"), ("flags", "<")],
                    rows, trailing=1)
    lines.append("")
    rows = []
    resonance_note = False
    for ca in chans:
        if ca.peaks is None:
            continue
        for pk in ca.peaks.peaks:
            m = pk.mode if pk.kind == "structural" else None
            kind = pk.kind + ("*" if pk.possible_resonance else "")
            resonance_note |= pk.possible_resonance
            note = ",".join(mode_flags(ca, pk)) if pk.kind == "structural" else line_label(pk)
            rows.append([ca.name.ljust(name_w), _f(pk.f_Hz, ".1f"), _f(pk.f_std_Hz, ".1f"),
                         _f(pk.prominence_dB, ".1f"), kind,
                         _f(m.f_n_Hz if m else None, ".1f"),
                         _f(m.f_n_std_Hz if m else None, ".1f"),
                         _f(m.zeta if m else None, ".4f"),
                         _f(m.zeta_std if m else None, ".4f"), note or "-"])
    lines += _table([("channel", "<"), ("f Hz", ">"), ("+-Hz", ">"), ("prom dB", ">"),
                     ("kind", "<"), ("f_n Hz", ">"), ("+-Hz", ">"), ("zeta", ">"),
                     ("+-", ">"), ("notes", "<")], rows, trailing=1)
    if not rows:
        lines.append("(no peak)")
    elif resonance_note:
        lines.append("* a line on a structural mode (the mode has its own structural row)")
    return "\n".join(lines)

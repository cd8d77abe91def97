"""``rigtools spectrum FILE``: Welch PSD, RMS and peaks (natural frequencies, damping) per channel.

Prints one line per channel (rate, Welch windows, degrees of freedom, RMS in the time domain
and from the PSD, quality flags) and one line per PSD peak (frequency, prominence, kind; for
structural peaks the SDOF natural frequency and damping with their standard uncertainties).
``--plot OUT.png`` draws the PSDs with the peaks marked (:func:`rigtools.plots.spectrum.
plot_spectrum`: a matplotlib Figure on the Agg canvas, no pyplot). Exit 0 when at least one
channel was analysed, 3 when none could be.
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from models.geometry import mesh_frequency_Hz
from rigtools.cli.arguments import int_at_least, non_negative_float, positive_float
from rigtools.cli.common import add_read_options, fail, read_from_args, warn_losses
from rigtools.ingest import Recording

if TYPE_CHECKING:
    from rigtools.analysis.recording import ChannelAnalysis, RecordingAnalysis

__all__ = ["add_parser", "format_spectrum", "mesh_frequency_from_speed", "run"]

#: Shortest Welch window accepted on the command line (samples).
MIN_NPERSEG = 16
SPEED_SIGNAL = "PinionSpeed_rpm"


def add_parser(subparsers: Any) -> None:
    """Register the subcommand."""
    p = subparsers.add_parser(
        "spectrum",
        help="print the PSD peaks (natural frequencies, damping) and RMS of each channel",
        description="Read a recording and print, per channel, the Welch PSD's RMS and peaks: "
        "natural frequencies with damping and uncertainties, mesh and shaft lines.",
    )
    p.add_argument("file", help="recording file")
    p.add_argument("--channel", action="append", dest="channels", metavar="C",
                   help="channel to analyse (repeat for several; default all)")
    p.add_argument("--nperseg", type=_nperseg, default=4096, metavar="N",
                   help=f"Welch window length in samples, >= {MIN_NPERSEG} (default 4096)")
    p.add_argument("--mesh-frequency-Hz", dest="mesh_Hz", type=positive_float, default=None,
                   metavar="F", help="mesh frequency (Hz, > 0), to tell mesh harmonics from "
                   "resonances; default z1 x mean speed / 60 when --z1 is given and the "
                   "recording holds the speed signal")
    p.add_argument("--z1", type=_teeth, default=None, metavar="N",
                   help="pinion teeth: with the speed signal gives the mesh frequency")
    p.add_argument("--speed-signal", dest="speed_signal", default=SPEED_SIGNAL, metavar="S",
                   help=f"slow signal of the pinion speed in rpm (default {SPEED_SIGNAL})")
    p.add_argument("--prominence-dB", dest="prominence_dB", type=non_negative_float, default=6.0,
                   metavar="DB", help="least prominence of a peak (dB, >= 0, default 6)")
    p.add_argument("--plot", metavar="OUT.png", help="write the PSDs with peaks as a PNG")
    add_read_options(p)
    p.set_defaults(func=run)


def _nperseg(text: str) -> int:
    return int_at_least(text, MIN_NPERSEG)


def _teeth(text: str) -> int:
    return int_at_least(text, 1)


def mesh_frequency_from_speed(rec: Recording, z1: int, speed_signal: str = SPEED_SIGNAL
                              ) -> tuple[float | None, str]:
    r"""Mesh frequency :math:`z_1 \bar n / 60` (Hz) from a speed slow signal in rpm.

    Returns the frequency (None when it cannot be derived) and a note saying how it was got
    or why not. The frequency is :func:`models.geometry.mesh_frequency_Hz` of the mean speed.
    """
    slow = rec.slow
    sig = slow.get(speed_signal)
    if sig is None:
        return None, (f"no slow signal {speed_signal!r} (the recording holds: "
                      f"{', '.join(slow) or 'none'})")
    v = np.asarray(sig.values, np.float64)
    v = v[np.isfinite(v)]
    if v.size == 0:
        return None, f"slow signal {speed_signal!r} holds no finite value"
    rpm = float(np.mean(np.abs(v)))
    if not rpm > 0:
        return None, f"slow signal {speed_signal!r} is zero (a standstill)"
    f_mesh = float(mesh_frequency_Hz(rpm, z1))
    return f_mesh, (f"mesh frequency {f_mesh:.4g} Hz = z1 {z1} x mean {speed_signal} "
                    f"{rpm:.5g} rpm / 60")


def _f(v: float | None, fmt: str) -> str:
    return "-" if v is None or not math.isfinite(v) else format(v, fmt)


def _channel_flags(ca: ChannelAnalysis) -> str:
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
    return ",".join(out) or "-"


def format_spectrum(analysis: RecordingAnalysis, source: str) -> str:
    """The printed table of a :class:`~rigtools.analysis.recording.RecordingAnalysis`."""
    chans = list(analysis.channels.values())
    first = next((c.spectrum for c in chans if c.spectrum is not None), None)
    lines = [f"source    {source}"]
    if first is not None:
        lines.append(f"welch     nperseg {first.nperseg} ({first.fs_Hz / first.nperseg:.4g} Hz "
                     f"bins), {first.window} window, noverlap {first.noverlap}")
    lines.append("")
    lines.append(f"{'channel':<16}{'unit':<9}{'rate Hz':>9}{'windows':>9}{'dof':>8}"
                 f"{'RMS time':>11}{'RMS PSD':>11}  flags")
    for ca in chans:
        if ca.spectrum is None or ca.rms is None:
            lines.append(f"{ca.name:<16}{ca.unit:<9}{ca.sample_rate_Hz:>9g}{'-':>9}{'-':>8}"
                         f"{'-':>11}{'-':>11}  {_channel_flags(ca)}: {ca.error}")
            continue
        q = ca.quality
        lines.append(f"{ca.name:<16}{ca.unit:<9}{ca.sample_rate_Hz:>9g}{q.n_windows:>9}"
                     f"{q.dof:>8.1f}{float(ca.rms.rms_time):>11.4g}"
                     f"{float(ca.rms.rms_parseval):>11.4g}  {_channel_flags(ca)}")
    lines.append("")
    lines.append(f"{'channel':<16}{'f Hz':>10}{'+-Hz':>8}{'prom dB':>9}  {'kind':<16}"
                 f"{'f_n Hz':>10}{'+-Hz':>8}{'zeta':>9}{'+-':>9}")
    n = 0
    for ca in chans:
        if ca.peaks is None:
            continue
        for pk in ca.peaks.peaks:
            n += 1
            m = pk.mode if (pk.kind == "structural" or pk.possible_resonance) else None
            kind = pk.kind + ("*" if pk.possible_resonance else "")
            lines.append(
                f"{ca.name:<16}{pk.f_Hz:>10.1f}{_f(pk.f_std_Hz, '.1f'):>8}"
                f"{pk.prominence_dB:>9.1f}  {kind:<16}"
                f"{_f(m.f_n_Hz if m else None, '.1f'):>10}"
                f"{_f(m.f_n_std_Hz if m else None, '.1f'):>8}"
                f"{_f(m.zeta if m else None, '.4f'):>9}{_f(m.zeta_std if m else None, '.4f'):>9}")
    if n == 0:
        lines.append("(no peak)")
    elif any(pk.possible_resonance for ca in chans if ca.peaks for pk in ca.peaks.peaks):
        lines.append("* broad peak on a mesh or shaft line: a resonance may coincide with it")
    return "\n".join(lines)


def run(args: argparse.Namespace) -> int:
    """Run the subcommand."""
    # The analysis (scipy.signal) is loaded when this subcommand runs, not when the command
    # line starts: ``rigtools info`` and ``ingest`` do not pay for it.
    from rigtools.analysis.recording import analyse_recording

    rec = read_from_args(args)
    if args.channels:
        missing = [c for c in args.channels if c not in rec.channels]
        if missing:
            return fail(f"{args.file}: no channel {', '.join(map(repr, missing))} "
                        f"(the recording holds: {', '.join(rec.channels) or 'none'})")
    if not rec.channels:
        return fail(f"{args.file}: the recording holds no uniform channel")
    mesh_Hz = args.mesh_Hz
    if mesh_Hz is None and getattr(args, "z1", None) is not None:
        mesh_Hz, note = mesh_frequency_from_speed(rec, args.z1, args.speed_signal)
        if mesh_Hz is None:
            print(f"rigtools: warning: {args.file}: --z1 given but {note}: mesh harmonics "
                  "are not told apart", file=sys.stderr)
        else:
            print(note)
    analysis = analyse_recording(rec, channels=args.channels, nperseg=args.nperseg,
                                 mesh_frequency_Hz=mesh_Hz,
                                 prominence_dB=args.prominence_dB, errors="flag")
    print(format_spectrum(analysis, str(args.file)))
    warn_losses(rec)
    for ca in analysis.channels.values():
        if ca.error:
            print(f"rigtools: warning: {ca.error}", file=sys.stderr)
    if args.plot:
        # matplotlib is loaded only when a figure is asked for (every subcommand starts faster)
        from rigtools.plots.spectrum import plot_spectrum

        fig = plot_spectrum(analysis, Path(args.file).name)
        out = Path(args.plot)
        fig.savefig(out, format="png", dpi=150)
        print(f"wrote {out}")
    if all(ca.spectrum is None for ca in analysis.channels.values()):
        return fail(f"{args.file}: no channel could be analysed")
    return 0

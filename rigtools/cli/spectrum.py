"""``rigtools spectrum FILE``: Welch PSD, RMS and peaks (natural frequencies, damping) per channel.

Prints one line per channel (rate, Welch windows, degrees of freedom, RMS in the time domain
and from the PSD, quality flags) and one line per PSD peak (frequency, prominence, kind; for
structural peaks the SDOF natural frequency and damping with their standard uncertainties and
the fit's flags; for mesh and shaft lines their order). ``--json`` prints the same as one JSON
document and ``--csv`` as one CSV table (:mod:`rigtools.cli.spectrum_tables` defines both).
``--plot OUT`` draws the PSDs with the peaks marked and the mesh orders labelled
(:func:`rigtools.plots.spectrum.plot_spectrum`) as PNG, SVG, PDF or JPEG after the suffix.
Every option is checked before the recording is read (exit 2; a plot path that cannot be
written, exit 3). Exit 0 when at least one channel was analysed, 3 when none could be.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Any, Final

import numpy as np

from models.geometry import mesh_frequency_Hz
from rigtools.cli.arguments import (
    int_at_least,
    int_in_range,
    non_negative_float,
    output_path,
    positive_float,
)
from rigtools.cli.common import (
    add_read_options,
    fail,
    output_problem,
    read_from_args,
    warn_losses,
)
from rigtools.cli.spectrum_tables import (
    CSV_COLUMNS,
    format_spectrum,
    spectrum_csv,
    spectrum_document,
)
from rigtools.ingest import Recording
from rigtools.recording_summary import json_safe, no_uniform_channel_hint

if TYPE_CHECKING:
    from rigtools.analysis.recording import RecordingAnalysis

__all__ = ["MAX_NPERSEG", "MIN_NPERSEG", "PLOT_SUFFIXES", "add_parser", "format_spectrum",
           "mesh_frequency_from_speed", "run"]

#: Shortest Welch window accepted on the command line (samples).
MIN_NPERSEG: Final = 16
#: Longest Welch window accepted (samples): 10.24 s at 25.6 kHz (0.1 Hz bins). The window's
#: properties cost about 1 kB per sample before the signal's length is checked (2**22 samples:
#: 4.6 GB and 50 s on a 1.5 s file; 1e8 asked 49 GiB), so longer ones are refused before any
#: work.
MAX_NPERSEG: Final = 1 << 18
SPEED_SIGNAL: Final = "PinionSpeed_rpm"
#: Suffixes ``--plot`` writes, each in its own format (matplotlib).
PLOT_SUFFIXES: Final = (".png", ".svg", ".pdf", ".jpg", ".jpeg")
#: ``--response`` choices: ``auto`` follows each channel's unit.
RESPONSES: Final = ("auto", "acceleration", "velocity", "displacement")


def add_parser(subparsers: Any) -> None:
    """Register the subcommand."""
    p = subparsers.add_parser(
        "spectrum",
        help="print the PSD peaks (natural frequencies, damping) and RMS of each channel",
        description="Read a recording and print, per channel, the Welch PSD's RMS and peaks: "
        "natural frequencies with damping and uncertainties, mesh and shaft lines. --csv "
        "columns: " + ", ".join(CSV_COLUMNS) + ".",
    )
    p.add_argument("file", help="recording file")
    p.add_argument("--channel", action="append", dest="channels", metavar="C",
                   help="channel to analyse (repeat for several; default all)")
    p.add_argument("--nperseg", type=_nperseg, default=4096, metavar="N",
                   help=f"Welch window length in samples, {MIN_NPERSEG} to {MAX_NPERSEG} "
                   "(default 4096)")
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
    p.add_argument("--response", choices=RESPONSES, default="auto",
                   help="single-DOF response fitted to the modes: auto (default) follows each "
                   "channel's unit (acceleration for m/s^2 and g, velocity for m/s and mm/s, "
                   "displacement for m and um; a unit that says nothing: the best fit, flagged)")
    p.add_argument("--f-min-Hz", dest="f_min", type=non_negative_float, default=None,
                   metavar="F", help="lowest frequency searched for peaks and plotted (Hz, >= 0; "
                   "default 0)")
    p.add_argument("--f-max-Hz", dest="f_max", type=positive_float, default=None,
                   metavar="F", help="highest frequency searched for peaks and plotted (Hz, "
                   "> --f-min-Hz; default the Nyquist frequency)")
    p.add_argument("--db", action="store_true",
                   help="plot the PSD in dB re 1 unit^2/Hz (default: a logarithmic axis)")
    p.add_argument("--plot", metavar="OUT", type=output_path(*PLOT_SUFFIXES),
                   help="write the PSDs with the peaks marked; the suffix chooses the format: "
                   + ", ".join(PLOT_SUFFIXES))
    out = p.add_mutually_exclusive_group()
    out.add_argument("--json", action="store_true",
                     help="print channels, lines and modes as one JSON document")
    out.add_argument("--csv", action="store_true",
                     help="print channels, lines and modes as one CSV table (a row per record, "
                     "column 'record' says which)")
    add_read_options(p)
    # the parser itself, for the checks that tie two options (argparse's usage error, exit 2)
    p.set_defaults(func=run, parser=p)


def _nperseg(text: str) -> int:
    return int_in_range(text, MIN_NPERSEG, MAX_NPERSEG)


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


def _print_result(args: argparse.Namespace, analysis: RecordingAnalysis,
                  note: str | None) -> None:
    if args.json:
        doc = json_safe(spectrum_document(analysis, str(args.file), note))
        print(json.dumps(doc, indent=2, allow_nan=False))
    elif args.csv:
        sys.stdout.write(spectrum_csv(analysis))
    else:
        print(format_spectrum(analysis, str(args.file)))


def run(args: argparse.Namespace) -> int:
    """Run the subcommand."""
    # The analysis (scipy.signal) is loaded when this subcommand runs, not when the command
    # line starts: ``rigtools info`` and ``ingest`` do not pay for it.
    from rigtools.analysis.recording import analyse_recording

    if args.f_min is not None and args.f_max is not None and not args.f_min < args.f_max:
        args.parser.error(f"argument --f-max-Hz: must be > --f-min-Hz ({args.f_min:g}), "
                          f"got {args.f_max:g}")
    if args.plot:
        problem = output_problem(args.plot)
        if problem:
            return fail(problem)
    machine = bool(args.json or args.csv)
    rec = read_from_args(args)
    if args.channels:
        missing = [c for c in args.channels if c not in rec.channels]
        if missing:
            return fail(f"{args.file}: no channel {', '.join(map(repr, missing))} "
                        f"(the recording holds: {', '.join(rec.channels) or 'none'})")
    if not rec.channels:
        warn_losses(rec)
        return fail(f"{args.file}: {no_uniform_channel_hint(rec)}")
    mesh_Hz = args.mesh_Hz
    note = None
    if mesh_Hz is None and getattr(args, "z1", None) is not None:
        mesh_Hz, note = mesh_frequency_from_speed(rec, args.z1, args.speed_signal)
        if mesh_Hz is None:
            print(f"rigtools: warning: {args.file}: --z1 given but {note}: mesh harmonics "
                  "are not told apart", file=sys.stderr)
            note = None
        elif not machine:
            print(note)
    f_range = None
    if args.f_min is not None or args.f_max is not None:
        f_range = (args.f_min or 0.0, args.f_max if args.f_max is not None else float("inf"))
    analysis = analyse_recording(rec, channels=args.channels, nperseg=args.nperseg,
                                 mesh_frequency_Hz=mesh_Hz, prominence_dB=args.prominence_dB,
                                 f_range_Hz=f_range,
                                 response=None if args.response == "auto" else args.response,
                                 errors="flag")
    _print_result(args, analysis, note)
    warn_losses(rec)
    for ca in analysis.channels.values():
        if ca.error:
            print(f"rigtools: warning: {ca.error}", file=sys.stderr)
    if args.plot:
        # matplotlib is loaded only when a figure is asked for (every subcommand starts faster)
        from rigtools.plots.spectrum import plot_spectrum

        fig = plot_spectrum(analysis, Path(args.file).name, f_range_Hz=f_range, db=args.db)
        out = Path(args.plot)
        fmt = out.suffix.lower().lstrip(".")
        fig.savefig(out, format="jpeg" if fmt == "jpg" else fmt, dpi=150)
        print(f"wrote {out}", file=sys.stderr if machine else sys.stdout)
    if all(ca.spectrum is None for ca in analysis.channels.values()):
        return fail(f"{args.file}: no channel could be analysed")
    return 0

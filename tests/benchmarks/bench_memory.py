"""Peak memory of ingest against the size of the decoded arrays.

The ingest issue asks that a 30-minute, 4-channel, 25.6 kHz recording reads with a peak
resident set within about twice the size of its decoded float arrays (4 x 46.08 M samples x
8 bytes = 1.47 GB). Each file is read in a fresh child process; the child first reads a tiny
file of the same format (so every lazily imported module is loaded), notes its resident set,
reads the big file, and reports the high-water mark above that baseline. Two modes: a plain
library call, and the command line's set-up (``rigtools.cli.tune_allocator``: a fixed glibc
mmap threshold, so freed batch buffers go back to the system instead of raising the peak).

Run: ``python tests/benchmarks/bench_memory.py [--seconds 1800] [--formats mcap blf]``
(writing the 30-minute files takes a few minutes and about 2 GB of /tmp).
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import textwrap
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from rigtools.ingest.can.frames import CanFrameBatch

FS = 25_600.0
N_CH = 4

_CHILD = textwrap.dedent(
    """
    import json, sys, time
    from rigtools.ingest import read

    def status(key):
        for line in open("/proc/self/status"):
            if line.startswith(key):
                return int(line.split()[1]) * 1024
        return 0

    small, big, mode = sys.argv[1], sys.argv[2], sys.argv[3]
    if mode == "cli":  # what the rigtools command line sets up before reading
        from rigtools.cli import tune_allocator
        tune_allocator()
    read(small)
    base = status("VmRSS:")
    t0 = time.perf_counter()
    rec = read(big)
    read_s = time.perf_counter() - t0
    peak = status("VmHWM:")
    n = sum(len(c) for c in rec.channels.values())
    print(json.dumps({"base": base, "peak": peak, "n_samples": n, "read_s": read_s,
                      "rejected": rec.report.n_rejected, "gaps": len(rec.report.gaps)}))
    """
)


def write_files(folder: Path, seconds: float, fmt: str) -> Path:
    """Write a ``seconds``-long reference recording (and a 1 s one) in ``fmt``."""
    for dur, name in ((1.0, "small"), (seconds, "big")):
        n = int(dur * FS) // 3 * 3
        rng = np.random.default_rng(0)
        chans = [np.round(rng.normal(0, 300, n)) * 0.015 for _ in range(N_CH)]
        path = folder / f"{name}.{fmt}"
        if fmt == "mcap":
            from rigtools.demo.mcap_writer import write_accel_mcap

            write_accel_mcap(
                path,
                {f"accel_{i + 1}": (c, FS, "m/s^2", 0, 1.7e9) for i, c in enumerate(chans)},
                compression="zstd", batch=2048, chunk_size=4 << 20,
            )
        else:
            from rigtools.demo.can_writer import encode_reference_frames, write_can_log

            frames = encode_reference_frames(chans, {"Torque_Nm": 302.0}, rng=1)
            del chans
            if fmt == "log":  # in pieces: the text of 61 M frames at once would take ~20 GB
                _write_candump_in_pieces(path, frames)
            else:
                write_can_log(path, frames, fmt, engine="rigtools")
    return folder / f"big.{fmt}"


def _write_candump_in_pieces(path: Path, frames: CanFrameBatch, piece: int = 1 << 20) -> None:
    """The ``candump -L`` text of ``frames``, written ``piece`` frames at a time.

    The same bytes as :func:`rigtools.demo.can_writer.write_can_log` (the frames are in time
    order, so no piece's first stamp lifts a later one), at the memory of one piece.
    """
    from rigtools.demo.can_writer import candump_text

    n = len(frames)
    with open(path, "w", encoding="utf-8", newline="\n") as f:
        for a in range(0, n, piece):
            f.write(candump_text(frames.take(np.arange(a, min(a + piece, n)))))


def read_in_child(small: Path, big: Path, mode: str = "library") -> dict[str, float]:
    """Read ``big`` in a fresh process after a warm-up read of ``small``; return its figures.

    ``base`` and ``peak`` are the resident set after the warm-up and its high-water mark
    (bytes), ``read_s`` the time of ``read(big)``, ``ratio`` the peak above the base per byte
    of decoded float64 samples.
    """
    run = subprocess.run([sys.executable, "-c", _CHILD, str(small), str(big), mode],
                         check=True, capture_output=True, text=True)
    r = json.loads(run.stdout.strip().splitlines()[-1])
    r["mode"] = mode
    r["file_bytes"] = big.stat().st_size
    r["decoded_bytes"] = r["n_samples"] * 8
    r["ratio"] = (r["peak"] - r["base"]) / r["decoded_bytes"]
    return r


def measure(fmt: str, seconds: float) -> list[dict[str, float]]:
    """Write once, read in a child per mode (library call, command line), return figures."""
    with tempfile.TemporaryDirectory() as tmp:
        big = write_files(Path(tmp), seconds, fmt)
        small = Path(tmp) / f"small.{fmt}"
        return [read_in_child(small, big, mode) for mode in ("library", "cli")]


def main(argv: list[str] | None = None) -> int:
    """Print peak-memory figures for each format."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seconds", type=float, default=1800.0)
    ap.add_argument("--formats", nargs="+", default=["mcap", "blf"])
    args = ap.parse_args(argv)
    print(f"{args.seconds:g} s, {N_CH} channels, {FS:g} Hz")
    print(f"{'format':<8}{'mode':<9}{'file MB':>10}{'decoded MB':>12}{'peak-base MB':>14}"
          f"{'ratio':>8}")
    for fmt in args.formats:
        for r in measure(fmt, args.seconds):
            print(f"{fmt:<8}{r['mode']:<9}{r['file_bytes'] / 1e6:>10.1f}"
                  f"{r['decoded_bytes'] / 1e6:>12.1f}{(r['peak'] - r['base']) / 1e6:>14.1f}"
                  f"{r['ratio']:>8.2f}", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

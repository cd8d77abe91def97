"""Linear cost of ingest: time per decoded sample and peak memory per decoded byte by size.

For each format (BLF, candump ``-L`` log, MCAP) and each duration (default 1, 10 and 30
minutes of 4 channels at 25.6 kHz, the reference layout; MCAP as protobuf ``AccelBatch``
messages in zstd chunks), the benchmark writes the recording, reads it with
``rigtools.ingest.read`` in a fresh process after a warm-up read of a 1-second file of the
same format (:func:`bench_memory.read_in_child`), and prints

* the time of ``read()`` per decoded sample (ns) and its ratio to the smallest duration's;
* the peak resident set of ``read()`` above the resident set after the warm-up, per byte of
  decoded float64 samples (issue 21 asks for cost that grows linearly: at most 2x at every
  size, for both figures).

Each file is written, read once and deleted before the next (the 30-minute candump log is
about 3 GB). Writing the 30-minute files takes minutes: run the full set once, develop with
``--minutes 1 10`` or less.

Run: ``python tests/benchmarks/bench_ingest_scaling.py [--minutes 1 10 30]
[--formats blf candump mcap]``, or ``python -m pytest tests/benchmarks/bench_ingest_scaling.py
-m benchmark -s``. Times depend on the machine and its load; the script prints ratios, it does
not assert them.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from collections.abc import Callable
from pathlib import Path

import pytest
from bench_memory import FS, N_CH, read_in_child, write_files

FORMATS = {"blf": "blf", "candump": "log", "mcap": "mcap"}


def run(minutes: list[float], formats: list[str],
        out: Callable[[str], object] = print) -> list[dict[str, float]]:
    """Measure every (format, duration); print one line each; return the figures."""
    out(f"{N_CH} channels at {FS:g} Hz, reference layout; read() in a fresh process")
    out(f"{'format':<9}{'minutes':>8}{'file MB':>10}{'samples':>14}{'read s':>9}"
        f"{'ns/sample':>11}{'x first':>9}{'peak-base MB':>14}{'RSS/byte':>10}{'x first':>9}")
    rows = []
    for fmt in formats:
        first: dict[str, float] | None = None
        for m in minutes:
            with tempfile.TemporaryDirectory() as tmp:
                big = write_files(Path(tmp), m * 60.0, FORMATS[fmt])
                r = read_in_child(Path(tmp) / f"small.{FORMATS[fmt]}", big)
            r["format"], r["minutes"] = fmt, m  # type: ignore[assignment]
            r["ns_per_sample"] = r["read_s"] / r["n_samples"] * 1e9
            first = first or r
            growth_t = r["ns_per_sample"] / first["ns_per_sample"]
            growth_m = r["ratio"] / first["ratio"] if first["ratio"] > 0 else float("nan")
            flag = "ok" if growth_t <= 2 and growth_m <= 2 and r["ratio"] <= 2 else "ABOVE 2x"
            out(f"{fmt:<9}{m:>8g}{r['file_bytes'] / 1e6:>10.1f}{r['n_samples']:>14,}"
                f"{r['read_s']:>9.2f}{r['ns_per_sample']:>11.1f}{growth_t:>8.2f}x"
                f"{(r['peak'] - r['base']) / 1e6:>14.1f}{r['ratio']:>10.2f}{growth_m:>8.2f}x"
                f"  {flag}")
            rows.append(r)
    return rows


@pytest.mark.benchmark
def test_bench_ingest_scaling(capsys):
    """The full benchmark (excluded from the default run by the ``benchmark`` marker)."""
    with capsys.disabled():
        rows = run([1.0, 10.0, 30.0], list(FORMATS))
    assert all(r["n_samples"] > 0 for r in rows)


def main(argv: list[str] | None = None) -> int:
    """Command-line entry point."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--minutes", type=float, nargs="+", default=[1.0, 10.0, 30.0])
    ap.add_argument("--formats", nargs="+", default=list(FORMATS), choices=list(FORMATS))
    args = ap.parse_args(argv)
    run(args.minutes, args.formats)
    return 0


if __name__ == "__main__":
    sys.exit(main())

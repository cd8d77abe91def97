"""Throughput of CAN ingest against python-can and cantools.

A 60 s, 4-channel, 25.6 kHz reference-layout recording (2 048 000 accelerometer frames plus
1 800 slow frames) is written as BLF and as candump ``-L`` log. For each file this prints

* frames/s of the whole ``rigtools.ingest.read`` (container or text parsing, DBC decoding,
  counter unwrapping, laying the channels on their grid), best of ``--repeat`` runs, and its
  ratio to bare iteration of python-can's own reader over the same file
  (``for m in can.BLFReader(f): pass``), target >= 10x;
* the reader alone (``iter_batches``) for reference;

and, once, the decode stage alone: ``rigtools.ingest.can.assembly.assemble_can`` over prepared
frame batches, and ``rigtools.ingest.can.dbc.decode_signal`` over every signal of every frame,
against cantools' per-frame ``db.decode_message(frame_id, data)`` (timed on the first
``--cantools-frames`` frames and expressed per frame), target >= 20x.

Run: ``python tests/benchmarks/bench_can.py [--seconds 60] [--repeat 3]``, or through pytest:
``python -m pytest tests/benchmarks/bench_can.py -m benchmark -s``. Timings depend on the
machine and its load; the script reports ratios, it does not assert them.
"""

from __future__ import annotations

import argparse
import gc
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest

FS = 25_600.0
N_CH = 4


def _best(fn: Callable[[], object], repeat: int) -> tuple[float, object]:
    best, out = float("inf"), None
    for _ in range(repeat):
        gc.collect()
        t0 = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t0)
    return best, out


def write_recording(folder: Path, seconds: float) -> tuple[dict[str, Path], int]:
    """Write the reference recording as BLF and candump; return the paths and frame count."""
    from rigtools.demo.can_writer import encode_reference_frames, write_can_log

    n = int(seconds * FS) // 3 * 3
    rng = np.random.default_rng(0)
    t = np.arange(n) / FS
    chans = [40 * np.sin(2 * np.pi * 400 * (i + 1) * t) + rng.normal(0, 5, n)
             for i in range(N_CH)]
    slow = {"Torque_Nm": 302.0, "PinionSpeed_rpm": 1500.0, "OilTemp_C": 90.0}
    frames = encode_reference_frames(chans, slow, rng=1)
    del chans, t
    paths = {
        "blf": write_can_log(folder / "bench.blf", frames, "blf", engine="rigtools"),
        "candump": write_can_log(folder / "bench.log", frames, "log", engine="rigtools"),
    }
    return paths, len(frames)


def bench_reader(path: Path, fmt: str, n_frames: int, repeat: int) -> dict[str, float]:
    """rigtools.ingest.read, the bare rigtools reader and bare python-can iteration."""
    import can

    from rigtools.ingest import read
    from rigtools.ingest.recording import IngestReport
    from rigtools.ingest.registry import CAN_READERS

    rigtools_reader = CAN_READERS[fmt]

    def bare_rigtools() -> int:
        with open(path, "rb") as f:
            return sum(len(b) for b in rigtools_reader.iter_batches(f, str(path), IngestReport()))

    def bare_python_can() -> int:
        reader = can.BLFReader if fmt == "blf" else can.CanutilsLogReader
        k = 0
        for _ in reader(str(path)):
            k += 1
        return k

    read(path)  # warm: imports, DBC parsing caches
    t_read, rec = _best(lambda: read(path), repeat)
    t_bare, n_bare = _best(bare_rigtools, repeat)
    t_pycan, n_pycan = _best(bare_python_can, 1)
    n_samples = sum(len(c) for c in rec.channels.values())  # type: ignore[attr-defined]
    if n_bare != n_frames or n_pycan != n_frames or rec.report.decoded != n_frames:  # type: ignore[attr-defined]
        raise RuntimeError(f"{fmt}: frame counts differ: {n_bare}, {n_pycan}, {n_frames}")
    return {"read_s": t_read, "bare_s": t_bare, "python_can_s": t_pycan, "n_frames": n_frames,
            "n_samples": n_samples, "file_bytes": path.stat().st_size}


def bench_decode(path: Path, repeat: int, cantools_frames: int) -> dict[str, float]:
    """Decode stage alone against cantools' per-frame decode_message."""
    from rigtools.ingest.builder import RecordingBuilder
    from rigtools.ingest.can import blf
    from rigtools.ingest.can.assembly import assemble_can
    from rigtools.ingest.can.dbc import decode_signal, load_dbc
    from rigtools.ingest.can.frames import concat
    from rigtools.ingest.layout import can_layout
    from rigtools.ingest.recording import IngestReport
    from rigtools.schemas import schema_path

    dbc = schema_path("rig_reference.dbc")
    db = load_dbc(dbc)
    layout = can_layout(db, None, str(dbc))
    with open(path, "rb") as f:
        batches = list(blf.iter_batches(f, str(path), IngestReport()))
    n = sum(len(b) for b in batches)

    def assemble() -> None:
        report = IngestReport()
        builder = RecordingBuilder(str(path), report)
        assemble_can(iter(batches), layout, builder, report)

    t_assemble, _ = _best(assemble, repeat)

    whole = concat(batches)
    by_id = {m.frame_id: (whole.data[whole.arbitration_id == m.frame_id], m)
             for m in db.messages}

    def decode_all() -> None:
        for data, message in by_id.values():
            for sig in message.signals:
                decode_signal(data, sig)

    t_signals, _ = _best(decode_all, repeat)

    k = min(cantools_frames, n)
    pairs = [(int(whole.arbitration_id[i]), bytes(whole.data[i, : whole.length[i]]))
             for i in range(k)]
    decode_message = db.decode_message

    def cantools_decode() -> None:
        for frame_id, data in pairs:
            decode_message(frame_id, data)

    t_cantools, _ = _best(cantools_decode, 1)
    return {"n_frames": n, "assemble_s": t_assemble, "signals_s": t_signals,
            "cantools_frames": k, "cantools_s": t_cantools}


def run(seconds: float = 60.0, repeat: int = 3, cantools_frames: int = 200_000,
        out: Callable[[str], object] = print) -> dict[str, dict[str, float]]:
    """Write the recording, run every measurement, print the table, return the figures."""
    figures: dict[str, dict[str, float]] = {}
    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.perf_counter()
        paths, n_frames = write_recording(Path(tmp), seconds)
        out(f"{seconds:g} s, {N_CH} channels at {FS:g} Hz + slow frames: {n_frames} frames "
            f"(written in {time.perf_counter() - t0:.1f} s)")
        out(f"{'format':<9}{'file MB':>9}{'read() s':>10}{'frames/s':>12}{'bare s':>8}"
            f"{'python-can s':>14}{'read/pycan':>12}{'bare/pycan':>12}")
        for fmt, path in paths.items():
            r = bench_reader(path, fmt, n_frames, repeat)
            figures[fmt] = r
            ratio = r["python_can_s"] / r["read_s"]
            flag = "ok" if ratio >= 10 else "below 10x"
            out(f"{fmt:<9}{r['file_bytes'] / 1e6:>9.1f}{r['read_s']:>10.2f}"
                f"{n_frames / r['read_s']:>12,.0f}{r['bare_s']:>8.2f}{r['python_can_s']:>14.2f}"
                f"{ratio:>11.1f}x{r['python_can_s'] / r['bare_s']:>11.1f}x  {flag}")
        d = bench_decode(paths["blf"], repeat, cantools_frames)
        figures["decode"] = d
        per_frame_cantools = d["cantools_s"] / d["cantools_frames"]
        for label, key in (("assemble_can (decode+unwrap)", "assemble_s"),
                           ("decode_signal, all signals", "signals_s")):
            per_frame = d[key] / d["n_frames"]
            ratio = per_frame_cantools / per_frame
            out(f"{label:<30}{d['n_frames'] / d[key]:>14,.0f} frames/s   cantools "
                f"decode_message {1 / per_frame_cantools:>10,.0f} frames/s "
                f"(on {d['cantools_frames']} frames)   ratio {ratio:6.1f}x  "
                f"{'ok' if ratio >= 20 else 'below 20x'}")
    return figures


@pytest.mark.benchmark
def test_bench_can(capsys):
    """The full benchmark (excluded from the default run by the ``benchmark`` marker)."""
    with capsys.disabled():
        figures = run()
    assert figures["blf"]["n_frames"] == figures["candump"]["n_frames"] > 2_000_000


def main(argv: list[str] | None = None) -> int:
    """Command-line entry point."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seconds", type=float, default=60.0)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--cantools-frames", type=int, default=200_000)
    args = ap.parse_args(argv)
    run(args.seconds, args.repeat, args.cantools_frames)
    return 0


if __name__ == "__main__":
    sys.exit(main())

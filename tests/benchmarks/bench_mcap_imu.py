"""Benchmark: a per-sample ROS 2 Imu stream through the MCAP fast path (issue 11).

Writes one file: 60 s of a 25.6 kHz, 3-axis ``sensor_msgs/msg/Imu`` stream, one message per
sample (1 536 000 messages, frame id ``imu_link``, CDR little-endian, zstd chunks of 1 MiB),
with three ``std_msgs/msg/Float64`` topics at 10 Hz interleaved. On that file, in one run, it
prints:

* ``read``: ``rigtools.ingest.read`` (everything: SHA-256 of the file, container, decoding,
  time base, the builder's grid and masks, provenance);
* ``ingest``: the same without hashing and building (container and decoding);
* ``mcap bare``: ``make_reader(f).iter_messages()`` with no decoding, and the ratio
  ``mcap bare / read`` (issue 11's target >= 10; issue 21's, with margin on a busy
  machine, >= 15);
* ``rigtools general``: rigtools' reader with the CDR fast path switched off (every message
  decoded on its own, as before issue 11);
* ``mcap + mcap_ros2``: ``iter_decoded_messages`` with ``mcap-ros2-support``'s decoder, the
  general path of the issue;
* ``decompress only``: zstd decompression of every chunk, the ceiling for any reader, and
  the distance to it (read time over decompression time);
* peak memory: each of a library call and the command line's set-up
  (``rigtools.cli.tune_allocator``) reads the file in a fresh child process after a 1 s file
  of the same kind; the high-water resident set above that baseline is printed against the
  decoded arrays (3 channels x n float64).

A second, smaller file (10 s of two Imu topics whose frame ids differ in length, taking turns
message by message: records of two lengths alternating, which the chunk walk reads as a
repeating pattern) is read against mcap's bare iteration too.

Times of the fast contenders are the best of :data:`REPEATS`, taken in alternating rounds (the
machine may be shared); the slow ones (mcap's iteration, the general paths) run once. Each
target of the issue is printed as "met" or "NOT met"; no wall-clock figure is asserted (the
machine is shared), but the peak-memory ratio, which does not depend on the machine's load,
is: at most :data:`MEMORY_TARGET` times the decoded arrays, for the library call and the
command line's set-up alike.

Run it as a script (``python tests/benchmarks/bench_mcap_imu.py``) or with pytest
(``pytest tests/benchmarks/bench_mcap_imu.py -m benchmark -s``); the default run skips it.
"""

from __future__ import annotations

import dataclasses
import json
import subprocess
import sys
import tempfile
import textwrap
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest

pytestmark = pytest.mark.benchmark

DURATION_S = 60.0
FS = 25_600.0
T0_NS = 1_700_000_000_000_000_000
SLOW_TOPICS = ("/rig/temperature", "/rig/speed", "/rig/torque")
SLOW_RATE_HZ = 10.0
REPEATS = 3
#: Targets of issues 11 and 21: read at least this many times faster than mcap's bare
#: iteration (issue 11 asked 10x; issue 21 asks 15x, a margin on a busy machine), and peak
#: resident memory above the baseline at most this many times the decoded arrays.
SPEED_TARGET = 15.0
MEMORY_TARGET = 2.0


def _met(ok: bool) -> str:
    return "met" if ok else "NOT met"


def write_recording(path: Path, seconds: float = DURATION_S) -> Path:
    """The benchmark file: the Imu stream and the slow Float64 topics."""
    from rigtools.demo.mcap_writer import write_imu_cdr_mcap

    n = int(seconds * FS)
    stamps = T0_NS + np.round(np.arange(n) * (1e9 / FS)).astype(np.int64)
    rng = np.random.default_rng(11)
    t = np.arange(n) / FS
    acc = np.stack(
        [np.sin(2 * np.pi * 50.0 * t), np.cos(2 * np.pi * 120.0 * t), 9.81 + 0 * t], axis=1
    ) + 0.05 * rng.standard_normal((n, 3))
    ts = np.arange(0.0, seconds, 1.0 / SLOW_RATE_HZ) + T0_NS * 1e-9
    scalars = {name: (ts, rng.standard_normal(ts.size)) for name in SLOW_TOPICS}
    return write_imu_cdr_mcap(
        path, stamps, acc, scalars=scalars, compression="zstd", chunk_size=1 << 20
    )


def _best(fn: Callable[[], object]) -> float:
    t = time.perf_counter()
    fn()
    return time.perf_counter() - t


_CHILD = textwrap.dedent(
    """
    import json, sys
    from rigtools.ingest import read

    def status(key):
        for line in open("/proc/self/status"):
            if line.startswith(key):
                return int(line.split()[1]) * 1024
        return 0

    small, big, mode = sys.argv[1], sys.argv[2], sys.argv[3]
    if mode == "cli":
        from rigtools.cli import tune_allocator
        tune_allocator()
    read(small)
    base = status("VmRSS:")
    rec = read(big)
    peak = status("VmHWM:")
    n = sum(len(c) for c in rec.channels.values() if c.name.startswith("/imu/"))
    print(json.dumps({"base": base, "peak": peak, "n_samples": n}))
    """
)


def peak_memory(small: Path, big: Path, mode: str) -> dict[str, float]:
    """High-water resident set of reading ``big`` in a fresh process, above the baseline."""
    out = subprocess.run(
        [sys.executable, "-c", _CHILD, str(small), str(big), mode],
        check=True,
        capture_output=True,
        text=True,
    ).stdout
    got = json.loads(out.strip().splitlines()[-1])
    return {
        "peak_above_base": float(got["peak"] - got["base"]),
        "decoded_bytes": 8.0 * got["n_samples"],
    }


def measure(path: Path, small: Path) -> dict[str, float]:
    """Times (s), counts and memory for the benchmark file."""
    import zstandard
    from mcap.reader import make_reader
    from mcap.records import Chunk
    from mcap.stream_reader import StreamReader
    from mcap_ros2.decoder import DecoderFactory

    from rigtools.ingest import read
    from rigtools.ingest.builder import RecordingBuilder
    from rigtools.ingest.mcap import decoders as mcap_decoders
    from rigtools.ingest.mcap import ingest
    from rigtools.ingest.recording import IngestReport

    n_imu = int(DURATION_S * FS)
    rec = read(path)
    got = sum(len(c) for c in rec.channels.values())
    if got != 3 * n_imu or rec.report.has_losses or len(rec.slow) != len(SLOW_TOPICS):
        raise RuntimeError(f"benchmark file read wrong: {got} samples, {rec.report.to_dict()}")

    def ingest_only() -> int:
        rep = IngestReport("messages")
        with open(path, "rb") as f:
            ingest(f, str(path), RecordingBuilder(str(path), rep), rep, None)
        return rep.decoded

    def bare() -> int:
        with open(path, "rb") as f:
            return sum(1 for _ in make_reader(f).iter_messages())

    def ros2_decoded() -> int:
        with open(path, "rb") as f:
            return sum(
                1
                for _ in make_reader(
                    f, decoder_factories=[DecoderFactory()]
                ).iter_decoded_messages()
            )

    def general() -> None:
        orig = mcap_decoders._decoder_for

        def plain(enc: str, schema: Any, generic: bool) -> Any:
            dec = orig(enc, schema, generic)
            if dec is not None and dec.kind in ("imu", "scalar", "generic"):
                return dataclasses.replace(dec, decode_many=None)
            return dec

        mcap_decoders._decoder_for = plain  # type: ignore[assignment]
        try:
            general_rec = read(path)
        finally:
            mcap_decoders._decoder_for = orig
        for name, ch in rec.channels.items():  # the fast path changed nothing
            if not ch.equals(general_rec.channels[name]):
                raise RuntimeError(f"fast and general paths differ on {name}")

    with open(path, "rb") as f:
        chunks = [
            (r.data, r.uncompressed_size)
            for r in StreamReader(f, emit_chunks=True).records
            if isinstance(r, Chunk)
        ]
    dec = zstandard.ZstdDecompressor()
    uncompressed = sum(u for _d, u in chunks)

    def decompress() -> int:
        return sum(len(dec.decompress(d, max_output_size=u)) for d, u in chunks)

    fast = {"read_s": lambda: read(path), "ingest_s": ingest_only, "decompress_s": decompress}
    best = dict.fromkeys(fast, float("inf"))
    for _ in range(REPEATS):
        for key, fn in fast.items():
            best[key] = min(best[key], _best(fn))
    out: dict[str, float] = dict(best)
    out["mcap_bare_s"] = _best(bare)
    out["general_s"] = _best(general)
    out["mcap_ros2_s"] = _best(ros2_decoded)
    out["messages"] = float(bare())
    out["imu_messages"] = float(n_imu)
    out["uncompressed_bytes"] = float(uncompressed)
    out["file_bytes"] = float(path.stat().st_size)
    out["n_chunks"] = float(len(chunks))
    for mode in ("library", "cli"):
        mem = peak_memory(small, path, mode)
        out[f"peak_{mode}_bytes"] = mem["peak_above_base"]
        out["decoded_bytes"] = mem["decoded_bytes"]
    return out


def report(m: dict[str, float]) -> str:
    """Human-readable lines."""
    mb = m["uncompressed_bytes"] / 1e6
    n = m["messages"]

    def line(label: str, s: float) -> str:
        return f"  {label:<30} {s:9.3f} s  {n / s / 1e6:7.2f} M messages/s"

    dec_mb = m["decoded_bytes"] / 1e6
    speed = m["mcap_bare_s"] / m["read_s"]
    mem = max(m["peak_library_bytes"], m["peak_cli_bytes"]) / m["decoded_bytes"]
    return "\n".join(
        [
            f"Imu stream: {m['file_bytes'] / 1e6:.1f} MB file, {mb:.1f} MB uncompressed in "
            f"{int(m['n_chunks'])} zstd chunks, {int(n)} messages ({int(m['imu_messages'])} Imu)",
            line("rigtools.ingest.read", m["read_s"]),
            line("ingest (no hash, no build)", m["ingest_s"]),
            line("mcap bare iter_messages", m["mcap_bare_s"]),
            line("rigtools general path", m["general_s"]),
            line("mcap + mcap_ros2 decoding", m["mcap_ros2_s"]),
            line("decompress only (ceiling)", m["decompress_s"]),
            f"  ratio mcap bare / read          {speed:8.1f}   "
            f"(target >= {SPEED_TARGET:g}: {_met(speed >= SPEED_TARGET)})",
            f"  ratio mcap bare / ingest        {m['mcap_bare_s'] / m['ingest_s']:8.1f}",
            f"  ratio rigtools general / read   {m['general_s'] / m['read_s']:8.1f}",
            f"  ratio mcap_ros2 / read          {m['mcap_ros2_s'] / m['read_s']:8.1f}",
            f"  read / decompress only          {m['read_s'] / m['decompress_s']:8.1f}   "
            "(distance to the ceiling; goal beyond issue 21: <= 2)",
            f"  peak RSS above baseline: library {m['peak_library_bytes'] / 1e6:.1f} MB, "
            f"cli {m['peak_cli_bytes'] / 1e6:.1f} MB; decoded arrays {dec_mb:.1f} MB "
            f"(ratio {m['peak_library_bytes'] / m['decoded_bytes']:.2f} / "
            f"{m['peak_cli_bytes'] / m['decoded_bytes']:.2f}; target <= {MEMORY_TARGET:g}: "
            f"{_met(mem <= MEMORY_TARGET)})",
        ]
    )


TURNS_SECONDS = 10.0


def write_turns(path: Path, seconds: float = TURNS_SECONDS) -> Path:
    """Two Imu topics (frame ids of different lengths) taking turns, message by message."""
    from mcap.writer import CompressionType, Writer

    from rigtools.demo.mcap_writer import imu_cdr_payloads
    from rigtools.ingest.mcap.decoders import IMU_SCHEMA_TEXT

    n = int(seconds * FS)
    stamps = T0_NS + np.round(np.arange(n) * (1e9 / FS)).astype(np.int64)
    acc = np.random.default_rng(12).standard_normal((n, 3))
    rows = [imu_cdr_payloads(stamps, acc, frame_id=f) for f in ("imu_a", "imu_link_b_long")]
    with open(path, "wb") as f:
        w = Writer(f, chunk_size=1 << 20, compression=CompressionType.ZSTD)
        w.start(profile="ros2", library="bench")
        sid = w.register_schema("sensor_msgs/msg/Imu", "ros2msg", IMU_SCHEMA_TEXT.encode())
        cids = [w.register_channel(t, "cdr", sid) for t in ("/imu_a", "/imu_b")]
        data = [r.tobytes() for r in rows]
        size = [r.shape[1] for r in rows]
        for i, t in enumerate(stamps.tolist()):
            for c, d, z in zip(cids, data, size, strict=True):
                w.add_message(
                    c, log_time=t, data=d[i * z : (i + 1) * z], publish_time=t, sequence=i
                )
        w.finish()
    return path


def measure_turns(path: Path) -> dict[str, float]:
    """Read time against mcap's bare iteration on the file of channels taking turns."""
    from mcap.reader import make_reader

    from rigtools.ingest import read

    def bare() -> int:
        with open(path, "rb") as f:
            return sum(1 for _ in make_reader(f).iter_messages())

    rec = read(path)
    if sum(len(c) for c in rec.channels.values()) != 6 * int(TURNS_SECONDS * FS):
        raise RuntimeError(f"turns file read wrong: {rec.report.to_dict()}")
    best = min(_best(lambda: read(path)) for _ in range(REPEATS))
    return {"read_s": best, "mcap_bare_s": _best(bare), "messages": float(bare())}


def run(directory: Path) -> dict[str, float]:
    """Write the files in ``directory``, measure and print."""
    t = time.perf_counter()
    path = write_recording(directory / "imu_stream.mcap")
    small = write_recording(directory / "imu_small.mcap", 1.0)
    print(f"(files written in {time.perf_counter() - t:.1f} s)", flush=True)
    m = measure(path, small)
    print(report(m), flush=True)
    turns = measure_turns(write_turns(directory / "imu_turns.mcap"))
    print(
        f"Two Imu topics taking turns (frame ids of different lengths), "
        f"{int(turns['messages'])} messages:\n"
        f"  rigtools.ingest.read {turns['read_s']:.3f} s, mcap bare iter_messages "
        f"{turns['mcap_bare_s']:.3f} s, ratio {turns['mcap_bare_s'] / turns['read_s']:.1f}",
        flush=True,
    )
    return m


def test_bench_mcap_imu(tmp_path):
    m = run(tmp_path)
    # not a wall-clock figure: the high-water resident set against the decoded arrays
    for mode in ("library", "cli"):
        ratio = m[f"peak_{mode}_bytes"] / m["decoded_bytes"]
        assert ratio <= MEMORY_TARGET, f"peak memory ({mode}) {ratio:.2f} x the decoded arrays"


if __name__ == "__main__":
    with tempfile.TemporaryDirectory() as d:
        run(Path(d))
    sys.exit(0)

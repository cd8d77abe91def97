"""Throughput of CAN ingest against python-can and cantools, reference and mapped layouts.

Two recordings, each written by the benchmark itself:

* the **reference layout** (``data_schemas/rig_reference.dbc``): ``--seconds`` (default 60) of
  4 channels at 25.6 kHz, 3 samples a frame (2 048 000 accelerometer frames plus slow
  frames), written as BLF and candump ``-L`` log by rigtools' vectorised writers;
* a **mapped layout** (a DBC and a mapping file written next to it): ``--mapped-seconds``
  (default 10) of one accelerometer message per sample at 25.6 kHz, a 16-bit counter and three
  int16 axes in one message (one message feeding three channels), a slow message at 10 Hz,
  3 % frames with identifiers the DBC does not know, and 0.1 % each error and remote frames
  mixed in (about 264 000 frames), written as BLF, candump and ASC by python-can's writers.

For each file it prints the time of the whole ``rigtools.ingest.read`` (container or text
parsing, DBC decoding, counter unwrapping, the channels on their grid, the SHA-256) against
bare iteration of python-can's own reader over the same file (``for m in
can.BLFReader(f): pass``), best of ``--repeat`` rounds that alternate between the two (a
burst of load on a shared machine hits both alike), and their ratio next to the goal of
issue 21 (reference: BLF and candump >= 10x; mapped: BLF >= 12x, candump >= 10x, ASC >= 10x).
The rigtools reader alone (``iter_batches``, no decoding) is printed for reference.

Once, the decode stage alone: ``rigtools.ingest.can.assembly.assemble_can`` over prepared
frame batches, and ``rigtools.ingest.can.dbc.decode_signal`` over every signal of every frame,
against cantools' per-frame ``db.decode_message(frame_id, data)`` (timed on the first
``--cantools-frames`` frames and expressed per frame), target >= 20x.

Run: ``python tests/benchmarks/bench_can.py [--seconds 60] [--mapped-seconds 10] [--repeat 3]
[--only mapped|reference]``, or through pytest:
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
    """Best time (s) of ``repeat`` calls, and the last result."""
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


def interleaved(fns: dict[str, Callable[[], object]], repeat: int) -> dict[str, float]:
    """Best time (s) of each function over ``repeat`` rounds that run them in turn."""
    best = dict.fromkeys(fns, float("inf"))
    for _ in range(repeat):
        for key, fn in fns.items():
            gc.collect()
            t0 = time.perf_counter()
            fn()
            best[key] = min(best[key], time.perf_counter() - t0)
    return best


def python_can_reader(fmt: str) -> Callable[[str], object]:
    """python-can's reader class for a format name of the registry."""
    import can

    return {"blf": can.BLFReader, "candump": can.CanutilsLogReader, "asc": can.ASCReader}[fmt]


def bench_reader(path: Path, fmt: str, n_frames: int, repeat: int, *,
                 dbc: Path | None = None, mapping: Path | None = None,
                 n_pycan: int | None = None) -> dict[str, float]:
    """rigtools.ingest.read, the bare rigtools reader and bare python-can iteration.

    ``n_frames`` data frames are expected from the file (``n_pycan`` messages from
    python-can, error and remote frames included; default ``n_frames``).
    """
    from rigtools.ingest import read
    from rigtools.ingest.recording import IngestReport
    from rigtools.ingest.registry import CAN_READERS

    rigtools_reader = CAN_READERS[fmt]
    reader = python_can_reader(fmt)

    def read_file() -> object:
        return read(path, dbc=dbc, mapping=mapping)

    def bare_rigtools() -> int:
        with open(path, "rb") as f:
            return sum(len(b) for b in rigtools_reader.iter_batches(f, str(path), IngestReport()))

    def bare_python_can() -> int:
        k = 0
        for _ in reader(str(path)):  # type: ignore[operator]
            k += 1
        return k

    rec = read_file()  # warm: imports, DBC parsing caches
    n_bare = bare_rigtools()
    n_msgs = bare_python_can()
    best = interleaved({"read_s": read_file, "bare_s": bare_rigtools,
                        "python_can_s": bare_python_can}, repeat)
    n_samples = sum(len(c) for c in rec.channels.values())  # type: ignore[attr-defined]
    if n_bare != n_frames or n_msgs != (n_pycan or n_frames):
        raise RuntimeError(f"{fmt}: frame counts differ: {n_bare}, {n_msgs}, {n_frames}")
    return {**best, "n_frames": n_frames, "n_samples": n_samples,
            "decoded": rec.report.decoded,  # type: ignore[attr-defined]
            "file_bytes": path.stat().st_size}


# -- the mapped layout --------------------------------------------------------------------------

#: Share of frames with identifiers the DBC does not know, and of error and of remote frames.
UNKNOWN_SHARE = 0.03
ERROR_SHARE = 0.001


def mapped_messages(seconds: float, rng: int = 0) -> tuple[list[object], int]:
    """python-can messages of the mapped layout, in time order; and the data frames among them.

    One ``IMU`` frame per sample at 25.6 kHz (16-bit counter, three int16 axes), a ``Rig``
    frame at 10 Hz (4 bytes), 3 % frames of 16 identifiers the DBC does not know, 0.1 % error
    frames and 0.1 % remote frames.
    """
    import can

    gen = np.random.default_rng(rng)
    n = int(seconds * FS)
    t0 = 1_700_000_000.0
    t = t0 + np.arange(n) / FS + 250e-6 + gen.uniform(0, 20e-6, n)
    payload = np.empty((n, 8), np.uint8)
    payload[:, :2] = (np.arange(n) % 65536).astype("<u2").view(np.uint8).reshape(n, 2)
    axes = np.round(gen.normal(0, 3000, (n, 3))).astype("<i2")
    payload[:, 2:] = axes.view(np.uint8).reshape(n, 6)
    n_slow = max(1, int(seconds * 10))
    slow = np.zeros((n_slow, 8), np.uint8)
    slow[:, :2] = np.full(n_slow, 13000, "<u2").view(np.uint8).reshape(n_slow, 2)
    slow[:, 2:4] = np.full(n_slow, 3000, "<u2").view(np.uint8).reshape(n_slow, 2)
    n_unknown = int(UNKNOWN_SHARE * n)
    n_err = max(1, int(ERROR_SHARE * n))
    kinds = np.r_[np.zeros(n + n_slow + n_unknown, np.int8), np.ones(n_err, np.int8),
                  np.full(n_err, 2, np.int8)]
    stamps = np.r_[t, t0 + np.arange(n_slow) / 10 + 1e-4,
                   t0 + gen.uniform(0, seconds, n_unknown + 2 * n_err)]
    ids = np.r_[np.full(n, 0x120), np.full(n_slow, 0x300),
                gen.integers(0x400, 0x410, n_unknown), np.zeros(n_err, np.int64),
                np.full(n_err, 0x200)]
    lengths = np.r_[np.full(n, 8), np.full(n_slow, 4), np.full(n_unknown, 8),
                    np.zeros(2 * n_err, np.int64)]
    data = np.concatenate([payload, slow, gen.integers(0, 256, (n_unknown, 8), np.uint8),
                           np.zeros((2 * n_err, 8), np.uint8)])
    order = np.argsort(stamps, kind="stable")
    out: list[object] = []
    for i in order.tolist():
        k = int(kinds[i])
        ts = float(stamps[i])
        if k == 1:
            out.append(can.Message(timestamp=ts, is_error_frame=True, channel=0, dlc=0))
        elif k == 2:
            out.append(can.Message(timestamp=ts, arbitration_id=int(ids[i]), is_extended_id=False,
                                   is_remote_frame=True, dlc=8, channel=0))
        else:
            d = int(lengths[i])
            out.append(can.Message(timestamp=ts, arbitration_id=int(ids[i]), is_extended_id=False,
                                   dlc=d, data=data[i, :d].tobytes(), channel=0))
    return out, n + n_slow + n_unknown


def write_mapped_recording(folder: Path, seconds: float) -> tuple[dict[str, Path], Path, Path,
                                                                   int, int]:
    """Write the mapped layout as BLF, candump and ASC (python-can's writers) with its files.

    Returns the paths by format, the DBC, the mapping file, the number of data frames and
    the number of all frames (error and remote frames included).
    """
    import can
    from imu_can_layout import OIL_TEMP_SIGNAL, imu_dbc, imu_mapping

    dbc = folder / "mapped.dbc"
    dbc.write_text(imu_dbc(slow_signals=(
        OIL_TEMP_SIGNAL, ' SG_ Speed : 16|16@1+ (0.5,0) [0|32767.5] "rpm" Logger')))
    mapping = folder / "mapped.toml"
    mapping.write_text(imu_mapping({axis: f"accel_{axis.lower()}" for axis in "XYZ"},
                                   sample_rate_Hz=FS, slow=[("oil_temp", "Rig", "OilTemp"),
                                                            ("speed", "Rig", "Speed")]))
    messages, n_data = mapped_messages(seconds)
    paths = {"blf": folder / "mapped.blf", "candump": folder / "mapped.log",
             "asc": folder / "mapped.asc"}
    writers = {"blf": can.BLFWriter, "candump": can.CanutilsLogWriter, "asc": can.ASCWriter}
    for fmt, path in paths.items():
        with writers[fmt](str(path)) as w:
            for m in messages:
                w.on_message_received(m)
    return paths, dbc, mapping, n_data, len(messages)


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


#: Goal of issue 21 for read() / python-can, by layout and format.
GOALS = {("reference", "blf"): 10.0, ("reference", "candump"): 10.0,
         ("mapped", "blf"): 12.0, ("mapped", "candump"): 10.0, ("mapped", "asc"): 10.0}


def _row(layout: str, fmt: str, r: dict[str, float], out: Callable[[str], object]) -> None:
    ratio = r["python_can_s"] / r["read_s"]
    goal = GOALS[(layout, fmt)]
    flag = "ok" if ratio >= goal else f"below {goal:g}x"
    out(f"{layout:<10}{fmt:<9}{r['file_bytes'] / 1e6:>9.1f}{r['n_frames']:>10,}"
        f"{r['read_s']:>10.3f}{r['bare_s']:>8.3f}{r['python_can_s']:>14.3f}"
        f"{ratio:>11.1f}x{r['python_can_s'] / r['bare_s']:>11.1f}x  goal {goal:g}x {flag}")


def _header(out: Callable[[str], object]) -> None:
    out(f"{'layout':<10}{'format':<9}{'file MB':>9}{'frames':>10}{'read() s':>10}{'bare s':>8}"
        f"{'python-can s':>14}{'read/pycan':>12}{'bare/pycan':>12}")


def run(seconds: float = 60.0, repeat: int = 3, cantools_frames: int = 200_000,
        out: Callable[[str], object] = print, mapped_seconds: float = 10.0,
        only: str | None = None) -> dict[str, dict[str, float]]:
    """Write the recordings, run every measurement, print the table, return the figures."""
    figures: dict[str, dict[str, float]] = {}
    with tempfile.TemporaryDirectory() as tmp:
        if only in (None, "mapped"):
            t0 = time.perf_counter()
            paths, dbc, mapping, n_data, n_all = write_mapped_recording(Path(tmp),
                                                                        mapped_seconds)
            out(f"mapped layout: {mapped_seconds:g} s, one IMU frame per sample at {FS:g} Hz "
                f"(3 channels), 3 % unknown ids, error and remote frames: {n_all} frames, "
                f"{n_data} data frames (written in {time.perf_counter() - t0:.1f} s)")
            _header(out)
            for fmt, path in paths.items():
                r = bench_reader(path, fmt, n_data, repeat, dbc=dbc, mapping=mapping,
                                 n_pycan=n_all)
                figures[f"mapped_{fmt}"] = r
                _row("mapped", fmt, r, out)
        if only in (None, "reference"):
            t0 = time.perf_counter()
            ref_paths, n_frames = write_recording(Path(tmp), seconds)
            out(f"reference layout: {seconds:g} s, {N_CH} channels at {FS:g} Hz + slow frames: "
                f"{n_frames} frames (written in {time.perf_counter() - t0:.1f} s)")
            _header(out)
            for fmt, path in ref_paths.items():
                r = bench_reader(path, fmt, n_frames, repeat)
                figures[fmt] = r
                _row("reference", fmt, r, out)
            d = bench_decode(ref_paths["blf"], repeat, cantools_frames)
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
    assert figures["mapped_asc"]["decoded"] == figures["mapped_blf"]["decoded"] > 250_000


def main(argv: list[str] | None = None) -> int:
    """Command-line entry point."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seconds", type=float, default=60.0)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--cantools-frames", type=int, default=200_000)
    ap.add_argument("--mapped-seconds", type=float, default=10.0)
    ap.add_argument("--only", choices=["mapped", "reference"], default=None)
    args = ap.parse_args(argv)
    run(args.seconds, args.repeat, args.cantools_frames, mapped_seconds=args.mapped_seconds,
        only=args.only)
    return 0


if __name__ == "__main__":
    # as a script: tests/ (shared test helpers: imu_can_layout) on the path, as under pytest
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
    sys.exit(main())

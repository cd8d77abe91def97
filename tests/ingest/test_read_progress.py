"""``read(..., progress=...)``: how far a long file is read, for the progress bars.

The callback gets ``(bytes_read, file_bytes)``, never more than the file, never going back,
and ``(size, size)`` at the end, for every way a file is read: MCAP at positions (``os.pread``,
the container's own position is reported), a CAN log read as a stream, a gzip file (the
compressed offset) and a normalized Parquet recording (once, at the end). The CLI shows a tqdm
bar for files from ``PROGRESS_MIN_BYTES`` on when stderr is a terminal.
"""

from __future__ import annotations

import gzip
import io
import os
import shutil
import sys
import threading
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest

import rigtools.cli.common as common
import rigtools.ingest.files as files_mod
import rigtools.ingest.stream_reader as stream_reader
from rigtools.cli import main
from rigtools.demo.can_writer import encode_reference_frames, write_can_log
from rigtools.demo.mcap_writer import write_accel_mcap
from rigtools.ingest import read, write_parquet

FS = 25_600.0


@pytest.fixture(scope="module")
def files(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    d = tmp_path_factory.mktemp("progress")
    rng = np.random.default_rng(3)
    n = int(4 * FS)
    chans = {f"accel_{i}": (np.round(rng.normal(0, 100, n)) * 0.015, FS, "m/s^2", 0, 1.7e9)
             for i in range(1, 3)}
    out = {"mcap": write_accel_mcap(d / "run.mcap", chans, None, None)}
    can = [np.round(rng.normal(0, 100, 3 * 4000)) * 0.015 for _ in range(4)]
    frames = encode_reference_frames(can, {"Torque_Nm": 302.0, "PinionSpeed_rpm": 1500.0},
                                     rng=2)
    out["blf"] = write_can_log(d / "run.blf", frames, "blf")
    out["log"] = write_can_log(d / "run.log", frames, "log")
    with open(out["log"], "rb") as src, gzip.open(d / "run.log.gz", "wb") as dst:
        shutil.copyfileobj(src, dst)
    out["gz"] = d / "run.log.gz"
    out["parquet"] = write_parquet(read(out["mcap"]), d / "run.parquet")
    return out


def _paced(fn: Callable[..., object], reported: threading.Event) -> Callable[..., object]:
    """``fn`` that, from its second call on, first waits for a progress report.

    The progress thread polls; a reader that finishes a small file between two polls (a busy
    machine, a single MCAP chunk) would show no report from inside the read. Pacing the
    reader's own reads by the reports makes that deterministic without a longer file.
    """
    calls = 0

    def paced(*args: object) -> object:
        nonlocal calls
        if calls:
            reported.clear()
            reported.wait(10.0)
        calls += 1
        return fn(*args)
    return paced


@pytest.mark.parametrize("kind", ["mcap", "blf", "log", "gz", "parquet"])
def test_progress_rises_to_the_file_size(files: dict[str, Path], kind: str,
                                         monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(stream_reader, "PROGRESS_INTERVAL_S", 0.0005)
    reported = threading.Event()
    if kind == "mcap":   # read at positions (os.pread), by the reader and its chunk worker
        monkeypatch.setattr(os, "pread", _paced(os.pread, reported))
    elif kind == "gz":
        monkeypatch.setattr(files_mod._GuardedGzip, "readinto",
                            _paced(files_mod._GuardedGzip.readinto, reported))
    seen: list[tuple[int, int]] = []

    def progress(done: int, total: int) -> None:
        seen.append((done, total))
        reported.set()
    rec = read(files[kind], progress=progress)
    size = files[kind].stat().st_size
    assert rec.channels
    assert seen[-1] == (size, size)
    assert all(total == size and 0 <= done <= size for done, total in seen)
    done = [d for d, _ in seen]
    assert done == sorted(done), "progress never goes back"
    if kind in ("mcap", "gz"):    # read piece by piece (candump: a few big blocks)
        assert any(0 < d < size for d in done), seen[:5]


def test_same_recording_with_and_without_progress(files: dict[str, Path]) -> None:
    a, b = read(files["mcap"]), read(files["mcap"], progress=lambda d, t: None)
    for name, ch in a.channels.items():
        np.testing.assert_array_equal(ch.values, b.channels[name].values)


class _Terminal(io.StringIO):
    def isatty(self) -> bool:
        return True


def test_the_cli_shows_a_bar_for_a_long_file_on_a_terminal(
        files: dict[str, Path], tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    term = _Terminal()
    monkeypatch.setattr(sys, "stderr", term)
    monkeypatch.setattr(common, "PROGRESS_MIN_BYTES", 1)
    assert main(["ingest", str(files["mcap"]), "-o", str(tmp_path / "o.parquet")]) == 0
    assert "reading run.mcap" in term.getvalue()
    quiet = io.StringIO()                              # not a terminal: no bar
    monkeypatch.setattr(sys, "stderr", quiet)
    assert main(["ingest", str(files["mcap"]), "-o", str(tmp_path / "p.parquet")]) == 0
    assert "reading" not in quiet.getvalue()

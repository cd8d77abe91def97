"""The SHA-256 of the provenance, computed as the file is read (rigtools.ingest.files)."""

from __future__ import annotations

import gzip
import hashlib
import io
import itertools
import threading
from pathlib import Path

import numpy as np
import pytest

from rigtools.demo.mcap_writer import write_accel_mcap
from rigtools.ingest import files, read
from rigtools.ingest.files import HashingFile, open_source, source_sha256


def _digest(path: Path) -> tuple[str, int]:
    data = path.read_bytes()
    return hashlib.sha256(data).hexdigest(), len(data)


def test_hashing_file_in_order_out_of_order_and_unread(tmp_path: Path) -> None:
    """Reads in order are hashed; seeks, reads at positions and the unread rest are not lost."""
    path = tmp_path / "bytes.bin"
    path.write_bytes(np.random.default_rng(0).integers(0, 256, 300_000, np.uint8).tobytes())
    with HashingFile(path) as f:
        assert f.sha256() == _digest(path)  # nothing read: all hashed at the end
        f.read(1000)
        f.seek(50_000)
        f.read(10)  # out of order: read, not hashed
        f.seek(1000)
        buf = bytearray(70_000)
        f.readinto(buf)
        assert f.sha256() == _digest(path)
        f.seek(0)
        f.read(5)  # again from the start: nothing new
        assert f.sha256() == _digest(path)
    with HashingFile(path) as f:
        io.BufferedReader(f, 4096).read()
        assert f.sha256() == _digest(path)


def test_source_sha256_of_plain_and_gzip_streams(tmp_path: Path) -> None:
    """The digest is that of the file on disk: the gzip file itself, not what it holds."""
    path = tmp_path / "text.log"
    path.write_bytes(b"(1.0) can0 123#00\n" * 5000)
    gz = tmp_path / "text.log.gz"
    gz.write_bytes(gzip.compress(path.read_bytes(), mtime=0) + b"trailing bytes")
    for p in (path, gz):
        with open_source(p) as stream:
            stream.read(100)
            assert source_sha256(stream) == _digest(p)
    assert source_sha256(io.BytesIO(b"x")) is None  # type: ignore[arg-type]


def test_read_keeps_the_file_digest(tmp_path: Path) -> None:
    """read() of a CAN log records the SHA-256 and size of the file, plain or gzipped."""
    lines = "".join(f"({1.7e9 + i / 100:.6f}) can0 200#{i % 256:02X}00000000000000\n"
                    for i in range(500))
    path = tmp_path / "slow.log"
    path.write_text(lines)
    gz = tmp_path / "slow.log.gz"
    gz.write_bytes(gzip.compress(path.read_bytes(), mtime=0))
    for p in (path, gz):
        rec = read(p)
        assert (rec.provenance.source_sha256, rec.provenance.source_size_bytes) == _digest(p)


def test_reads_at_positions_from_two_threads_are_hashed_in_file_order(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """``took_at``: pieces in any order, overlapping, with gaps, from two threads at once.

    Gaps up to ``HASH_GAP_BYTES`` (made 4 KiB here) are read by ``took_at`` itself; a piece
    further ahead is ignored; the digest is always that of the whole file.
    """
    monkeypatch.setattr(files, "HASH_GAP_BYTES", 4096)
    data = np.random.default_rng(1).integers(0, 256, 400_000, np.uint8).tobytes()
    path = tmp_path / "bytes.bin"
    path.write_bytes(data)
    rng = np.random.default_rng(2)
    for trial in range(20):
        cuts = np.sort(rng.integers(0, len(data), 60))
        pieces = [(int(a), int(b) + int(rng.integers(0, 3000)))
                  for a, b in itertools.pairwise(cuts)]
        pieces = [(a, min(b, len(data))) for a, b in pieces if rng.random() > 0.1]  # gaps
        pieces.append((len(data) - 100, len(data)))                     # far ahead first
        order = [pieces[-1], *pieces[:-1]]
        with HashingFile(path) as f:
            halves = (order[::2], order[1::2])

            def feed(part: list[tuple[int, int]], hf: HashingFile = f) -> None:
                for a, b in part:
                    hf.took_at(a, data[a:b])
            threads = [threading.Thread(target=feed, args=(h,)) for h in halves]
            for t in threads:
                t.start()
            for t in threads:
                t.join()
            assert f.hashed <= len(data)
            assert f.sha256() == _digest(path), trial


def test_an_mcap_file_is_hashed_while_it_is_read(tmp_path: Path,
                                                 monkeypatch: pytest.MonkeyPatch) -> None:
    """MCAP, read at positions by the walk and its chunk worker: hashed as it is read.

    Issue 21, must-hold 2: by the end of the decoding every byte of an intact file has been
    hashed (no second pass over the file, no thread of its own), and the digest is the
    file's, for zstd chunks, uncompressed chunks and a gzipped file.
    """
    left: list[int] = []
    original = HashingFile.sha256

    def spy(self: HashingFile) -> tuple[str, int]:
        left.append(self.seek(0, io.SEEK_END) - self.hashed)
        return original(self)
    monkeypatch.setattr(HashingFile, "sha256", spy)
    t = np.arange(20_000) / 2000.0
    chans = {"accel_x": (np.sin(t).astype(np.float32), 2000.0, "m/s^2", 0, 0.0)}
    for compression in ("zstd", "none"):
        p = write_accel_mcap(tmp_path / f"{compression}.mcap", chans, {}, {},
                             compression=compression, batch=256, chunk_size=16 * 1024)
        left.clear()
        rec = read(p)
        assert (rec.provenance.source_sha256, rec.provenance.source_size_bytes) == _digest(p)
        assert left == [0], compression
    gz = tmp_path / "zstd.mcap.gz"
    gz.write_bytes(gzip.compress((tmp_path / "zstd.mcap").read_bytes(), mtime=0))
    rec = read(gz)
    assert (rec.provenance.source_sha256, rec.provenance.source_size_bytes) == _digest(gz)

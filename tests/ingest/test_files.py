"""The SHA-256 of the provenance, computed as the file is read (rigtools.ingest.files)."""

from __future__ import annotations

import gzip
import hashlib
import io
from pathlib import Path

import numpy as np

from rigtools.ingest import read
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

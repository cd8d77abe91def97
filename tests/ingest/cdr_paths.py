"""The two paths of the MCAP reader over CDR payloads, and the files the CDR tests run them on.

Shared by ``test_mcap_cdr_fast.py`` and ``test_mcap_cdr_checks.py``: :func:`both_paths` reads
the same bytes with the CDR fast path switched off (the general path: every message decoded on
its own) and on (spied on, so a test can check the fast path was taken), and checks that both
give the same report, channels and slow signals; the writers build Imu and other ROS 2 files
and payloads.
"""

from __future__ import annotations

import dataclasses
import io
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from rigtools.demo.mcap_writer import imu_cdr_payloads
from rigtools.ingest import read
from rigtools.ingest.builder import RecordingBuilder
from rigtools.ingest.layout import ChannelMapping
from rigtools.ingest.mcap import decoders as mcap_decoders
from rigtools.ingest.mcap import ingest
from rigtools.ingest.mcap.decoders import IMU_SCHEMA_TEXT
from rigtools.ingest.recording import IngestReport

T0_NS = 1_700_000_000_000_000_000
FS = 1000.0


class CdrPaths:
    """Switches the CDR fast path off (general path) or spies on it (fast path)."""

    def __init__(self, monkeypatch: pytest.MonkeyPatch) -> None:
        self.mp = monkeypatch
        self.orig = mcap_decoders._decoder_for
        self.taken = 0  # blocks the fast path answered
        self.declined = 0  # blocks it left to the general decoder

    def _spy(self, many: Any) -> Any:
        def spy(*args: Any, **kwargs: Any) -> Any:
            got = many(*args, **kwargs)
            if got is None:
                self.declined += 1
            else:
                self.taken += 1
            return got

        return spy

    def general(self) -> None:
        def plain(enc: str, schema: Any, generic: bool) -> Any:
            dec = self.orig(enc, schema, generic)
            if dec is not None and dec.kind in ("imu", "scalar", "generic"):
                return dataclasses.replace(dec, decode_many=None)
            return dec

        self.mp.setattr(mcap_decoders, "_decoder_for", plain)

    def fast(self) -> None:
        def spied(enc: str, schema: Any, generic: bool) -> Any:
            dec = self.orig(enc, schema, generic)
            if (
                dec is not None
                and dec.kind in ("imu", "scalar", "generic")
                and dec.decode_many is not None
            ):
                return dataclasses.replace(dec, decode_many=self._spy(dec.decode_many))
            return dec

        self.mp.setattr(mcap_decoders, "_decoder_for", spied)



def _outcome(data: bytes, path: Path, mapping: ChannelMapping | None, source: str) -> Any:
    """What ``read`` and ``ingest`` make of the bytes: report, channels, slow signals."""
    path.write_bytes(data)
    rep = IngestReport(units="messages")
    b = RecordingBuilder(str(path), rep)
    if source == "stream":  # not seekable: no read ahead, no index, as a pipe

        class Pipe(io.RawIOBase):
            def __init__(self) -> None:
                self.src = io.BytesIO(data)

            def readable(self) -> bool:
                return True

            def readinto(self, buf: Any) -> int:
                chunk = self.src.read(min(len(buf), 65_536))
                buf[: len(chunk)] = chunk
                return len(chunk)

        stream: Any = io.BufferedReader(Pipe())
    else:
        stream = open(path, "rb")
    with stream:
        try:
            ingest(stream, str(path), b, rep, mapping)
            blt = b.build(*_meta(str(path), rep))
            got = (rep.to_dict(), blt.channels, blt.slow)
        except Exception as exc:  # the same error either way
            got = (repr(exc), {}, {})
    try:
        rec = read(path, mapping=mapping)
        whole = (rec.report.to_dict(), rec.channels, rec.slow)
    except Exception as exc:
        whole = (repr(exc), {}, {})
    return got, whole



def _meta(path: str, rep: IngestReport) -> tuple[Any, Any]:
    from rigtools.ingest.recording import Provenance, RunMetadata

    return RunMetadata(run_id="r"), Provenance(path, "0" * 64, 0, "mcap", {}, rep)



def _assert_same(a: Any, b: Any) -> None:
    for x, y in zip(a, b, strict=True):
        assert x[0] == y[0]
        assert x[1].keys() == y[1].keys()
        assert all(x[1][k].equals(y[1][k]) for k in x[1])
        assert x[2].keys() == y[2].keys()
        assert all(x[2][k].equals(y[2][k]) for k in x[2])



def both_paths(
    monkeypatch: pytest.MonkeyPatch,
    tmp_path: Path,
    data: bytes,
    mapping: ChannelMapping | None = None,
    source: str = "file",
) -> tuple[Any, CdrPaths]:
    """The general and the fast outcome of the same bytes, checked equal; the fast spy."""
    paths = CdrPaths(monkeypatch)
    paths.general()
    general = _outcome(data, tmp_path / "same.mcap", mapping, source)
    paths.fast()
    fast = _outcome(data, tmp_path / "same.mcap", mapping, source)
    monkeypatch.setattr(mcap_decoders, "_decoder_for", paths.orig)
    _assert_same(general, fast)
    return fast, paths



def imu_stamps(n: int, fs: float = FS) -> np.ndarray:
    return T0_NS + np.round(np.arange(n) * 1e9 / fs).astype(np.int64)



def imu_accel(n: int, seed: int = 0) -> np.ndarray:
    return np.random.default_rng(seed).standard_normal((n, 3)) * 9.81



def raw_writer(f: Any, chunk_size: int, compression: str = "zstd", **kw: Any) -> Any:
    from mcap.writer import CompressionType, Writer

    comp = {"zstd": CompressionType.ZSTD, "lz4": CompressionType.LZ4, "none": CompressionType.NONE}[
        compression
    ]
    w = Writer(f, chunk_size=chunk_size, compression=comp, **kw)
    w.start(profile="ros2", library="test")
    return w



def imu_file(
    path: Path,
    payloads: list[bytes],
    log_ns: list[int],
    *,
    chunk_size: int = 8192,
    compression: str = "zstd",
    extra: list[tuple[int, bytes]] | None = None,
    n_imu_channels: int = 1,
    **kw: Any,
) -> Path:
    """An Imu file of the payloads given, with Float64 messages interleaved.

    Imu payloads go round robin over ``n_imu_channels`` topics; ``extra`` holds Float64
    messages (log time, payload), put in log-time order among them.
    """
    with open(path, "wb") as f:
        w = raw_writer(f, chunk_size, compression, **kw)
        sid = w.register_schema("sensor_msgs/msg/Imu", "ros2msg", IMU_SCHEMA_TEXT.encode())
        cids = [w.register_channel(f"/imu{k or ''}", "cdr", sid) for k in range(n_imu_channels)]
        fsid = w.register_schema("std_msgs/msg/Float64", "ros2msg", b"float64 data\n")
        fcid = w.register_channel("/slow/x", "cdr", fsid)
        ev = [(t, 0, i) for i, t in enumerate(log_ns)]
        ev += [(t, 1, j) for j, (t, _p) in enumerate(extra or [])]
        for t, kind, i in sorted(ev):
            if kind == 0:
                w.add_message(
                    cids[i % n_imu_channels],
                    log_time=t,
                    data=payloads[i],
                    publish_time=t,
                    sequence=i,
                )
            else:
                w.add_message(
                    fcid, log_time=t, data=(extra or [])[i][1], publish_time=t, sequence=i
                )
        w.finish()
    return path



def imu_rows(stamps: np.ndarray, acc: np.ndarray, **kw: Any) -> list[bytes]:
    return [r.tobytes() for r in imu_cdr_payloads(stamps, acc, **kw)]



def cdr_encode(schema_name: str, schema_text: str, msg: dict, big_endian: bool) -> bytes:
    """CDR bytes by mcap-ros2-support's own serialiser, in either byte order."""
    from mcap_ros2._cdr import CdrWriter, EncapsulationKind
    from mcap_ros2._dynamic import _for_each_msgdef, _write_complex_type

    defs: dict[str, Any] = {}

    def keep(name: str, short: str, d: Any) -> None:
        defs[name] = defs[short] = d

    _for_each_msgdef(schema_name, schema_text, keep)
    out = io.BytesIO()
    w = CdrWriter(out, EncapsulationKind.CDR_BE if big_endian else EncapsulationKind.CDR_LE)
    d = defs[schema_name]
    _write_complex_type(d.msg_name, d.fields, defs, msg, w)
    return out.getvalue()



def lay_out(msgs: list[bytes], gaps: list[int]) -> tuple[bytes, np.ndarray, np.ndarray]:
    buf, s, e = b"", [], []
    for m, g in zip(msgs, gaps, strict=False):
        buf += b"\xee" * g
        s.append(len(buf))
        buf += m
        e.append(len(buf))
    return buf, np.asarray(s, np.int64), np.asarray(e, np.int64)

"""Build a corpus of damaged recordings from intact ones written by the real writers.

Usage::

    python tests/make_damaged_corpus.py OUT_DIR

writes into ``OUT_DIR``

* ``intact/``: small intact recordings of the same synthetic run, written by python-can's
  ``BLFWriter`` (zlib and stored containers), ``ASCWriter``, ``TRCWriter``,
  ``CanutilsLogWriter`` and ``CSVWriter`` (through :func:`rigtools.demo.can_writer.write_can_log`),
  by rigtools' vectorised BLF writer, and by mcap's ``Writer`` (through
  :func:`rigtools.demo.mcap_writer.write_accel_mcap`: zstd, lz4 and uncompressed chunks,
  unchunked, unindexed, JSON-encoded);
* ``damaged/``: one file per (intact file, damage), named ``<intact stem>__<damage>.<suffix>``;
* ``truth.npz``: the samples the writers were given (what an intact read must return);
* ``manifest.json``: for each damaged file its source, its reader and the damage done.

Damages (each a pure function of the intact bytes, so the corpus is the same on every run):
truncation at 16 points spread over the file plus the first and last byte, wrong magic,
a flipped byte inside compressed or CRC-covered data, zero-length and oversized chunk /
container / record length fields, a gzip wrapper cut short, and for the text logs garbage
lines, Latin-1 and NUL bytes, a UTF-8 BOM, mixed CRLF line ends, an over-long line, UTF-16
re-encoding and duplicated, dropped and shuffled lines.

Every damage leaves the samples it does not touch where they were, so the oracle of
``tests/ingest/test_damaged_corpus.py`` holds for all of them: every valid sample a reader
returns equals the written sample at the same absolute index, every slow-signal point is a
written point, and what is missing is counted, or the reader raises a ``RigtoolsError``.
The same files seed the atheris harnesses in ``tests/fuzz/`` (``--seeds-only`` writes the
flat seed directories they take).
"""

from __future__ import annotations

import argparse
import gzip
import json
import random
import re
import struct
import tracemalloc
import zlib
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

__all__ = [
    "ALLOC_FIXED_BYTES",
    "ALLOC_MULTIPLE",
    "CAN_FIRST_COUNTER",
    "MAX_CPU_S_FIXED",
    "MAX_CPU_S_PER_MB",
    "MCAP_FIRST_INDEX",
    "OracleResult",
    "build_corpus",
    "can_frames",
    "can_row_samples",
    "check_against_truth",
    "intact_files",
    "main",
    "mcap_required",
    "peak_bytes",
    "required_samples",
    "touched_records",
]

# --- the bounds every reader keeps, whatever the input (issue 12) --------------------------------
#: CPU time a read may take whatever the input, plus ...
MAX_CPU_S_FIXED = 0.5
#: ... this much per megabyte of input (s/MB). Measured: about 0.3 s/MB for ASC and TRC (python-can
#: parses each line), under 0.05 s/MB for candump, CSV, BLF and MCAP.
MAX_CPU_S_PER_MB = 5.0
#: Peak Python heap of a read (tracemalloc) is at most this multiple of the file size ...
ALLOC_MULTIPLE = 64
#: ... plus this (bytes): the readers' fixed buffers (``blf.PARSE_BYTES`` of inflated objects, one
#: container or chunk) and the Recording's arrays for a small file.
ALLOC_FIXED_BYTES = 24 << 20


def peak_bytes(fn: Callable[[], Any]) -> tuple[int, object]:
    """Peak traced Python heap (bytes) while ``fn`` runs, and what it returned (or raised).

    A :class:`~rigtools.errors.RigtoolsError` is returned, not raised (refusing is allowed).
    """
    from rigtools.errors import RigtoolsError

    tracemalloc.start()
    try:
        try:
            out: object = fn()
        except RigtoolsError as exc:
            out = exc
        return tracemalloc.get_traced_memory()[1], out
    finally:
        tracemalloc.stop()


#: Frame counter of the first frame of every CAN channel (wraps after 536 frames).
CAN_FIRST_COUNTER = 65_000
#: Absolute sample index of the first MCAP sample.
MCAP_FIRST_INDEX = 1_000
_START = 1_700_000_000.0
_FS_CAN = 25_600.0
_N_CAN = 3 * 240  # samples per CAN channel: 240 frames each
_SPEED = np.array([1500.0])  # one slow frame per signal (duration 28 ms at 10 Hz)
_FS_MCAP = 10_000.0
_N_MCAP = 1_500

_HDR = struct.Struct("<BQ")  # MCAP record opcode, content length
_BLF_OBJ = struct.Struct("<4sHHLL")


# --- intact files ------------------------------------------------------------------------------


def _can_truth() -> dict[str, np.ndarray]:
    rng = np.random.default_rng(12)
    t = np.arange(_N_CAN) / _FS_CAN
    return {
        f"accel_{i + 1}": 40 * np.sin(2 * np.pi * 500 * (i + 1) * t) + rng.normal(0, 5, _N_CAN)
        for i in range(4)
    }


def _mcap_truth() -> dict[str, np.ndarray]:
    rng = np.random.default_rng(13)
    return {f"accel_{i}": rng.standard_normal(_N_MCAP).astype(np.float32) for i in (1, 2)}


def can_frames() -> Any:
    """The frames every intact CAN file of the corpus holds (a ``CanFrameBatch``, in order)."""
    from rigtools.demo.can_writer import encode_reference_frames

    slow = {"Torque_Nm": 302.0, "PinionSpeed_rpm": _SPEED, "OilTemp_C": 90.5}
    return encode_reference_frames(
        _can_truth(), slow, start_time_s=_START, first_counter=CAN_FIRST_COUNTER, rng=5
    )


def _blf_small_containers(path: Path, frames: object) -> Path:
    """python-can's BLFWriter with 4 KiB containers, so one file holds several of them."""
    import can

    from rigtools.ingest.can.frames import CanFrameBatch

    assert isinstance(frames, CanFrameBatch)
    with can.BLFWriter(str(path)) as w:
        w.max_container_size = 4096
        for i in range(len(frames)):
            w.on_message_received(
                can.Message(
                    timestamp=float(frames.timestamp_s[i]),
                    arbitration_id=int(frames.arbitration_id[i]),
                    is_extended_id=bool(frames.is_extended[i]),
                    dlc=int(frames.length[i]),
                    data=bytes(frames.data[i, : int(frames.length[i])]),
                    channel=0,
                )
            )
    return path


def intact_files(out: Path) -> tuple[list[tuple[Path, str]], dict[str, np.ndarray]]:
    """Write the intact recordings into ``out``; return ``(path, family)`` pairs and the truth.

    ``family`` is ``"can"`` or ``"mcap"``. The truth maps ``can:<channel>`` to the samples as
    the DBC quantises them (:func:`rigtools.demo.can_writer.quantise_reference`),
    ``can:PinionSpeed_rpm`` etc. to the slow values, and ``mcap:<channel>`` to the float32
    samples widened to float64; ``first_index`` entries give the absolute index of sample 0.
    """
    from rigtools.demo.can_writer import blf_bytes, quantise_reference, write_can_log
    from rigtools.demo.mcap_writer import write_accel_mcap

    out.mkdir(parents=True, exist_ok=True)
    chans = _can_truth()
    frames = can_frames()
    files: list[tuple[Path, str]] = []
    for fmt in ("blf", "asc", "trc", "log", "csv"):
        files.append((write_can_log(out / f"can_{fmt}.{fmt}", frames, fmt), "can"))
    files.append(
        (write_can_log(out / "can_blf_stored.blf", frames, "blf", compression_level=0), "can")
    )
    p = out / "can_blf_rigtools.blf"
    p.write_bytes(blf_bytes(frames))
    files.append((p, "can"))
    files.append((_blf_small_containers(out / "can_blf_4k.blf", frames), "can"))

    truth: dict[str, np.ndarray] = {f"can:{k}": v for k, v in quantise_reference(chans).items()}
    truth["can:first_index"] = np.array([3 * CAN_FIRST_COUNTER])
    truth["can:Torque_Nm"] = np.array([302.0])
    truth["can:PinionSpeed_rpm"] = _SPEED
    truth["can:OilTemp_C"] = np.array([90.5])

    mchans = _mcap_truth()
    spec = {k: (v, _FS_MCAP, "g", MCAP_FIRST_INDEX, _START) for k, v in mchans.items()}
    slow_pts = {
        "PinionSpeed_rpm": (_START + np.arange(3) * 0.05, np.array([1500.0, 1501, 1502]), "rpm")
    }
    variants: dict[str, dict[str, object]] = {
        "zstd": {},
        "lz4": {"compression": "lz4"},
        "none": {"compression": "none"},
        "unchunked": {"use_chunking": False},
        "unindexed": {"indexed": False},
        "json": {"encoding": "json", "compression": "none"},
    }
    for name, kw in variants.items():
        p = write_accel_mcap(
            out / f"mcap_{name}.mcap", spec, slow_pts, batch=100, chunk_size=2048, **kw
        )  # type: ignore[arg-type]
        files.append((p, "mcap"))
    for k, v in mchans.items():
        truth[f"mcap:{k}"] = v.astype(np.float64)
    truth["mcap:first_index"] = np.array([MCAP_FIRST_INDEX])
    truth["mcap:PinionSpeed_rpm"] = np.array([1500.0, 1501, 1502])
    return files, truth


# --- the oracle ---------------------------------------------------------------------------------


@dataclass(frozen=True)
class OracleResult:
    """What :func:`check_against_truth` found.

    Attributes
    ----------
    matched : int
        Valid samples equal to the written sample at their absolute index.
    wrong : int
        Valid samples that differ from it, or lie outside the written range.
    missing : int
        Written samples not returned as valid.
    interior_missing : int
        Of those, samples between the first and last valid sample of their channel.
    """

    matched: int
    wrong: int
    missing: int
    interior_missing: int


_BUS = re.compile(r"@bus-?\d+$")


def check_against_truth(
    rec: Any,
    truth: Mapping[str, np.ndarray],
    family: str,
    *,
    tolerance_samples: int = 0,
    intact: Any = None,
    tolerance_slow: int = 0,
    required: Mapping[str, np.ndarray] | None = None,
    index_modulus: int | None = None,
    tolerance_lost: int | None = None,
) -> OracleResult:
    """The oracle: a reader's Recording against the samples the writer was given.

    Asserts that

    * every valid sample equals, bit for bit, the written sample at the same absolute index,
      except at most ``tolerance_samples`` of them (samples of frames whose own bytes were
      damaged in a way no check can see, e.g. a flipped data bit in a format without CRC);
    * samples missing between the first and last valid sample of a channel are counted
      (``report.gaps`` or ``report.rejected`` is not empty);
    * every slow-signal value is a value of the same signal in ``intact`` (the Recording of
      the undamaged file), except at most ``tolerance_slow`` of them.

    * every sample flagged in ``required`` (base channel name -> mask over the written
      samples: the samples of the records no damage touched) is returned, valid and equal,
      except at most ``tolerance_lost`` of them (default: ``tolerance_samples``): a damaged
      record may take the place of one intact record (a flipped identifier or counter bit
      makes it a well-formed twin of another frame, and which of two differing twins is the
      true one cannot be known). Cuts, dropped, duplicated and shuffled records make no
      twins: pass 0 there.

    Channel names may carry a ``@busN`` suffix (a damaged bus field puts frames on another
    bus); they are compared under their base name. ``index_modulus`` compares absolute
    indices modulo the counter's range (``k * 2**bits`` samples): a file whose first frames
    are lost starts after an unknown number of counter wraps.
    """
    first = int(truth[f"{family}:first_index"][0])
    matched = wrong = missing = interior = 0
    got: dict[str, np.ndarray] = {}
    for name, ch in rec.channels.items():
        key = f"{family}:{_BUS.sub('', name)}"
        if key not in truth:  # a damaged name field made a channel of its own
            wrong += int(ch.valid.sum())
            continue
        want = truth[key]
        rel = ch.first_index - first + np.flatnonzero(ch.valid)
        if index_modulus:
            rel = rel % index_modulus
        vals = ch.values[ch.valid]
        inside = (rel >= 0) & (rel < want.size)
        same = np.zeros(rel.size, bool)
        same[inside] = vals[inside].view(np.int64) == want[rel[inside]].view(np.int64)
        matched += int(same.sum())
        wrong += int((~same).sum())
        present = np.zeros(want.size, bool)
        present[rel[same]] = True
        got[_BUS.sub("", name)] = got.get(_BUS.sub("", name), present) | present
        missing += int((~present).sum())
        occupied = np.zeros(want.size, bool)  # a valid sample there, right or (tolerated) wrong
        occupied[rel[inside]] = True
        if rel[same].size:
            lo, hi = int(rel[same].min()), int(rel[same].max())
            interior += int((~occupied[lo : hi + 1]).sum())
    for name, want in truth.items():  # channels that vanished entirely
        fam, _, base = name.partition(":")
        if (
            fam == family
            and base.startswith("accel_")
            and not any(_BUS.sub("", n) == base for n in rec.channels)
        ):
            missing += int(want.size)
    assert wrong <= tolerance_samples, (
        f"{wrong} valid sample(s) differ from the written ones (tolerated: {tolerance_samples})"
    )
    if interior:
        assert rec.report.has_losses, f"{interior} interior sample(s) missing, nothing counted"
    n_lost = 0
    for base, mask in (required or {}).items():
        have = got.get(base, np.zeros(mask.size, bool))
        n_lost += int((mask & ~have).sum())
    lost_ok = tolerance_samples if tolerance_lost is None else tolerance_lost
    assert n_lost <= lost_ok, (
        f"{n_lost} sample(s) of undamaged records missing (tolerated: {lost_ok})"
    )
    if intact is not None:
        bad_slow = 0
        for name, s in rec.slow.items():
            base = _BUS.sub("", name)
            if base not in intact.slow:
                bad_slow += len(s)
                continue
            known = intact.slow[base].values
            bad_slow += int((~np.isin(s.values, known)).sum())
        assert bad_slow <= tolerance_slow, f"{bad_slow} slow value(s) were never written"
    return OracleResult(matched, wrong, missing, interior)


def can_row_samples(frames: Any) -> tuple[list[str | None], np.ndarray, int]:
    """Which written samples each frame row of a reference-layout batch carries.

    Returns ``(channel, start, k)``: per row the base channel name (None for slow frames) and
    the index of its first sample relative to the first written sample; ``k`` samples per
    frame. Rows of a channel are its frames in order, as
    :func:`rigtools.demo.can_writer.encode_reference_frames` writes them.
    """
    from rigtools.demo.can_writer import reference_layout

    layout = reference_layout()
    by_id = {int(u.message.frame_id): u.spec.channel for u in layout.uniform}
    k = len(layout.uniform[0].samples)
    names: list[str | None] = []
    start = np.full(len(frames), -1, np.int64)
    seen: dict[str, int] = {}
    for i, fid in enumerate(frames.arbitration_id.tolist()):
        name = by_id.get(int(fid))
        names.append(name)
        if name is not None:
            start[i] = k * seen.get(name, 0)
            seen[name] = seen.get(name, 0) + 1
    return names, start, k


def required_samples(
    names: list[str | None],
    start: np.ndarray,
    k: int,
    rows: Any,
    truth: Mapping[str, np.ndarray],
    family: str = "can",
) -> dict[str, np.ndarray]:
    """Per channel, a mask over the written samples that the frame ``rows`` carry."""
    out = {
        key.partition(":")[2]: np.zeros(v.size, bool)
        for key, v in truth.items()
        if key.startswith(f"{family}:accel_")
    }
    for r in rows:
        name = names[r]
        if name is not None:
            out[name][start[r] : start[r] + k] = True
    return out


# --- damages ------------------------------------------------------------------------------------

Damage = Callable[[bytes], bytes | None]  # None: not applicable to this file


def _truncations(data: bytes) -> dict[str, Damage]:
    n = len(data)
    points = sorted({1, n - 1, *(round(n * k / 17) for k in range(1, 17))})
    return {f"cut_at_{p}": (lambda d, p=p: d[:p]) for p in points if 0 < p < n}


def _mcap_records(data: bytes) -> list[tuple[int, int, int]]:
    out, pos = [], 8
    while pos + 9 <= len(data):
        op, length = _HDR.unpack_from(data, pos)
        out.append((op, pos, length))
        pos += 9 + length
        if op == 0x02:
            break
    return out


def _mcap_chunks(data: bytes) -> list[dict[str, int]]:
    out = []
    for op, pos, _length in _mcap_records(data):
        if op != 0x06:
            continue
        c = pos + 9
        clen = struct.unpack_from("<I", data, c + 28)[0]
        rlen_at = c + 32 + clen
        out.append(
            {
                "pos": pos,
                "usize_at": c + 16,
                "crc_at": c + 24,
                "rlen_at": rlen_at,
                "records_at": rlen_at + 8,
                "records_len": struct.unpack_from("<Q", data, rlen_at)[0],
            }
        )
    return out


def _patched(data: bytes, at: int, fmt: str, value: int) -> bytes:
    b = bytearray(data)
    struct.pack_into(fmt, b, at, value)
    return bytes(b)


def _flip(data: bytes, at: int, mask: int = 0x10) -> bytes:
    b = bytearray(data)
    b[at] ^= mask
    return bytes(b)


def _mcap_damages(data: bytes) -> dict[str, Damage]:
    out: dict[str, Damage] = {"wrong_magic": lambda d: b"\x89MCAX0\r\n" + d[8:]}
    recs = _mcap_records(data)
    chunks = _mcap_chunks(data)
    if chunks:
        c = chunks[len(chunks) // 2]
        out["chunk_crc_wrong"] = lambda d: _patched(
            d, c["crc_at"], "<I", struct.unpack_from("<I", d, c["crc_at"])[0] ^ 0xDEADBEEF
        )
        out["chunk_data_flipped"] = lambda d: _flip(d, c["records_at"] + c["records_len"] // 2)
        out["chunk_records_zero_length"] = lambda d: _patched(d, c["rlen_at"], "<Q", 0)
        out["chunk_records_oversized"] = lambda d: _patched(d, c["rlen_at"], "<Q", 1 << 62)
        out["chunk_usize_oversized"] = lambda d: _patched(d, c["usize_at"], "<Q", 1 << 40)
        out["chunk_usize_zero"] = lambda d: _patched(d, c["usize_at"], "<Q", 0)
    mid = [r for r in recs if r[0] in (0x05, 0x06)]
    if mid:
        _, pos, _ = mid[len(mid) // 3]
        out["record_length_oversized"] = lambda d: _patched(d, pos + 1, "<Q", (1 << 63) - 1)
        out["record_length_zero"] = lambda d: _patched(d, pos + 1, "<Q", 0)
        out["record_opcode_unknown"] = lambda d: _patched(d, pos, "<B", 0x7E)
    footer = [r for r in recs if r[0] == 0x02]
    if footer:
        out["footer_summary_start_wrong"] = lambda d: _patched(
            d, footer[0][1] + 9, "<Q", len(d) * 3
        )
    out["tail_magic_missing"] = lambda d: d[:-8]
    return out


def _blf_objects(data: bytes) -> list[tuple[int, int]]:
    """(offset, size) of the top-level objects after the 144-byte header."""
    out, pos = [], struct.unpack_from("<L", data, 4)[0]
    while pos + 16 <= len(data):
        sig, _hs, _hv, size, _t = _BLF_OBJ.unpack_from(data, pos)
        if sig != b"LOBJ" or size < 16:
            break
        out.append((pos, size))
        pos += size + (size % 4)
    return out


def _blf_damages(data: bytes) -> dict[str, Damage]:
    out: dict[str, Damage] = {
        "wrong_magic": lambda d: b"LOGX" + d[4:],
        "header_size_oversized": lambda d: _patched(d, 4, "<L", 0xFFFFFFF0),
        "header_size_zero": lambda d: _patched(d, 4, "<L", 0),
    }
    objs = _blf_objects(data)
    if objs:
        pos, size = objs[len(objs) // 2]
        out["container_size_zero"] = lambda d: _patched(d, pos + 8, "<L", 0)
        out["container_size_oversized"] = lambda d: _patched(d, pos + 8, "<L", 0xFFFFFFF0)
        out["container_usize_oversized"] = lambda d: _patched(d, pos + 16 + 8, "<L", 0xFFFFFFF0)
        out["container_data_flipped"] = lambda d: _flip(d, pos + 32 + (size - 32) // 2)
        out["container_signature_wrong"] = lambda d: d[:pos] + b"LOBX" + d[pos + 4 :]
        out["container_duplicated"] = lambda d: (
            d[: pos + size] + d[pos : pos + size] + d[pos + size :]
        )
        out["container_dropped"] = lambda d: d[:pos] + d[pos + size :]
    return out


def _lines(data: bytes) -> list[bytes]:
    return data.splitlines(keepends=True)


def _text_damages(data: bytes) -> dict[str, Damage]:
    lines = _lines(data)
    n = len(lines)
    mid = n // 2
    rnd = random.Random(7)

    def shuffled(d: bytes) -> bytes:
        ls = _lines(d)
        body = ls[mid : mid + 30]
        rnd.shuffle(body)
        return b"".join(ls[:mid] + body + ls[mid + 30 :])

    return {
        "garbage_lines": lambda d: b"".join(
            ls + (b"@@ garbage \x00\xff line %d\n" % i if i % 37 == 5 else b"")
            for i, ls in enumerate(_lines(d))
        ),
        "latin1_line": lambda d: b"".join(
            [*_lines(d)[:mid], b"// comment caf\xe9 \xa7\n", *_lines(d)[mid:]]
        ),
        "nul_bytes": lambda d: d[: len(d) // 2] + b"\x00" * 64 + d[len(d) // 2 :],
        "utf8_bom": lambda d: b"\xef\xbb\xbf" + d,
        "crlf_mixed": lambda d: b"".join(
            ls.replace(b"\n", b"\r\n") if i % 2 else ls for i, ls in enumerate(_lines(d))
        ),
        "overlong_line": lambda d: b"".join(
            [*_lines(d)[:mid], b"9" * 200_000 + b"\n", *_lines(d)[mid:]]
        ),
        "utf16": lambda d: d.decode("latin-1").encode("utf-16"),
        "lines_duplicated": lambda d: b"".join(
            _lines(d)[:mid] + _lines(d)[mid : mid + 20] + _lines(d)[mid:]
        ),
        "lines_dropped": lambda d: b"".join(_lines(d)[:mid] + _lines(d)[mid + 20 :]),
        "lines_shuffled": shuffled,
        "header_lost": lambda d: b"".join(_lines(d)[6:]),
        "line_cut_in_middle": lambda d: b"".join(
            [*_lines(d)[:mid], _lines(d)[mid][:9] + b"\n", *_lines(d)[mid + 1 :]]
        ),
    }


# --- what each damage touches ------------------------------------------------------------------
#
# Every damaged file records which records of the intact file the damage touched: frame rows
# (CAN: the i-th frame the writer was given) or (channel, sequence) of MCAP batch messages.
# Every other record must come back whole (``required`` of the oracle); a reader that drops
# intact data next to the damage fails. A damage is a set of byte ranges of the intact file;
# a record is touched when a range overlaps the unit holding it (a text line, a BLF container
# -- a frame object may straddle two --, an MCAP chunk or top-level message record, or the
# record defining its MCAP channel).

_TEXT_FRAME_LINE = {
    ".asc": re.compile(rb"^\s*\d+\.\d+\s+\d+\s+[0-9A-Fa-f]+x?\s+(Rx|Tx)"),
    ".trc": re.compile(rb"^\s*\d+\s+\d"),
    ".log": re.compile(rb"^\("),
    ".csv": re.compile(rb"^\d"),
}

Unit = tuple[int, int, list[Any]]  # byte range [start, end) of the intact file, its records


def _text_units(path: Path, data: bytes) -> list[Unit]:
    units, pos, row = [], 0, 0
    for ln in _lines(data):
        rows: list[Any] = []
        if _TEXT_FRAME_LINE[path.suffix].match(ln):
            rows, row = [row], row + 1
        units.append((pos, pos + len(ln), rows))
        pos += len(ln)
    return units


def _blf_units(data: bytes) -> list[Unit]:
    conts = _blf_objects(data)
    stream, bounds = b"", [0]
    for pos, size in conts:
        method = struct.unpack_from("<H", data, pos + 16)[0]
        payload = data[pos + 32 : pos + size]
        stream += zlib.decompress(payload) if method == 2 else payload
        bounds.append(len(stream))
    rows: list[list[Any]] = [[] for _ in conts]
    pos, row = 0, 0
    while pos + 16 <= len(stream):
        size = _BLF_OBJ.unpack_from(stream, pos)[3]
        a = int(np.searchsorted(bounds, pos, side="right")) - 1
        b = int(np.searchsorted(bounds, pos + size - 1, side="right")) - 1
        for c in range(a, b + 1):
            rows[c].append(row)
        row += 1
        pos += size + size % 4
    return [(pos, pos + size + size % 4, r) for (pos, size), r in zip(conts, rows, strict=True)]


def _mcap_inner(content: bytes) -> list[tuple[int, bytes]]:
    out, pos = [], 0
    while pos + 9 <= len(content):
        op, length = _HDR.unpack_from(content, pos)
        out.append((op, content[pos + 9 : pos + 9 + length]))
        pos += 9 + length
    return out


def _mcap_units(data: bytes) -> list[Unit]:
    """Units of an MCAP file (top-level records; a chunk with its inner records).

    Records are ``("msg", channel id, sequence)`` and ``("chan", id, topic)`` (a channel
    definition: every message of the channel depends on it).
    """
    import lz4.frame
    import zstandard

    units = []
    for op, pos, length in _mcap_records(data):
        body = data[pos + 9 : pos + 9 + length]
        inner = [(op, body)]
        if op == 0x06:
            clen = struct.unpack_from("<I", body, 28)[0]
            comp = body[32 : 32 + clen].decode()
            rlen = struct.unpack_from("<Q", body, 32 + clen)[0]
            raw = body[40 + clen : 40 + clen + rlen]
            usize = struct.unpack_from("<Q", body, 16)[0]
            if comp == "zstd":
                raw = zstandard.ZstdDecompressor().decompress(raw, max_output_size=usize)
            elif comp == "lz4":
                raw = lz4.frame.decompress(raw)
            inner = _mcap_inner(raw)
        recs: list[Any] = []
        for iop, content in inner:
            if iop == 0x05:
                cid, seq = struct.unpack_from("<HI", content, 0)
                recs.append(("msg", cid, seq))
            elif iop == 0x04:
                cid = struct.unpack_from("<H", content, 0)[0]
                tlen = struct.unpack_from("<I", content, 4)[0]
                recs.append(("chan", cid, content[8 : 8 + tlen].decode()))
        units.append((pos, pos + 9 + length, recs))
    return units


def _gunzip_prefix(g: bytes) -> int:
    """Bytes of the original a truncated gzip stream still gives."""
    d = zlib.decompressobj(31)
    try:
        return len(d.decompress(g))
    except zlib.error:
        return 0


def _damage_ranges(path: Path, data: bytes, name: str) -> list[tuple[int, int]] | None:
    """Byte ranges of the intact file that damage ``name`` touches; None: nothing is left."""
    n = len(data)
    if name.startswith("cut_at_"):
        return [(int(name[7:]), n)]
    if name == "gzip_cut":
        g = gzip.compress(data, mtime=0)
        return [(_gunzip_prefix(g[: len(g) * 2 // 3]), n)]
    if name in ("zero_length", "utf16"):
        return None
    if name == "wrong_magic":
        return [(0, 8)]
    if name.startswith("header_size"):
        return [(0, 144)]
    if path.suffix == ".blf" and name.startswith("container_"):
        objs = _blf_objects(data)
        pos, size = objs[len(objs) // 2]
        return [(pos, pos + size)]
    if name.startswith("chunk_"):
        c = _mcap_chunks(data)[len(_mcap_chunks(data)) // 2]
        return [(c["pos"], c["pos"] + 1)]
    if name.startswith("record_"):
        mid = [r for r in _mcap_records(data) if r[0] in (0x05, 0x06)]
        pos = mid[len(mid) // 3][1]
        return [(pos, pos + 9)]
    if name == "footer_summary_start_wrong":
        pos = next(r[1] for r in _mcap_records(data) if r[0] == 0x02)
        return [(pos, pos + 17)]
    if name == "tail_magic_missing":
        return [(n - 8, n)]
    spans = np.cumsum([0] + [len(ln) for ln in _lines(data)])
    mid = (len(spans) - 1) // 2
    return {
        "nul_bytes": [(n // 2 - 1, n // 2 + 1)],
        "lines_dropped": [(int(spans[mid]), int(spans[min(mid + 20, len(spans) - 1)]))],
        "header_lost": [(0, int(spans[min(6, len(spans) - 1)]))],
        "line_cut_in_middle": [(int(spans[mid]), int(spans[mid + 1]))],
    }.get(name, [])  # insertions, re-encodings, reorderings: nothing of the intact file lost


def touched_records(path: Path, data: bytes, name: str) -> list[Any] | None:
    """Records of the intact file at ``path`` that damage ``name`` touched (see above).

    CAN: frame rows (ints); MCAP: ``[topic, sequence]`` of batch messages. None: no record
    is required (nothing of the file is left, or the whole file was re-encoded).
    """
    ranges = _damage_ranges(path, data, name)
    if ranges is None:
        return None
    if path.suffix == ".mcap":
        units = _mcap_units(data)
    elif path.suffix == ".blf":
        units = _blf_units(data)
    else:
        units = _text_units(data=data, path=path)
    hit = [any(a < e and s < b for a, b in ranges) for s, e, _ in units]
    touched = {r for h, (_s, _e, recs) in zip(hit, units, strict=True) if h for r in recs}
    if path.suffix != ".mcap":
        return sorted(touched)
    topic = {r[1]: r[2] for _s, _e, recs in units for r in recs if r[0] == "chan"}
    # A channel is lost only when every definition of it is touched (the summary repeats it).
    defined = {r[1] for _s, _e, recs in units for r in recs if r[0] == "chan"}
    lost_chan = defined - {
        r[1]
        for h, (_s, _e, recs) in zip(hit, units, strict=True)
        if not h
        for r in recs
        if r[0] == "chan"
    }
    out = set()
    for _s, _e, recs in units:
        for r in recs:
            if r[0] == "msg" and (r in touched or r[1] in lost_chan):
                out.add((topic.get(r[1], ""), r[2]))
    return sorted([t, s] for t, s in out)


def mcap_required(
    touched: list[Any], truth: Mapping[str, np.ndarray], batch: int = 100
) -> dict[str, np.ndarray]:
    """Per MCAP channel, a mask over the written samples of the messages not touched."""
    out = {
        key.partition(":")[2]: np.ones(v.size, bool)
        for key, v in truth.items()
        if key.startswith("mcap:accel_")
    }
    for topic, seq in touched:
        name = topic.rpartition("/")[2]
        if topic.startswith("/accel/") and name in out:
            out[name][seq * batch : (seq + 1) * batch] = False
    return out


def damages_for(path: Path, data: bytes) -> dict[str, Damage]:
    """Every damage that applies to an intact file, by name."""
    out = dict(_truncations(data))
    suffix = path.suffix
    if suffix == ".mcap":
        out.update(_mcap_damages(data))
    elif suffix == ".blf":
        out.update(_blf_damages(data))
    else:
        out.update(_text_damages(data))
    out["gzip_cut"] = lambda d: (lambda g: g[: len(g) * 2 // 3])(gzip.compress(d, mtime=0))
    out["gzip_crc_wrong"] = lambda d: (
        lambda g: g[:-8] + struct.pack("<I", zlib.crc32(d) ^ 1) + g[-4:]
    )(gzip.compress(d, mtime=0))
    out["zero_length"] = lambda d: b""
    return out


def build_corpus(out: str | Path) -> list[dict[str, Any]]:
    """Write intact files, damaged files, ``truth.npz`` and ``manifest.json`` into ``out``.

    Returns the manifest: one dict per damaged file with ``file`` (relative to ``out``),
    ``source`` (the intact file), ``family`` (``can``/``mcap``), ``damage`` and ``touched``
    (:func:`touched_records`: the records the damage touched, or None).
    """
    root = Path(out)
    files, truth = intact_files(root / "intact")
    np.savez(root / "truth.npz", **truth)
    dmg = root / "damaged"
    dmg.mkdir(parents=True, exist_ok=True)
    manifest = []
    for path, family in files:
        data = path.read_bytes()
        for name, fn in damages_for(path, data).items():
            bad = fn(data)
            if bad is None:
                continue
            suffix = path.suffix + (".gz" if name.startswith("gzip") else "")
            target = dmg / f"{path.stem}__{name}{suffix}"
            target.write_bytes(bad)
            manifest.append(
                {
                    "file": str(target.relative_to(root)),
                    "source": path.name,
                    "family": family,
                    "damage": name,
                    "touched": touched_records(path, data, name),  # type: ignore[dict-item]
                }
            )
    (root / "manifest.json").write_text(json.dumps(manifest, indent=1))
    return manifest


def write_seeds(out: str | Path) -> None:
    """Flat seed directories for the atheris harnesses: ``out/mcap`` and ``out/can``."""
    root = Path(out)
    build_corpus(root / "corpus")
    for family in ("mcap", "can"):
        d = root / family
        d.mkdir(parents=True, exist_ok=True)
        srcs = [
            p
            for p in (root / "corpus" / "intact").iterdir()
            if (p.suffix == ".mcap") == (family == "mcap")
        ]
        srcs += [
            p
            for p in (root / "corpus" / "damaged").iterdir()
            if (".mcap" in p.suffixes) == (family == "mcap") and p.suffix != ".gz"
        ]
        for p in srcs:
            data = p.read_bytes()
            if 0 < len(data) <= 256 * 1024:  # libFuzzer's -max_len below bounds them anyway
                (d / p.name).write_bytes(data)


def main(argv: list[str] | None = None) -> int:
    """Command line: ``python tests/make_damaged_corpus.py OUT_DIR [--seeds]``."""
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("out", type=Path, help="directory to write into (created)")
    ap.add_argument(
        "--seeds",
        action="store_true",
        help="also write flat seed directories OUT/mcap and OUT/can for atheris",
    )
    args = ap.parse_args(argv)
    if args.seeds:
        write_seeds(args.out)
        print(f"seeds in {args.out / 'mcap'} and {args.out / 'can'}")
    else:
        manifest = build_corpus(args.out)
        print(f"{len(manifest)} damaged files in {args.out / 'damaged'}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

"""MCAP reader on damaged files, built in code from files the rigtools writer made.

Each case damages an intact file the way storage, transfer or a buggy logger would (cut short,
flipped bytes, lying length fields, stripped summary, foreign records) and checks that the
reader returns what is intact, counts what is not, and never allocates what a field claims.
"""

from __future__ import annotations

import gzip
import io
import struct
import tracemalloc
import zlib
from pathlib import Path

import mcap_layout
import numpy as np
import pytest

from rigtools.demo.mcap_writer import write_accel_mcap
from rigtools.errors import NoDataError, RecordingFormatError
from rigtools.ingest import read
from rigtools.ingest.builder import RecordingBuilder
from rigtools.ingest.mcap import MAGIC, ingest, iter_messages
from rigtools.ingest.mcap.decoders import decode_accel_batch_protobuf
from rigtools.ingest.recording import IngestReport

T0 = 1_700_000_000.0
_HDR = struct.Struct("<BQ")


# --- an independent walker over the file, for locating what to damage ------------------------




def _messages_in_chunk(data: bytes, chunk: dict) -> int:
    """Message records inside an uncompressed chunk."""
    import zstandard

    raw = data[chunk["records_at"] : chunk["records_at"] + chunk["records_len"]]
    if chunk["compression"] == "zstd":
        raw = zstandard.ZstdDecompressor().decompressobj().decompress(raw)
    n, pos = 0, 0
    while pos < len(raw):
        op, length = _HDR.unpack_from(raw, pos)
        n += op == 0x05
        pos += 9 + length
    return n


def _reference_prefix(data: bytes) -> list:
    """Messages mcap's own StreamReader yields from (possibly cut) data before it gives up."""
    from mcap.records import Message
    from mcap.stream_reader import StreamReader

    out = []
    try:
        for rec in StreamReader(io.BytesIO(data), skip_magic=False).records:
            if isinstance(rec, Message):
                out.append(rec)
    except Exception:  # the reference reader fails at the cut, by design
        pass
    return out


# --- fixtures -------------------------------------------------------------------------------


def _chans(n=6000, seed=0):
    rng = np.random.default_rng(seed)
    return {f"accel_{i}": (rng.standard_normal(n).astype(np.float32), 10_000.0, "g", 0, T0)
            for i in (1, 2)}


@pytest.fixture(scope="module")
def intact(tmp_path_factory) -> Path:
    d = tmp_path_factory.mktemp("hostile")
    return write_accel_mcap(d / "intact.mcap", _chans(), batch=256, chunk_size=4096)


@pytest.fixture(scope="module")
def intact_plain(tmp_path_factory) -> Path:
    d = tmp_path_factory.mktemp("hostile_plain")
    return write_accel_mcap(d / "plain.mcap", _chans(), batch=256, chunk_size=4096,
                            compression="none")


def _write(tmp_path: Path, data: bytes, name="damaged.mcap") -> Path:
    p = tmp_path / name
    p.write_bytes(data)
    return p


def _ingest(path: Path, **kw):
    rep = IngestReport(units="messages")
    b = RecordingBuilder(str(path), rep)
    with open(path, "rb") as f:
        ingest(f, str(path), b, rep, None)
    return b, rep


def _same_prefix(got, ref) -> None:
    """Every channel of ``got`` is an exact prefix of the same channel of ``ref``."""
    for name, ch in got.channels.items():
        r = ref.channels[name]
        assert ch.first_index == r.first_index
        n = len(ch)
        assert np.array_equal(ch.values, r.values[:n]) and np.array_equal(ch.valid, r.valid[:n])


# --- empty, wrong magic ----------------------------------------------------------------------


def test_empty_file_names_path_byte_0_and_the_magic(tmp_path):
    rep = IngestReport(units="messages")
    with pytest.raises(RecordingFormatError,
                       match=r"empty\.mcap at byte 0: expected the MCAP magic .*an empty file"):
        ingest(io.BytesIO(b""), str(tmp_path / "empty.mcap"), RecordingBuilder("x", rep), rep,
               None)
    p = _write(tmp_path, b"", "empty.mcap")
    with pytest.raises(RecordingFormatError, match=r"at byte 0: expected the MCAP magic"):
        read(p, fmt="mcap")
    with pytest.raises(RecordingFormatError, match=r"at byte 0: expected a non-empty recording"):
        read(p)


def test_wrong_magic_names_what_was_found(tmp_path):
    p = _write(tmp_path, b"NOTMCAP!" + bytes(100), "wrong.mcap")
    with pytest.raises(RecordingFormatError, match=r"at byte 0: .*found b'NOTMCAP!"):
        read(p, fmt="mcap")


def test_magic_only_is_cut_before_any_record(tmp_path):
    p = _write(tmp_path, MAGIC)
    with pytest.raises(NoDataError, match="truncated_record: 1"):
        read(p)


# --- truncation -----------------------------------------------------------------------------


def test_truncated_at_several_points_returns_exactly_the_complete_prefix(intact, tmp_path):
    data = intact.read_bytes()
    ref = read(intact)
    chunks = mcap_layout.chunks(data)
    assert len(chunks) >= 8
    recs = mcap_layout.records(data)
    data_end = next(pos for op, pos, _l in recs if op == 0x0F)
    cuts = {
        "inside chunk 3 header": chunks[3]["pos"] + 4,
        "inside chunk 3 data": chunks[3]["pos"] + 5000,
        "right after chunk 5 (before its indexes)": chunks[5]["end"],
        "inside the last chunk": chunks[-1]["end"] - 1,
        "at DataEnd": data_end,
    }
    for label, cut in cuts.items():
        p = _write(tmp_path, data[:cut])
        rec = read(p)  # never raises: complete chunks are there
        want = _reference_prefix(data[:cut])
        want_samples = {}
        for m in want:
            b = decode_accel_batch_protobuf(m.data)
            want_samples[b.channel] = want_samples.get(b.channel, 0) + b.values.size
        assert {k: len(v) for k, v in rec.channels.items()} == want_samples, label
        assert rec.report.decoded == len(want), label
        _same_prefix(rec, ref)
        assert rec.report.rejected["truncated_record"] == 1, label
        start = max(pos for _op, pos, _l in recs if pos <= cut)
        assert rec.report.first_position["truncated_record"] == f"byte {start}", label
        assert any(f"cut at byte {start}" in w for w in rec.report.warnings), label


def test_cut_inside_the_first_chunk_leaves_no_data_but_counts_the_loss(intact, tmp_path):
    data = intact.read_bytes()
    c0 = mcap_layout.chunks(data)[0]
    with pytest.raises(NoDataError, match="truncated_record: 1"):
        read(_write(tmp_path, data[: c0["pos"] + 100]))


def test_cut_in_the_summary_loses_nothing(intact, tmp_path):
    data = intact.read_bytes()
    ref = read(intact)
    recs = mcap_layout.records(data)
    data_end = next((pos, length) for op, pos, length in recs if op == 0x0F)
    for cut in (data_end[0] + 9 + data_end[1], data_end[0] + 9 + data_end[1] + 4,
                len(data) - 20, len(data) - 3):
        rec = read(_write(tmp_path, data[:cut]))
        assert all(rec.channels[k].equals(ref.channels[k]) for k in ref.channels)
        assert not rec.report.rejected
        assert rec.report.warnings


def test_unchunked_file_cut_inside_a_message(tmp_path):
    p = write_accel_mcap(tmp_path / "flat.mcap", _chans(n=3000), batch=256, use_chunking=False)
    data = p.read_bytes()
    ref = read(p)
    msgs = [(pos, length) for op, pos, length in mcap_layout.records(data) if op == 0x05]
    cut = msgs[10][0] + 9 + 100
    rec = read(_write(tmp_path, data[:cut]))
    assert rec.report.decoded == 10
    assert rec.report.first_position["truncated_record"] == f"byte {msgs[10][0]}"
    _same_prefix(rec, ref)


# --- no summary, no index -------------------------------------------------------------------


@pytest.mark.parametrize("use_chunking", [True, False])
def test_file_without_summary_or_indexes_reads_by_streaming(tmp_path, use_chunking):
    chans = _chans(n=4000)
    ref = read(write_accel_mcap(tmp_path / "ref.mcap", chans, batch=256, chunk_size=8192))
    p = write_accel_mcap(tmp_path / "bare.mcap", chans, batch=256, chunk_size=8192,
                         use_chunking=use_chunking, indexed=False)
    ops = {op for op, _p, _l in mcap_layout.records(p.read_bytes())}
    assert not ops & {0x07, 0x08, 0x0B, 0x0E}  # no message/chunk index, statistics, offsets
    rec = read(p)
    assert all(rec.channels[k].equals(ref.channels[k]) for k in ref.channels)
    assert not rec.report.rejected and rec.report.decoded == ref.report.decoded


def test_mcap_library_needs_the_summary_we_do_not(tmp_path):
    p = write_accel_mcap(tmp_path / "bare.mcap", _chans(n=2000), batch=256, indexed=False)
    data = p.read_bytes()
    data_end = next(pos for op, pos, _l in mcap_layout.records(data) if op == 0x0F)
    stripped = _write(tmp_path, data[: data_end + 9 + 4])  # DataEnd kept, footer gone
    rec = read(stripped)
    assert sum(len(c) for c in rec.channels.values()) == 4000
    assert not rec.report.rejected
    assert any("inside its summary section (expected a Footer" in w
               for w in rec.report.warnings)


# --- CRC ------------------------------------------------------------------------------------


def test_flipped_byte_in_uncompressed_chunk_fails_its_crc(intact_plain, tmp_path):
    data = bytearray(intact_plain.read_bytes())
    ref = read(intact_plain)
    c = mcap_layout.chunks(bytes(data))[2]
    n_msgs = _messages_in_chunk(bytes(data), c)
    # a byte deep inside the samples of the chunk's second record (not a length field)
    second = c["records_at"] + 9 + struct.unpack_from("<Q", data, c["records_at"] + 1)[0]
    data[second + 9 + 22 + 200] ^= 0x40
    rec = read(_write(tmp_path, bytes(data)))
    assert rec.report.rejected["chunk_crc_mismatch"] == n_msgs > 0
    assert rec.report.first_position["chunk_crc_mismatch"] == f"byte {c['pos']}"
    assert rec.report.decoded == ref.report.decoded - n_msgs
    assert rec.report.gaps  # the builder marks the hole left by the refused chunk
    for name, ch in rec.channels.items():
        r = ref.channels[name]
        assert np.array_equal(ch.values[ch.valid], r.values[:len(ch)][ch.valid])
    # without CRC checks the damaged data would have been used
    rep = IngestReport(units="messages")
    with open(_write(tmp_path, bytes(data), "again.mcap"), "rb") as f:
        n = sum(1 for _ in iter_messages(f, "again", rep, validate_crcs=False))
    assert n == ref.report.decoded and not rep.rejected


def test_flipped_byte_in_zstd_chunk_is_refused_and_counted(intact, tmp_path):
    data = bytearray(intact.read_bytes())
    ref = read(intact)
    c = mcap_layout.chunks(bytes(data))[4]
    assert c["compression"] == "zstd"
    n_msgs = _messages_in_chunk(bytes(data), c)
    data[c["records_at"] + c["records_len"] // 2] ^= 0x01
    rec = read(_write(tmp_path, bytes(data)))
    lost = sum(rec.report.rejected[r] for r in
               ("chunk_crc_mismatch", "chunk_decompression_error", "chunk_size_mismatch"))
    assert lost == n_msgs and rec.report.decoded == ref.report.decoded - n_msgs


def test_refused_chunk_without_message_indexes_counts_as_one(tmp_path):
    p = write_accel_mcap(tmp_path / "bare.mcap", _chans(n=4000), batch=256, chunk_size=8192,
                         compression="none", indexed=False)
    data = bytearray(p.read_bytes())
    c = mcap_layout.chunks(bytes(data))[1]
    data[c["records_at"] + 300] ^= 0xFF
    rec = read(_write(tmp_path, bytes(data)))
    assert rec.report.rejected["chunk_crc_mismatch"] == 1


def test_zero_crc_means_unchecked_and_a_bad_record_inside_is_counted(intact_plain, tmp_path):
    data = bytearray(intact_plain.read_bytes())
    c = mcap_layout.chunks(bytes(data))[1]
    struct.pack_into("<I", data, c["crc_at"], 0)
    rec = read(_write(tmp_path, bytes(data)))  # crc 0: not checked, still intact
    assert not rec.report.rejected
    # now make the third record inside the chunk claim more than the chunk holds
    pos = c["records_at"]
    for _ in range(2):
        pos += 9 + struct.unpack_from("<Q", data, pos + 1)[0]
    struct.pack_into("<Q", data, pos + 1, 10**9)
    rec = read(_write(tmp_path, bytes(data), "bad_inner.mcap"))
    assert rec.report.rejected["bad_chunk_record"] == 1
    assert rec.report.first_position["bad_chunk_record"].startswith(f"chunk at byte {c['pos']}")


# --- size claims ----------------------------------------------------------------------------


def _peak_bytes(fn) -> int:
    tracemalloc.start()
    try:
        fn()
        return tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()


@pytest.mark.parametrize("claim", [2**62, 64 << 20])
def test_absurd_uncompressed_size_is_refused_before_allocating(intact, tmp_path, claim):
    data = bytearray(intact.read_bytes())
    ref = read(intact)
    c = mcap_layout.chunks(bytes(data))[3]
    n_msgs = _messages_in_chunk(bytes(data), c)
    struct.pack_into("<Q", data, c["usize_at"], claim)
    p = _write(tmp_path, bytes(data))
    out = {}
    peak = _peak_bytes(lambda: out.setdefault("rec", read(p)))
    rec = out["rec"]
    assert peak < 16 << 20, f"peak {peak} bytes"
    assert rec.report.rejected["absurd_chunk_size"] == n_msgs
    assert rec.report.first_position["absurd_chunk_size"] == f"byte {c['pos']}"
    assert rec.report.decoded == ref.report.decoded - n_msgs  # and it went on after it


def _mcap(records: list[tuple[int, bytes]]) -> bytes:
    body = b"".join(_HDR.pack(op, len(c)) + c for op, c in records)
    return MAGIC + body


def _s(text: str) -> bytes:
    b = text.encode()
    return struct.pack("<I", len(b)) + b


def test_zstd_frame_claiming_a_huge_content_size_is_bounded_by_the_chunk(tmp_path):
    import zstandard

    bomb = zstandard.ZstdCompressor().compress(bytes(200 << 20))  # 200 MiB of zeros, ~6 KiB
    assert len(bomb) < 64 << 10
    records = [(0x01, _s("") + _s("hand")),
               (0x06, struct.pack("<QQQI", 0, 0, 1000, 0) + _s("zstd")
                + struct.pack("<Q", len(bomb)) + bomb),
               (0x0F, struct.pack("<I", 0))]
    p = _write(tmp_path, _mcap(records))
    rep = IngestReport(units="messages")
    peak = _peak_bytes(lambda: list(iter_messages(open(p, "rb"), str(p), rep)))
    assert peak < 8 << 20, f"peak {peak} bytes"
    assert rep.rejected["chunk_size_mismatch"] == 1


def test_record_length_past_end_of_file(intact, tmp_path):
    data = bytearray(intact.read_bytes())
    ref = read(intact)
    c = mcap_layout.chunks(bytes(data))[6]
    struct.pack_into("<Q", data, c["pos"] + 1, len(data))
    rec = read(_write(tmp_path, bytes(data)))
    # the chunk's own fields give its true length and its CRC vouches for its records: the
    # chunk and every later one are read, the lie is warned about (issue 12, (b))
    assert not rec.report.rejected
    assert any(f"Chunk record at byte {c['pos']} claims {len(data)} bytes" in w
               for w in rec.report.warnings)
    assert all(rec.channels[k].equals(ref.channels[k]) for k in ref.channels)
    # a stream that cannot be read ahead (gzip) still ends there, counted
    gz = tmp_path / "lie.mcap.gz"
    gz.write_bytes(gzip.compress(bytes(data)))
    rec = read(gz)
    assert rec.report.rejected["truncated_record"] == 1
    assert rec.report.first_position["truncated_record"] == f"byte {c['pos']}"
    want = _reference_prefix(bytes(data[: c["pos"]]))
    assert rec.report.decoded == len(want) > 0
    _same_prefix(rec, ref)


def test_record_length_of_2_63_in_a_gzip_stream_allocates_nothing(intact, tmp_path):
    data = bytearray(intact.read_bytes())
    c = mcap_layout.chunks(bytes(data))[2]
    struct.pack_into("<Q", data, c["pos"] + 1, 2**63)
    gz = tmp_path / "huge.mcap.gz"
    gz.write_bytes(gzip.compress(bytes(data)))
    out = {}
    peak = _peak_bytes(lambda: out.setdefault("rec", read(gz)))
    assert peak < 16 << 20, f"peak {peak} bytes"
    rec = out["rec"]
    assert rec.report.rejected["oversized_record"] == 1
    assert rec.report.rejected["truncated_record"] == 1


def test_unknown_compression_is_counted(intact, tmp_path):
    data = bytearray(intact.read_bytes())
    c = mcap_layout.chunks(bytes(data))[1]
    n_msgs = _messages_in_chunk(bytes(data), c)
    data[c["comp_at"] : c["comp_at"] + 4] = b"brot"
    rec = read(_write(tmp_path, bytes(data)))
    assert rec.report.rejected == {"unknown_compression": n_msgs}
    assert any("'brot'" in w for w in rec.report.warnings)


def test_channels_defined_only_in_a_refused_chunk_come_back_from_the_summary(intact, tmp_path):
    data = bytearray(intact.read_bytes())
    ref = read(intact)
    # the writer puts Schema and Channel records in the first chunk
    c = mcap_layout.chunks(bytes(data))[0]
    n_msgs = _messages_in_chunk(bytes(data), c)
    data[c["records_at"] + 40] ^= 0x10
    rec = read(_write(tmp_path, bytes(data)))
    lost = sum(rec.report.rejected[r] for r in
               ("chunk_crc_mismatch", "chunk_decompression_error", "chunk_size_mismatch"))
    assert lost == n_msgs and "unknown_channel" not in rec.report.rejected
    assert rec.report.decoded == ref.report.decoded - n_msgs
    assert any("found in the summary" in w for w in rec.report.warnings)
    # without a summary nothing defines them: counted, not dropped
    bare = write_accel_mcap(tmp_path / "bare.mcap", _chans(), batch=256, chunk_size=4096,
                            indexed=False)
    data = bytearray(bare.read_bytes())
    c = mcap_layout.chunks(bytes(data))[0]
    data[c["records_at"] + 40] ^= 0x10
    with pytest.raises(NoDataError, match=r"unknown_channel: \d+"):
        read(_write(tmp_path, bytes(data), "bare_damaged.mcap"))


# --- foreign and odd records ----------------------------------------------------------------


def test_unknown_opcodes_are_skipped_by_length(intact, tmp_path):
    data = intact.read_bytes()
    ref = read(intact)
    c = mcap_layout.chunks(data)[2]
    junk = _HDR.pack(0x42, 5) + b"hello" + _HDR.pack(0xF0, 0) + _HDR.pack(0x10, 3) + b"\x00" * 3
    rec = read(_write(tmp_path, data[: c["pos"]] + junk + data[c["pos"] :]))
    assert all(rec.channels[k].equals(ref.channels[k]) for k in ref.channels)
    assert not rec.report.rejected


def test_message_naming_an_undefined_channel_is_counted(tmp_path):
    p = write_accel_mcap(tmp_path / "flat.mcap", _chans(n=1000), batch=256, use_chunking=False)
    data = bytearray(p.read_bytes())
    msgs = [pos for op, pos, _l in mcap_layout.records(bytes(data)) if op == 0x05]
    struct.pack_into("<H", data, msgs[3] + 9, 999)
    rec = read(_write(tmp_path, bytes(data)))
    assert rec.report.rejected["unknown_channel"] == 1
    assert rec.report.decoded == len(msgs) - 1


def test_message_shorter_than_its_header_is_counted(tmp_path):
    records = [(0x01, _s("") + _s("hand")),
               (0x03, struct.pack("<H", 1) + _s("x") + _s("y") + _s("")),
               (0x04, struct.pack("<HH", 1, 1) + _s("/t") + _s("z") + struct.pack("<I", 0)),
               (0x05, struct.pack("<HI", 1, 0)),
               (0x0F, struct.pack("<I", 0))]
    rep = IngestReport(units="messages")
    assert list(iter_messages(io.BytesIO(_mcap(records)), "hand", rep)) == []
    assert rep.rejected == {"bad_record": 1}  # no Footer after DataEnd: warned, nothing lost
    assert any("expected a Footer" in w for w in rep.warnings)


def test_nan_and_inf_payloads_survive_damage_free_and_are_counted(tmp_path):
    vals = np.array([1, np.nan, 2, np.inf, -np.inf, 3] * 100, np.float32)
    for enc in ("protobuf", "json"):
        p = write_accel_mcap(tmp_path / f"n_{enc}.mcap", {"a": (vals, 100.0, "g", 7, T0)},
                             encoding=enc, batch=64)
        rec = read(p)
        ch = rec.channels["a"]
        assert np.array_equal(ch.values, vals.astype(np.float64), equal_nan=True)
        assert ch.valid.tolist() == np.isfinite(vals).tolist()
        assert rec.report.rejected["non_finite_sample"] == 300


def test_every_single_byte_cut_of_a_small_file_reads_without_exceptions(tmp_path):
    p = write_accel_mcap(tmp_path / "small.mcap", _chans(n=600), batch=100, chunk_size=2048)
    data = p.read_bytes()
    for cut in range(0, len(data), 7):
        rep = IngestReport(units="messages")
        b = RecordingBuilder("cut", rep)
        if cut < 8:
            with pytest.raises(RecordingFormatError, match="expected the MCAP magic"):
                ingest(io.BytesIO(data[:cut]), "cut", b, rep, None)
            continue
        ingest(io.BytesIO(data[:cut]), "cut", b, rep, None)
        assert rep.decoded + rep.n_rejected >= 1 or cut < 40


def test_crc_helper_agrees_with_the_writer(intact_plain):
    data = intact_plain.read_bytes()
    c = mcap_layout.chunks(data)[0]
    raw = data[c["records_at"] : c["records_at"] + c["records_len"]]
    assert zlib.crc32(raw) == struct.unpack_from("<I", data, c["crc_at"])[0]

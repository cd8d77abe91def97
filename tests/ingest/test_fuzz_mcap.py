"""Property-based damage of MCAP files, and the allocation bound on lying length fields.

Small recordings (2 accelerometer channels of 1500 samples in 100-sample protobuf batches,
plus a slow JSON signal) are written by mcap's ``Writer`` (through
:func:`rigtools.demo.mcap_writer.write_accel_mcap`) with 2 KiB zstd chunks, uncompressed
chunks, and without chunks. An independent walker (below; not rigtools' reader) maps every
message to its unit of damage: the chunk holding it (its CRC and compression make a chunk
stand or fall as a whole), or the message record itself in an unchunked file. hypothesis
then cuts the file anywhere, flips bits anywhere, and duplicates, drops and shuffles chunks
(with their message indexes) or message records. The oracle is that of the other
``test_fuzz_*`` modules (``make_damaged_corpus.check_against_truth``), with ``k`` = 100
samples per message.

A message is required (must come back exactly) when its unit is intact and the definitions it
needs (schema and channel records) are readable: in an intact unit before it, or in an intact
summary section.

Length fields claiming gigabytes (record length, chunk uncompressed size, chunk records
length, zstd content size) must cost at most :data:`ALLOC_MULTIPLE` x the file size +
:data:`ALLOC_FIXED_BYTES` of Python heap.
"""

from __future__ import annotations

import atexit
import functools
import shutil
import struct
import tempfile
import time
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from make_damaged_corpus import (
    ALLOC_FIXED_BYTES,
    ALLOC_MULTIPLE,
    MAX_CPU_S_FIXED,
    MAX_CPU_S_PER_MB,
    check_against_truth,
    peak_bytes,
)

from rigtools.demo.mcap_writer import write_accel_mcap
from rigtools.errors import RigtoolsError
from rigtools.ingest import read

FIRST = 5_000
N = 1_500
BATCH = 100
T0 = 1_700_000_000.0
_HDR = struct.Struct("<BQ")

FAST = settings(
    max_examples=30,
    deadline=None,
    derandomize=True,
    database=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
)
LONG = settings(
    max_examples=1000,
    deadline=None,
    database=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
)

_TMP = Path(tempfile.mkdtemp(prefix="rigtools-fuzz-mcap-"))
atexit.register(shutil.rmtree, _TMP, True)

VARIANTS = {
    "zstd": {"compression": "zstd"},
    "none": {"compression": "none"},
    "unchunked": {"use_chunking": False},
}


def _truth() -> dict[str, np.ndarray]:
    rng = np.random.default_rng(21)
    chans = {f"accel_{i}": rng.standard_normal(N).astype(np.float32) for i in (1, 2)}
    out = {f"mcap:{k}": v.astype(np.float64) for k, v in chans.items()}
    out["mcap:first_index"] = np.array([FIRST])
    return out


_TRUTH = _truth()


def records(data: bytes) -> list[tuple[int, int, int]]:
    """``(opcode, offset, total length)`` of the top-level records up to the footer."""
    out, pos = [], 8
    while pos + 9 <= len(data):
        op, length = _HDR.unpack_from(data, pos)
        out.append((op, pos, 9 + length))
        pos += 9 + length
        if op == 0x02:
            break
    return out


def _inner(data: bytes, pos: int) -> bytes:
    """The uncompressed records of the chunk record at ``pos``."""
    c = pos + 9
    clen = struct.unpack_from("<I", data, c + 28)[0]
    comp = data[c + 32 : c + 32 + clen].decode()
    rlen = struct.unpack_from("<Q", data, c + 32 + clen)[0]
    raw = data[c + 40 + clen : c + 40 + clen + rlen]
    if comp == "zstd":
        import zstandard

        return zstandard.ZstdDecompressor().decompressobj().decompress(raw)
    assert comp == "", comp
    return raw


def _walk_records(buf: bytes, base: int) -> list[tuple[int, int, bytes]]:
    out, pos = [], base
    while pos + 9 <= len(buf):
        op, length = _HDR.unpack_from(buf, pos)
        out.append((op, pos, buf[pos + 9 : pos + 9 + length]))
        pos += 9 + length
    return out


@functools.cache
def layout(variant: str):
    """The intact file and, per unit of damage, its byte range and what it holds.

    Returns ``(data, units, summary_start, msgs)``: ``units`` is a tuple of ``(start, end,
    defines)`` (a chunk with its message indexes, or a single top-level record), ``defines``
    the channel ids whose Channel record the unit holds; ``msgs`` lists per accel message
    ``(unit, channel name, k-th message of the channel, unit of its Channel record, unit of
    its Schema record)``.
    """
    chans = {
        k.partition(":")[2]: (v.astype(np.float32), 10_000.0, "g", FIRST, T0)
        for k, v in _TRUTH.items()
        if k.startswith("mcap:accel")
    }
    slow = {"PinionSpeed_rpm": (T0 + np.arange(4) * 0.03, np.array([1.0, 2.0, 3.0, 4.0]), "rpm")}
    p = write_accel_mcap(
        _TMP / f"intact_{variant}.mcap",
        chans,
        slow,
        batch=BATCH,
        chunk_size=2048,
        **VARIANTS[variant],
    )  # type: ignore[arg-type]
    data = p.read_bytes()
    recs = records(data)
    data_end = next(pos for op, pos, _ in recs if op == 0x0F)
    units: list[tuple[int, int, set[int]]] = []
    topics: dict[int, str] = {}
    msgs: list[tuple[int, str, int]] = []
    seen: dict[str, int] = {}
    schema_unit: dict[int, int] = {}
    schema_of: dict[int, int] = {}
    for op, pos, length in recs:
        if pos >= data_end:
            break
        if op == 0x07 and units:  # message index: belongs to the chunk before it
            units[-1] = (units[-1][0], pos + length, units[-1][2])
            continue
        if op == 0x01:
            continue
        u = len(units)
        units.append((pos, pos + length, set()))
        inner = (
            _walk_records(_inner(data, pos), 0)
            if op == 0x06
            else [(op, pos, data[pos + 9 : pos + length])]
        )
        for iop, _ipos, body in inner:
            if iop == 0x03:
                schema_unit.setdefault(struct.unpack_from("<H", body, 0)[0], u)
            elif iop == 0x04:
                cid, sid = struct.unpack_from("<HH", body, 0)
                tlen = struct.unpack_from("<I", body, 4)[0]
                topics[cid] = body[8 : 8 + tlen].decode()
                schema_of[cid] = sid
                units[u][2].add(cid)
            elif iop == 0x05:
                cid = struct.unpack_from("<H", body, 0)[0]
                topic = topics[cid]
                if topic.startswith("/accel/"):
                    name = topic.rsplit("/", 1)[1]
                    msgs.append((u, name, seen.get(name, 0)))
                    seen[name] = seen.get(name, 0) + 1
    definer = {cid: next(i for i, un in enumerate(units) if cid in un[2]) for cid in topics}
    by_name = {
        t.rsplit("/", 1)[1]: (definer[cid], schema_unit[schema_of[cid]])
        for cid, t in topics.items()
    }
    frozen = tuple((a, b, frozenset(d)) for a, b, d in units)
    return data, frozen, data_end, tuple((u, n, k, *by_name[n]) for u, n, k in msgs)


@functools.cache
def _intact(variant: str):
    layout(variant)
    return read(_TMP / f"intact_{variant}.mcap")


def _required(
    variant: str, intact_units: set[int], summary_ok: bool, order: list[int] | None = None
) -> dict[str, np.ndarray]:
    _, _, _, msgs = layout(variant)
    out = {
        k.partition(":")[2]: np.zeros(v.size, bool)
        for k, v in _TRUTH.items()
        if k.startswith("mcap:accel")
    }
    pos = {u: i for i, u in enumerate(order)} if order is not None else None
    for u, name, k, channel_unit, schema_unit in msgs:
        if u not in intact_units:
            continue
        defined = all(
            d in intact_units and (pos is None or pos.get(d, 1 << 30) <= pos[u])
            for d in (channel_unit, schema_unit)
        )
        if defined or summary_ok:
            out[name][k * BATCH : (k + 1) * BATCH] = True
    return out


def _read_checked(
    data: bytes,
    variant: str,
    *,
    n_damaged: int,
    refused_ok: bool,
    required: dict[str, np.ndarray],
    n_lost: int = 0,
):
    p = _TMP / f"damaged_{variant}.mcap"
    p.write_bytes(data)
    _intact(variant)  # first reads import the decoders: not part of the bound
    t0 = time.process_time()
    try:
        rec = read(p)
    except RigtoolsError:
        rec = None
    cpu = time.process_time() - t0
    assert cpu <= MAX_CPU_S_FIXED + MAX_CPU_S_PER_MB * len(data) / 1e6, f"{cpu:.2f} s CPU"
    if rec is None:
        assert refused_ok or not any(m.any() for m in required.values()), (
            "refused although intact messages remain"
        )
        return None
    check_against_truth(
        rec,
        _TRUTH,
        "mcap",
        tolerance_samples=BATCH * n_damaged,
        required=required,
        tolerance_lost=BATCH * n_lost,
    )
    return rec


VARIANT = st.sampled_from(sorted(VARIANTS))


# --- cuts and flips ----------------------------------------------------------------------------


def _check_cut(variant: str, frac: float) -> None:
    data, units, _, msgs = layout(variant)
    cut = int(frac * len(data))
    whole = {i for i, (_a, b, _d) in enumerate(units) if b <= cut}
    hit = {i for i, (a, b, _) in enumerate(units) if a < cut < b}
    n_damaged = sum(1 for m in msgs if m[0] in hit)  # the messages of the unit cut through
    _read_checked(
        data[:cut],
        variant,
        n_damaged=n_damaged,
        refused_ok=cut < 8 + 9,
        required=_required(variant, whole, summary_ok=False),
    )


@FAST
@given(variant=VARIANT, frac=st.floats(0.0, 1.0))
def test_cut_anywhere_returns_every_complete_chunk(variant, frac):
    _check_cut(variant, frac)


def _check_flips(variant: str, flips: list[tuple[float, int]]) -> None:
    data, units, data_end, msgs = layout(variant)
    b = bytearray(data)
    hit: set[int] = set()
    where = [min(int(frac * len(b)), len(b) - 1) for frac, _ in flips]
    for at, (_, bit) in zip(where, flips, strict=True):
        b[at] ^= 1 << bit
        hit.update(i for i, (a, e, _) in enumerate(units) if a <= at < e)
    intact = set(range(len(units))) - hit
    summary_ok = all(at < data_end for at in where)
    n_damaged = sum(1 for m in msgs if m[0] in hit)  # the messages of the units hit
    _read_checked(
        bytes(b),
        variant,
        n_damaged=n_damaged,
        n_lost=len(flips),  # a flipped id or sequence may make a twin of one intact message
        refused_ok=any(at < units[0][0] for at in where),  # magic or header record
        required=_required(variant, intact, summary_ok),
    )


_FLIPS = st.lists(st.tuples(st.floats(0.0, 1.0), st.integers(0, 7)), min_size=1, max_size=3)


@FAST
@given(variant=VARIANT, flips=_FLIPS)
def test_bit_flips_lose_at_most_the_chunks_or_messages_they_hit(variant, flips):
    _check_flips(variant, flips)


# --- duplicated, dropped and shuffled chunks or messages ---------------------------------------


def _check_units(variant: str, op: str, a: int, width: int, seed: int) -> None:
    data, units, _, _ = layout(variant)
    n = len(units)
    a = min(a, n - 1)
    sel = list(range(a, min(n, a + width)))
    order = list(range(n))
    if op == "duplicate":
        order = order[: sel[-1] + 1] + sel + order[sel[-1] + 1 :]
    elif op == "drop":
        order = [u for u in order if u not in set(sel)]
    else:
        perm = np.random.default_rng(seed).permutation(sel).tolist()
        order = order[:a] + perm + order[a + len(sel) :]
    body = b"".join(data[units[u][0] : units[u][1]] for u in order)
    new = data[: units[0][0]] + body + data[units[-1][1] :]
    # Offsets in the summary (chunk indexes) no longer match; the reader must not trust them
    # blindly, but it may use the channel definitions there.
    req = _required(variant, set(order), summary_ok=True, order=order)
    _read_checked(new, variant, n_damaged=0, refused_ok=False, required=req)


@FAST
@given(
    variant=VARIANT,
    op=st.sampled_from(["duplicate", "drop", "shuffle"]),
    a=st.integers(0, 40),
    width=st.integers(1, 6),
    seed=st.integers(0, 2**16),
)
def test_duplicated_dropped_and_shuffled_chunks_and_messages(variant, op, a, width, seed):
    _check_units(variant, op, a, width, seed)


@pytest.mark.slow
@LONG
@given(
    variant=VARIANT,
    frac=st.floats(0.0, 1.0),
    flips=_FLIPS,
    op=st.sampled_from(["duplicate", "drop", "shuffle"]),
    a=st.integers(0, 40),
    width=st.integers(1, 6),
    seed=st.integers(0, 2**16),
)
def test_long_profile(variant, frac, flips, op, a, width, seed):
    _check_cut(variant, frac)
    _check_flips(variant, flips)
    _check_units(variant, op, a, width, seed)


# --- length fields that claim gigabytes --------------------------------------------------------


def _claims(variant: str) -> list[tuple[str, int, int]]:
    data, units, _, _ = layout(variant)
    pos = units[len(units) // 2][0]
    out = [("record_length_2**62", pos + 1, 1 << 62), ("record_length_60MiB", pos + 1, 60 << 20)]
    if variant != "unchunked":
        c = pos + 9
        clen = struct.unpack_from("<I", data, c + 28)[0]
        out += [
            ("chunk_uncompressed_size_2**40", c + 16, 1 << 40),
            ("chunk_records_length_2**62", c + 32 + clen, 1 << 62),
            ("chunk_records_length_60MiB", c + 32 + clen, 60 << 20),
        ]
    return out


_CLAIM_CASES = [(v, c[0]) for v in VARIANTS for c in _claims(v)]


@pytest.mark.parametrize(("variant", "name"), _CLAIM_CASES)
def test_length_fields_claiming_gigabytes_allocate_nothing_like_it(variant, name):
    data, _, _, _ = layout(variant)
    _, at, value = next(c for c in _claims(variant) if c[0] == name)
    b = bytearray(data)
    struct.pack_into("<Q", b, at, value)
    p = _TMP / f"claim_{variant}_{name}.mcap"
    p.write_bytes(bytes(b))
    _intact(variant)  # warm imports and caches outside the measurement
    peak, out = peak_bytes(lambda: read(p))
    bound = ALLOC_MULTIPLE * len(b) + ALLOC_FIXED_BYTES
    assert peak <= bound, f"{name}: peak {peak / 2**20:.1f} MiB > {bound / 2**20:.1f} MiB"
    if not isinstance(out, RigtoolsError):
        # a lost record is counted; a chunk whose record length lies is read whole by the
        # length its own fields imply (its CRC vouches for it), and only warned about
        report = out.report  # type: ignore[attr-defined]
        assert report.has_losses or any("read with the latter" in w for w in report.warnings)


def test_allocation_bound_holds_on_the_intact_file():
    data, _, _, _ = layout("zstd")
    _intact("zstd")
    peak, out = peak_bytes(lambda: read(_TMP / "intact_zstd.mcap"))
    assert not isinstance(out, RigtoolsError)
    assert peak <= ALLOC_MULTIPLE * len(data) + ALLOC_FIXED_BYTES


# --- defects the long profile found, fixed (issue 12; focused tests in test_mcap_resync.py) ---
# A record whose length field lies no longer ends the walk (resynchronisation, or a chunk read
# by its own fields), and a damaged Schema or Channel record no longer wins over the intact copy
# the CRC-checked summary repeats. The oracle above models none of them any more.


def test_record_length_lie_in_unchunked_file_keeps_the_rest():
    data, units, _, msgs = layout("unchunked")
    u = len(units) * 3 // 4
    b = bytearray(data)
    b[units[u][0] + 8] ^= 0x01  # high byte of the record length: claims 2**56 more bytes
    p = _TMP / "lie_unchunked.mcap"
    p.write_bytes(bytes(b))
    rec = read(p)
    lost = {(n, k) for uu, n, k, _, _ in msgs if uu == u}
    for name, ch in rec.channels.items():
        want = {k for uu, n, k, _, _ in msgs if n == name and (n, k) not in lost}
        got = set(((ch.first_index - FIRST + np.flatnonzero(ch.valid)) // BATCH).tolist())
        assert want <= got, f"{name}: messages {sorted(want - got)} lost"


def test_damaged_schema_record_is_replaced_by_the_summary_copy():
    data = layout("unchunked")[0]
    op, pos, _ = records(data)[1]
    assert op == 0x03  # the first Schema record, before any message
    b = bytearray(data)
    b[pos + 86] ^= 0x01  # a byte of the FileDescriptorSet (found by the long profile)
    p = _TMP / "bad_schema.mcap"
    p.write_bytes(bytes(b))
    rec = read(p)
    assert rec.report.rejected["bad_schema"] == 0
    assert sorted(rec.channels) == ["accel_1", "accel_2"]


# --- regressions found by the long profile -----------------------------------------------------


def test_damaged_rate_in_the_first_message_costs_that_message_only():
    """A damaged rate in a channel's first message costs that message, not the channel.

    Found by the long profile (unchunked file, one flipped bit in the first accel_2 message's
    sample_rate_Hz: 10000 -> 9488): the builder fixed the channel's layout from its first
    block and dropped the 14 intact messages after it as inconsistent_channel_layout. It now
    keeps the layout that carries the most samples.
    """
    data, units, _, msgs = layout("unchunked")
    u = next(uu for uu, n, k, _, _ in msgs if n == "accel_2" and k == 0)
    start, end, _ = units[u]
    body = bytes(data[start:end])
    j = body.index(struct.pack("<d", 10_000.0))  # protobuf double field of the rate
    b = bytearray(data)
    b[start + j + 6] ^= 0x01
    p = _TMP / "bad_rate.mcap"
    p.write_bytes(bytes(b))
    rec = read(p)
    assert rec.report.rejected["inconsistent_channel_layout"] == BATCH
    req = _required("unchunked", set(range(len(units))) - {u}, summary_ok=True)
    check_against_truth(rec, _TRUTH, "mcap", required=req)
    assert rec.channels["accel_2"].sample_rate_Hz == 10_000.0


def test_damaged_channel_record_is_replaced_by_the_summary_copy():
    data = layout("unchunked")[0]
    op, pos, _ = records(data)[3]
    assert op == 0x04  # the second Channel record (accel_2), before any message
    b = bytearray(data)
    b[pos + 40] ^= 0x01  # inside its message encoding "protobuf" (found by the long profile)
    p = _TMP / "bad_channel.mcap"
    p.write_bytes(bytes(b))
    rec = read(p)
    assert rec.report.rejected["no_decoder"] == 0
    assert sorted(rec.channels) == ["accel_1", "accel_2"]


def test_record_length_lie_in_chunked_file_keeps_every_later_chunk():
    data, units, _, msgs = layout("zstd")
    b = bytearray(data)
    b[units[0][0] + 7] ^= 0x01  # 6th byte of the first chunk's record length (found by the
    p = _TMP / "lie_chunked.mcap"  # long profile): claims 2**40 more bytes
    p.write_bytes(bytes(b))
    try:
        rec = read(p)
    except RigtoolsError as exc:
        pytest.fail(f"refused: {exc}")
    later = {(n, k) for u, n, k, _, _ in msgs if u > 0}
    for name, ch in rec.channels.items():
        got = set(((ch.first_index - FIRST + np.flatnonzero(ch.valid)) // BATCH).tolist())
        want = {k for n, k in later if n == name}
        assert want <= got, f"{name}: messages {sorted(want - got)} lost"

"""Property-based damage of BLF files, and the allocation bound on lying length fields.

A small recording of the reference layout is written by python-can's ``BLFWriter`` with
2 KiB containers (so objects straddle containers, as in real files), zlib-compressed and
stored. An independent walker (below, not rigtools' reader) maps every frame to the
container(s) holding it. hypothesis then cuts the file anywhere, flips bits anywhere, and
duplicates, drops and shuffles containers; the oracle is the one of
``test_fuzz_text_logs.py`` (``make_damaged_corpus.check_against_truth``), with the container
as the unit of damage: a frame is intact when every container holding its bytes is intact
and in its place relative to its neighbours. Every intact frame must come back: no lost
intact sample is tolerated after cuts, duplicated, dropped or shuffled containers, and one
frame per flipped bit (a flipped identifier or counter bit can make a damaged frame the twin
of an intact one). Absolute sample indices are compared exactly when the first frame of
every channel is intact, else modulo one counter wrap.

Length fields that claim gigabytes (file header size, container size, uncompressed size,
object size inside a container) must cost no more than :data:`ALLOC_MULTIPLE` x the file
size + :data:`ALLOC_FIXED_BYTES` of Python heap (tracemalloc peak, which sees NumPy's buffers).
"""

from __future__ import annotations

import atexit
import functools
import gc
import itertools
import shutil
import struct
import tempfile
import time
import zlib
from pathlib import Path

import can
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from make_damaged_corpus import (
    ALLOC_FIXED_BYTES,
    ALLOC_MULTIPLE,
    MAX_CPU_S_FIXED,
    MAX_CPU_S_PER_MB,
    can_row_samples,
    check_against_truth,
    peak_bytes,
    required_samples,
)

from rigtools.demo.can_writer import encode_reference_frames, quantise_reference
from rigtools.errors import RigtoolsError
from rigtools.ingest import read

FIRST_COUNTER = 65_500
N_FRAMES = 60  # per channel
MODULUS = 3 * (1 << 16)
_OBJ = struct.Struct("<4sHHLL")
_HEADER = 144

FAST = settings(
    max_examples=30,
    deadline=None,
    derandomize=True,
    database=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
)
LONG = settings(
    max_examples=400,
    deadline=None,
    database=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
)

_TMP = Path(tempfile.mkdtemp(prefix="rigtools-fuzz-blf-"))
atexit.register(shutil.rmtree, _TMP, True)


def _source():
    rng = np.random.default_rng(5)
    chans = [rng.normal(0, 30, 3 * N_FRAMES) for _ in range(4)]
    frames = encode_reference_frames(
        chans, {"Torque_Nm": 40.0, "OilTemp_C": 80.0}, first_counter=FIRST_COUNTER, rng=5
    )
    truth = {f"can:{k}": v for k, v in quantise_reference(chans).items()}
    truth["can:first_index"] = np.array([3 * FIRST_COUNTER])
    return frames, truth


_FRAMES, _TRUTH = _source()
_NAMES, _START, _K = can_row_samples(_FRAMES)


def _write_blf(path: Path, level: int, container_bytes: int = 2048) -> Path:
    with can.BLFWriter(str(path), compression_level=level) as w:
        w.max_container_size = container_bytes
        f = _FRAMES
        for i in range(len(f)):
            w.on_message_received(
                can.Message(
                    timestamp=float(f.timestamp_s[i]),
                    arbitration_id=int(f.arbitration_id[i]),
                    is_extended_id=False,
                    dlc=8,
                    data=bytes(f.data[i, :8]),
                    channel=0,
                )
            )
    return path


def containers(data: bytes) -> list[tuple[int, int]]:
    """``(offset, length including padding)`` of each top-level container (independent walk)."""
    out, pos = [], struct.unpack_from("<L", data, 4)[0]
    while pos + 16 <= len(data):
        sig, _hs, _hv, size, _t = _OBJ.unpack_from(data, pos)
        assert sig == b"LOBJ" and size >= 32
        out.append((pos, size + size % 4))
        pos += size + size % 4
    assert pos == len(data)
    return out


def row_containers(data: bytes, conts: list[tuple[int, int]]) -> list[tuple[int, ...]]:
    """For each frame object (= frame row, in order), the containers its bytes lie in."""
    stream, bounds = b"", [0]
    for pos, _length in conts:
        method, _usize = struct.unpack_from("<H6xL4x", data, pos + 16)
        size = _OBJ.unpack_from(data, pos)[3]
        payload = data[pos + 32 : pos + size]
        stream += zlib.decompress(payload) if method == 2 else payload
        bounds.append(len(stream))
    out, pos = [], 0
    while pos + 16 <= len(stream):
        sig, _hs, _hv, size, _t = _OBJ.unpack_from(stream, pos)
        assert sig == b"LOBJ"
        a = int(np.searchsorted(bounds, pos, side="right")) - 1
        b = int(np.searchsorted(bounds, pos + size - 1, side="right")) - 1
        out.append(tuple(range(a, b + 1)))
        pos += size + size % 4
    assert len(out) == len(_FRAMES)
    return out


@functools.cache
def _written(level: int) -> tuple[bytes, tuple[tuple[int, int], ...], tuple[tuple[int, ...], ...]]:
    data = _write_blf(_TMP / f"intact{level}.blf", level).read_bytes()
    conts = containers(data)
    return data, tuple(conts), tuple(row_containers(data, conts))


@functools.cache
def _intact(level: int):
    _written(level)
    return read(_TMP / f"intact{level}.blf")


def _read_checked(
    data: bytes,
    level: int,
    *,
    damaged_rows: set[int],
    header_hit: bool,
    required_rows: list[int],
    name: str = "damaged.blf",
    twin_flips: int = 0,
):
    p = _TMP / name
    p.write_bytes(data)
    _intact(level)  # the first read of a process parses the DBC: not part of the bound
    gc.collect()  # garbage of earlier examples is not this read's time
    t0 = time.process_time()
    try:
        rec = read(p)
    except RigtoolsError:
        rec = None
    cpu = time.process_time() - t0
    assert cpu <= MAX_CPU_S_FIXED + MAX_CPU_S_PER_MB * len(data) / 1e6, f"{cpu:.2f} s CPU"
    req = required_samples(_NAMES, _START, _K, required_rows, _TRUTH)
    if rec is None:
        assert header_hit or not any(m.any() for m in req.values()), (
            "refused although intact containers remain"
        )
        return None
    check_against_truth(
        rec,
        _TRUTH,
        "can",
        intact=_intact(level),
        # Absolute indices are known only if the first frame of every channel is there;
        # else the read starts after an unknown number of counter wraps.
        index_modulus=None if _first_frames_required(req) and not header_hit else MODULUS,
        tolerance_samples=_K * len(damaged_rows),
        tolerance_slow=2 * len(damaged_rows),
        required=None if header_hit else req,
        # Intact records lost: none, except that each flip may make a damaged frame a
        # well-formed twin of one intact frame (an identifier or counter bit), which can
        # take its place. Cuts, drops, duplicates and shuffles make no twins.
        tolerance_lost=_K * twin_flips,
    )
    return rec


def _first_frames_required(req: dict[str, np.ndarray]) -> bool:
    return all(m.size and m[0] for m in req.values())


LEVELS = st.sampled_from([-1, 0])  # zlib (python-can's default) and stored containers


# --- cuts and flips ----------------------------------------------------------------------------


def _check_cut(level: int, frac: float) -> None:
    data, conts, rows = _written(level)
    cut = int(frac * len(data))
    whole = {i for i, (pos, length) in enumerate(conts) if pos + length <= cut}
    required = [r for r, cs in enumerate(rows) if set(cs) <= whole]
    damaged = {r for r, cs in enumerate(rows) if not set(cs) <= whole}
    _read_checked(
        data[:cut], level, damaged_rows=damaged, header_hit=cut < _HEADER, required_rows=required
    )


@FAST
@given(level=LEVELS, frac=st.floats(0.0, 1.0))
def test_cut_anywhere_returns_every_complete_container(level, frac):
    _check_cut(level, frac)


def _check_flips(level: int, flips: list[tuple[float, int]]) -> None:
    data, conts, rows = _written(level)
    b = bytearray(data)
    hit: set[int] = set()
    header_hit = False
    starts = np.array([pos for pos, _ in conts])
    for frac, bit in flips:
        at = min(int(frac * len(b)), len(b) - 1)
        b[at] ^= 1 << bit
        if at < _HEADER:
            header_hit = True
        else:
            hit.add(int(np.searchsorted(starts, at, side="right")) - 1)
    damaged = {r for r, cs in enumerate(rows) if hit & set(cs)}
    required = [r for r in range(len(rows)) if r not in damaged]
    _read_checked(
        bytes(b),
        level,
        damaged_rows=damaged,
        header_hit=header_hit,
        required_rows=required,
        twin_flips=len(flips),
    )


_FLIPS = st.lists(st.tuples(st.floats(0.0, 1.0), st.integers(0, 7)), min_size=1, max_size=3)


@FAST
@given(level=LEVELS, flips=_FLIPS)
def test_bit_flips_lose_at_most_the_containers_they_hit(level, flips):
    _check_flips(level, flips)


# --- duplicated, dropped and shuffled containers -----------------------------------------------


def _intact_rows(order: list[int], rows: tuple[tuple[int, ...], ...]) -> list[int]:
    """Rows whose containers all appear in ``order``, consecutively and in their order."""
    pairs = set(itertools.pairwise(order))
    present = set(order)
    out = []
    for r, cs in enumerate(rows):
        if set(cs) <= present and all((a, a + 1) in pairs for a in cs[:-1]):
            out.append(r)
    return out


def _check_containers(level: int, op: str, a: int, width: int, seed: int) -> None:
    data, conts, rows = _written(level)
    n = len(conts)
    a = min(a, n - 1)
    sel = list(range(a, min(n, a + width)))
    order = list(range(n))
    if op == "duplicate":
        order = order[: sel[-1] + 1] + sel + order[sel[-1] + 1 :]
    elif op == "drop":
        order = [c for c in order if c not in set(sel)]
    else:
        perm = np.random.default_rng(seed).permutation(sel).tolist()
        order = order[:a] + perm + order[a + len(sel) :]
    required = _intact_rows(order, rows)
    # A row spanning containers (a, a + 1) is also damaged wherever a copy of ``a`` is not
    # followed by ``a + 1``: its head there joins the wrong bytes into a garbage object.
    broken = {(a, b) for a, b in itertools.pairwise(order) if b != a + 1}
    if order:
        broken.add((order[-1], -1))
    damaged = {r for r in range(len(rows)) if r not in set(required)} | {
        r for r, cs in enumerate(rows) if len(cs) > 1 and any(a == cs[0] for a, _ in broken)
    }
    body = b"".join(data[conts[c][0] : conts[c][0] + conts[c][1]] for c in order)
    new = data[:_HEADER] + body
    _read_checked(new, level, damaged_rows=damaged, header_hit=False, required_rows=required)


@FAST
@given(
    level=LEVELS,
    op=st.sampled_from(["duplicate", "drop", "shuffle"]),
    a=st.integers(0, 40),
    width=st.integers(1, 6),
    seed=st.integers(0, 2**16),
)
def test_duplicated_dropped_and_shuffled_containers(level, op, a, width, seed):
    _check_containers(level, op, a, width, seed)


@pytest.mark.slow
@LONG
@given(
    level=LEVELS,
    frac=st.floats(0.0, 1.0),
    flips=_FLIPS,
    op=st.sampled_from(["duplicate", "drop", "shuffle"]),
    a=st.integers(0, 40),
    width=st.integers(1, 6),
    seed=st.integers(0, 2**16),
)
def test_long_profile(level, frac, flips, op, a, width, seed):
    _check_cut(level, frac)
    _check_flips(level, flips)
    _check_containers(level, op, a, width, seed)


# --- length fields that claim gigabytes --------------------------------------------------------


def _claims() -> list[tuple[str, int, str, int]]:
    """(name, offset, struct format, claimed value) of length fields in the stored file."""
    _, conts, _ = _written(0)
    pos = conts[len(conts) // 2][0]
    first_obj = conts[1][0] + 32  # first object inside the second (stored) container
    return [
        ("header_size", 4, "<L", 0xFFFF_FFF0),
        ("container_size_4GiB", pos + 8, "<L", 0xFFFF_FFF0),
        ("container_size_60MiB", pos + 8, "<L", 60 << 20),
        ("container_uncompressed_size_4GiB", pos + 24, "<L", 0xFFFF_FFF0),
        ("object_size_4GiB", first_obj + 8, "<L", 0xFFFF_FFF0),
        ("object_size_15MiB", first_obj + 8, "<L", 15 << 20),
    ]


@pytest.mark.parametrize("name", [c[0] for c in _claims()])
def test_length_fields_claiming_gigabytes_allocate_nothing_like_it(name):
    data, _, _ = _written(0)
    _, at, fmt, value = next(c for c in _claims() if c[0] == name)
    b = bytearray(data)
    struct.pack_into(fmt, b, at, value)
    p = _TMP / f"claim_{name}.blf"
    p.write_bytes(bytes(b))
    read(_TMP / "intact0.blf")  # warm caches (DBC, imports) outside the measurement
    peak, out = peak_bytes(lambda: read(p))
    bound = ALLOC_MULTIPLE * len(b) + ALLOC_FIXED_BYTES
    assert peak <= bound, f"{name}: peak {peak / 2**20:.1f} MiB > {bound / 2**20:.1f} MiB"
    assert peak < value, f"{name}: allocated what the field claims"
    if not isinstance(out, RigtoolsError):  # the lie is told: counted, or warned about
        rep = out.report  # type: ignore[attr-defined]
        assert rep.has_losses or any("claims" in w for w in rep.warnings), rep.to_dict()


def test_allocation_bound_holds_on_the_intact_file():
    data, _, _ = _written(-1)
    read(_TMP / "intact-1.blf")
    peak, out = peak_bytes(lambda: read(_TMP / "intact-1.blf"))
    assert not isinstance(out, RigtoolsError)
    assert peak <= ALLOC_MULTIPLE * len(data) + ALLOC_FIXED_BYTES


# --- regressions found by the long profile -----------------------------------------------------


def _object_row(data: bytes, conts: tuple[tuple[int, int], ...], at: int) -> int:
    """Row of the frame object that starts at file offset ``at`` (stored containers only)."""
    stream_at, before = -1, 0
    for pos, _length in conts:
        size = _OBJ.unpack_from(data, pos)[3]
        if pos + 32 <= at < pos + size:
            stream_at = before + at - (pos + 32)
        before += size - 32
    starts, p = [], 0
    stream = b"".join(data[pos + 32 : pos + _OBJ.unpack_from(data, pos)[3]] for pos, _ in conts)
    while p + 16 <= len(stream):
        starts.append(p)
        size = _OBJ.unpack_from(stream, p)[3]
        p += size + size % 4
    return starts.index(stream_at)


def test_object_size_lie_inside_a_stored_container_costs_that_object_only():
    """An object size field that lies upwards costs that object, not the objects after it.

    Found by the long profile: an object whose size field claims 4 KiB more swallowed the ~85
    objects after it, counted as one corrupt_object. The walker now spots the object headers
    inside the claimed body and resynchronises there.
    """
    data, conts, rows = _written(0)
    pos = conts[2][0] + 32  # the stream inside container 2 starts here (stored: byte for byte)
    j = data.index(b"LOBJ", pos + 200)
    row = _object_row(data, conts, j)  # the frame object whose size field is damaged
    b = bytearray(data)
    b[j + 9] ^= 0x10  # second byte of the object size: +4096
    rec = _read_checked(
        bytes(b),
        0,
        damaged_rows={row},
        header_hit=False,
        required_rows=[r for r in range(len(rows)) if r != row],
    )
    assert rec is not None and rec.report.rejected["corrupt_object"] == 1


def test_container_size_lie_upwards_loses_nothing():
    """A container size field that lies upwards loses nothing.

    Found by the long profile: a container whose size field claims 4 bytes more read the next
    container's signature as its own; that container was then lost. The overrun is now found
    (a container header inside the body) and the read goes on from there.
    """
    data, conts, rows = _written(-1)
    b = bytearray(data)
    struct.pack_into(
        "<L", b, conts[0][0] + 8, struct.unpack_from("<L", data, conts[0][0] + 8)[0] + 4
    )
    rec = _read_checked(
        bytes(b), -1, damaged_rows=set(), header_hit=False, required_rows=list(range(len(rows)))
    )
    assert rec is not None and not rec.report.has_losses
    assert any("nothing lost" in w for w in rec.report.warnings)


def test_whole_object_straddling_the_parse_buffer_is_not_taken_for_a_size_lie():
    """An object cut by the end of a parse buffer, more data to come, is not scanned for lies.

    Review of issue 12 (minor): the size-lie check scanned the body of an object that ran past
    the buffer; a payload holding a plausible object header (bytes ``LOBJ`` + a sane size)
    then read as a lying size field and a false corrupt_object. Now such an object waits for
    the rest of its bytes; only at the end of the data is it scanned.
    """
    from rigtools.ingest.can.blf_objects import ContainerOrigin, ObjectParser
    from rigtools.ingest.recording import IngestReport

    inner = _OBJ.pack(b"LOBJ", 32, 1, 64, 1)  # a plausible header inside the payload
    size = 200
    obj = _OBJ.pack(b"LOBJ", 32, 1, size, 1) + bytes(16) + inner
    obj += bytes(size - len(obj))
    origin = ContainerOrigin(np.array([0]), np.array([_HEADER]))
    report = IngestReport()
    walker = ObjectParser("x.blf", report, 0.0, 1 << 20)
    assert walker.walk(obj[:120], origin, final=False) is None
    assert walker.stop == 0 and report.n_rejected == 0  # waits for the rest
    walked = walker.walk(obj + _OBJ.pack(b"LOBJ", 32, 1, 48, 1), origin, final=False)
    assert walked is not None and walked[0].tolist() == [0] and report.n_rejected == 0
    cut = IngestReport()
    walker = ObjectParser("x.blf", cut, 0.0, 1 << 20)
    walker.walk(obj[:120], origin, final=True)  # no more data: the size cannot be right
    assert cut.rejected["corrupt_object"] >= 1

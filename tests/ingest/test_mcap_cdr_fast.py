"""The MCAP fast path for per-sample ROS 2 (CDR) streams against the general path.

The general path is the same reader decoding every message on its own (``decode_imu_cdr`` for
``sensor_msgs/msg/Imu``, ``mcap-ros2-support``'s decoder for every other ROS 2 type); the
fast path reads a chunk's messages of one constant layout at once
(:mod:`rigtools.ingest.mcap.cdr`). Every test compares the two on the same file, bit for bit,
including the report (counts, positions, warnings), and checks that the fast path was really
taken where it should be (so an always-declining fast path would fail). Values are also
checked against ``mcap-ros2-support``'s own reader and decoder, an implementation independent
of both rigtools paths.

Which reference must-hold (2) of issue 11 uses: for ``sensor_msgs/msg/Imu`` the fast path must
equal rigtools' general path, :func:`~rigtools.ingest.mcap.ros2.decode_imu_cdr`, bit for bit;
``mcap-ros2-support`` agrees with it on every well-formed payload written here, but differs on
three malformed kinds: PL_CDR encapsulation (rigtools rejects, mcap-ros2-support decodes),
invalid UTF-8 in ``frame_id`` (rigtools decodes, mcap-ros2-support raises) and a payload cut
right after ``linear_acceleration`` (rigtools decodes, mcap-ros2-support raises). For every
other type the general path is ``mcap-ros2-support``'s decoder itself.
"""

from __future__ import annotations

import struct
import zlib
from pathlib import Path
from typing import Any

import mcap_layout
import numpy as np
import pytest
from cdr_paths import (
    FS,
    T0_NS,
    both_paths,
    cdr_encode,
    imu_accel,
    imu_file,
    imu_rows,
    imu_stamps,
    lay_out,
    raw_writer,
)
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from realdata_path import REALDATA

from rigtools.demo.mcap_writer import imu_cdr_payloads, write_imu_cdr_mcap, write_imu_mcap
from rigtools.ingest.layout import ChannelMapping, SlowSpec, UniformSpec
from rigtools.ingest.mcap.cdr import Ros2BlockDecoder, decode_imu_cdr_many
from rigtools.ingest.mcap.container import ContainerScanner
from rigtools.ingest.mcap.decoders import get_field, message_stamp_ns
from rigtools.ingest.mcap.ros2 import decode_imu_cdr
from rigtools.ingest.mcap.signal_handlers import numeric_array
from rigtools.ingest.recording import IngestReport

ROSBAG2 = REALDATA / "mcap-rosbag2"


# --- an independent reference: mcap's reader with mcap-ros2-support's decoder ---------------


def _imu_reference(path: Path, topic: str = "/imu") -> tuple[np.ndarray, np.ndarray]:
    """Header stamps (ns) and accelerations by mcap's reader with mcap-ros2-support's decoder."""
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory

    st_, acc = [], []
    with open(path, "rb") as f:
        for _s, _c, _m, d in make_reader(
            f, decoder_factories=[DecoderFactory()]
        ).iter_decoded_messages(topics=[topic], log_time_order=False):
            st_.append(d.header.stamp.sec * 1_000_000_000 + d.header.stamp.nanosec)
            la = d.linear_acceleration
            acc.append((la.x, la.y, la.z))
    return np.asarray(st_, np.int64), np.asarray(acc, np.float64)


# --- Imu files ------------------------------------------------------------------------------


@pytest.mark.parametrize("big_endian", [False, True])
@pytest.mark.parametrize("compression", ["zstd", "lz4", "none"])
def test_imu_stream_equals_general_path_and_mcap_ros2(
    monkeypatch, tmp_path, big_endian, compression
):
    n = 6000
    acc = imu_accel(n)
    acc[5, 0] = np.nan  # a NaN sample is kept as received (the builder marks it invalid)
    acc[7, 1] = -0.0
    p = write_imu_cdr_mcap(
        tmp_path / "imu.mcap",
        imu_stamps(n),
        acc,
        big_endian=big_endian,
        compression=compression,
        chunk_size=64 << 10,
        scalars={"/slow/temp": (np.arange(0, 6, 0.5) + T0_NS * 1e-9, np.arange(12.0))},
    )
    (rep, chans, slow), _whole = both_paths(monkeypatch, tmp_path, p.read_bytes())[0]
    stamps, ref = _imu_reference(p)
    assert stamps.tolist() == imu_stamps(n).tolist()  # the writer wrote what it was given
    np.testing.assert_array_equal(ref.view(np.int64), acc.view(np.int64))
    for k, axis in enumerate("xyz"):
        ch = chans[f"/imu/linear_acceleration.{axis}"]
        assert ch.sample_rate_Hz == FS
        assert ch.values.view(np.int64).tolist() == ref[:, k].view(np.int64).tolist()
    assert slow["/slow/temp"].values.tolist() == list(np.arange(12.0))
    assert rep["decoded"] == n + 12


def test_the_fast_path_is_taken_for_every_uniform_chunk(monkeypatch, tmp_path):
    n = 5000
    p = write_imu_cdr_mcap(
        tmp_path / "imu.mcap",
        imu_stamps(n),
        imu_accel(n),
        chunk_size=32 << 10,
        scalars={"/slow/a": (np.arange(0, 5, 0.01) + T0_NS * 1e-9, np.arange(500.0))},
    )
    _out, spy = both_paths(monkeypatch, tmp_path, p.read_bytes())
    n_chunks = len(mcap_layout.chunks(p.read_bytes()))
    # every chunk: the Imu block and (in most chunks) a Float64 block, none declined
    assert spy.taken >= n_chunks and spy.declined == 0


def test_imu_written_by_mcap_ros2_itself(monkeypatch, tmp_path):
    """The reference writer (mcap-ros2-support) rather than rigtools' array writer."""
    n = 1500
    t = imu_stamps(n) * 1e-9
    p = write_imu_mcap(
        tmp_path / "ros.mcap",
        t,
        imu_accel(n, 3),
        chunk_size=16 << 10,
        frame_id="base_link_imu",
        log_delay_s=0.002,
        scalars={"/slow/speed": (np.arange(0, 1.5, 0.1) + t[0], np.arange(15.0) * 10)},
    )
    ((_rep, chans, _slow), _w), spy = both_paths(monkeypatch, tmp_path, p.read_bytes())
    assert spy.taken > 0 and spy.declined == 0
    _stamps_ref, ref = _imu_reference(p)
    assert chans["/imu/linear_acceleration.z"].values.tolist() == ref[:, 2].tolist()


def test_interleaved_channels_evenly_and_unevenly(monkeypatch, tmp_path):
    n = 4000
    stamps = imu_stamps(n, 2 * FS)
    pay = imu_rows(stamps, imu_accel(n))
    log = stamps.tolist()
    rng = np.random.default_rng(5)
    extra = [
        (int(t), b"\0\1\0\0" + struct.pack("<d", float(v)))
        for t, v in zip(
            np.sort(rng.choice(stamps, 60, replace=False)) + 1, rng.standard_normal(60), strict=True
        )
    ]
    p = imu_file(tmp_path / "a.mcap", pay, log, n_imu_channels=2)  # taking turns
    ((_rep, chans, _s), _w), spy = both_paths(monkeypatch, tmp_path, p.read_bytes())
    assert spy.taken > 0 and spy.declined == 0
    assert set(chans) == {f"/imu{k}/linear_acceleration.{a}" for k in ("", "1") for a in "xyz"}
    p = imu_file(tmp_path / "b.mcap", pay, log, n_imu_channels=2, extra=extra)  # uneven
    ((_rep, chans, slow), _w), spy = both_paths(monkeypatch, tmp_path, p.read_bytes())
    assert spy.taken > 0 and spy.declined == 0
    assert len(slow["/slow/x"]) == 60


def test_channels_taking_turns_with_different_layouts(monkeypatch, tmp_path):
    """Two Imu topics of different frame_id lengths alternating.

    Records of two lengths take turns: the walk reads them as a pattern, each channel's
    block has one layout.
    """
    n = 4000
    stamps = imu_stamps(n, 2 * FS)
    acc = imu_accel(n, 12)
    pay = [
        imu_rows(stamps[i : i + 1], acc[i : i + 1], frame_id="a" if i % 2 else "imu_link_b")[0]
        for i in range(n)
    ]
    p = imu_file(tmp_path / "t.mcap", pay, stamps.tolist(), n_imu_channels=2)
    ((_rep, chans, _s), _w), spy = both_paths(monkeypatch, tmp_path, p.read_bytes())
    assert spy.taken > 0 and spy.declined == 0
    _st, ref = _imu_reference(p, "/imu1")
    assert chans["/imu1/linear_acceleration.x"].values.tolist() == ref[:, 0].tolist()


def test_frame_id_lengths_varying_across_and_within_chunks(monkeypatch, tmp_path):
    """Uniform chunks take the fast path with their own frame_id length; mixed chunks fall back."""
    n = 3000
    stamps = imu_stamps(n)
    acc = imu_accel(n, 1)
    names = ["imu", "imu_link", "a_much_longer_frame_name", ""]
    pay = []
    for i in range(n):
        # blocks of 700 messages per name (several chunks each), and a stretch that flips
        # name every message (mixed chunks)
        name = names[(i // 700) % 4] if i < 2400 else names[i % 2]
        pay += imu_rows(stamps[i : i + 1], acc[i : i + 1], frame_id=name)
    p = imu_file(tmp_path / "v.mcap", pay, stamps.tolist())
    ((_rep, chans, _s), _w), spy = both_paths(monkeypatch, tmp_path, p.read_bytes())
    assert spy.taken > 0 and spy.declined > 0
    _st, ref = _imu_reference(p)
    assert chans["/imu/linear_acceleration.y"].values.tolist() == ref[:, 1].tolist()


@pytest.mark.parametrize(
    "odd",
    [
        "longer_frame",
        "short_payload",
        "bad_encapsulation",
        "big_endian_one",
        "trailing_byte",
        "absurd_frame_length",
    ],
)
def test_one_odd_message_in_a_chunk(monkeypatch, tmp_path, odd):
    n = 2000
    stamps = imu_stamps(n)
    acc = imu_accel(n, 2)
    pay = imu_rows(stamps, acc)
    k = 1234
    if odd == "longer_frame":
        pay[k] = imu_rows(stamps[k : k + 1], acc[k : k + 1], frame_id="imu_link_2")[0]
    elif odd == "short_payload":
        pay[k] = pay[k][:100]
    elif odd == "bad_encapsulation":
        pay[k] = b"\x00\x07" + pay[k][2:]
    elif odd == "big_endian_one":
        pay[k] = imu_rows(stamps[k : k + 1], acc[k : k + 1], big_endian=True)[0]
    elif odd == "trailing_byte":
        pay[k] = pay[k] + b"\0"
    elif odd == "absurd_frame_length":
        pay[k] = pay[k][:12] + struct.pack("<I", 0xFFFFFFF0) + pay[k][16:]
    p = imu_file(tmp_path / "o.mcap", pay, stamps.tolist())
    ((rep, _c, _s), _w), spy = both_paths(monkeypatch, tmp_path, p.read_bytes())
    assert spy.taken > 0 and spy.declined >= 1  # only the odd message's chunk fell back
    bad = odd in ("short_payload", "bad_encapsulation", "absurd_frame_length")
    assert rep["rejected"] == ({"decode_error": 1} if bad else {})


def test_stamps_with_gaps_and_duplicates_recorded_never_filled(monkeypatch, tmp_path):
    n = 3000
    stamps = imu_stamps(n)
    keep = np.ones(n, bool)
    keep[1000:1010] = False  # 10 samples lost
    keep[2500] = False
    idx = np.flatnonzero(keep)
    idx = np.insert(idx, 1500, idx[1499])  # one message sent twice
    s = stamps[idx]
    acc = imu_accel(n, 4)[idx]
    p = imu_file(tmp_path / "g.mcap", imu_rows(s, acc), (s + 5000).tolist())
    ((_rep, chans, _s), whole), spy = both_paths(monkeypatch, tmp_path, p.read_bytes())
    assert spy.taken > 0 and spy.declined == 0
    ch = chans["/imu/linear_acceleration.x"]
    assert len(ch) == n and ch.sample_rate_Hz == FS
    assert np.flatnonzero(~ch.valid).tolist() == [*range(1000, 1010), 2500]
    assert np.isnan(ch.values[~ch.valid]).all()  # gaps stay NaN: nothing interpolated
    gaps = [
        (g["start_index"], g["n_missing"])
        for g in whole[0]["gaps"]
        if g["channel"] == "/imu/linear_acceleration.x"
    ]
    assert gaps == [(1000, 10), (2500, 1)]
    # the repeated message is one duplicate sample per axis
    assert whole[0]["rejected"] == {"duplicate_sample": 3}


def test_all_zero_header_stamps_use_log_times_on_both_paths(monkeypatch, tmp_path):
    n = 1200
    pay = imu_rows(np.zeros(n, np.int64), imu_accel(n, 6))
    p = imu_file(tmp_path / "z.mcap", pay, imu_stamps(n).tolist())
    ((rep, chans, _s), _w), spy = both_paths(monkeypatch, tmp_path, p.read_bytes())
    assert spy.taken > 0
    assert any("all zero" in w for w in rep["warnings"])
    assert chans["/imu/linear_acceleration.x"].sample_rate_Hz == FS


# --- damage -------------------------------------------------------------------------------


def _damage(data: bytes, kind: str) -> bytes:
    out = bytearray(data)
    cs = mcap_layout.chunks(data)
    c = cs[2]
    if kind == "wrong_crc":
        struct.pack_into("<I", out, c["crc_at"], 0x12345678)
    elif kind == "flip_in_records":
        out[c["records_at"] + c["records_len"] // 2] ^= 0x01
    elif kind == "cut_in_chunk":
        return bytes(out[: c["pos"] + 9 + c["records_len"] // 2])
    elif kind == "absurd_size":
        struct.pack_into("<Q", out, c["usize_at"], 2**62)
    elif kind == "chunk_length_past_end":
        struct.pack_into("<Q", out, c["pos"] + 1, len(out))
    elif kind in ("message_length_absurd", "message_length_short"):
        # uncompressed chunk: a Message record's length inside it, CRC made right again
        assert c["compression"] == ""
        rec_at = c["records_at"]
        pos, end = rec_at, rec_at + c["records_len"]
        seen = 0
        while pos < end:
            op, length = struct.unpack_from("<BQ", out, pos)
            if op == 0x05:
                seen += 1
                if seen == 7:
                    new = 2**40 if kind == "message_length_absurd" else length - 30
                    struct.pack_into("<Q", out, pos + 1, new)
                    break
            pos += 9 + length
        struct.pack_into("<I", out, c["crc_at"], zlib.crc32(bytes(out[rec_at:end])) & 0xFFFFFFFF)
    return bytes(out)


@pytest.fixture(scope="module")
def damage_sources(tmp_path_factory) -> dict[str, bytes]:
    d = tmp_path_factory.mktemp("cdr_damage")
    n = 3000
    sc = {"/slow/t": (np.arange(0, 3, 0.1) + T0_NS * 1e-9, np.arange(30.0))}
    out = {}
    for comp in ("zstd", "none"):
        out[comp] = write_imu_cdr_mcap(
            d / f"{comp}.mcap",
            imu_stamps(n),
            imu_accel(n, 7),
            compression=comp,
            chunk_size=48 << 10,
            scalars=sc,
        ).read_bytes()
    return out


@pytest.mark.parametrize(
    "kind",
    [
        "intact",
        "wrong_crc",
        "flip_in_records",
        "cut_in_chunk",
        "absurd_size",
        "chunk_length_past_end",
        "message_length_absurd",
        "message_length_short",
    ],
)
@pytest.mark.parametrize("source", ["file", "stream"])
def test_damage_counts_and_keeps_the_same(monkeypatch, tmp_path, damage_sources, kind, source):
    comp = "none" if kind.startswith("message_length") else "zstd"
    data = _damage(damage_sources[comp], kind)
    ((rep, chans, _s), _w), spy = both_paths(monkeypatch, tmp_path, data, source=source)
    assert spy.taken > 0
    if kind == "intact":
        assert not rep["rejected"] and len(chans["/imu/linear_acceleration.x"]) == 3000
    elif kind == "chunk_length_past_end" and not rep["rejected"]:
        # a reader that finds the chunk's true end from its own header recovers it all,
        # but must say the length was wrong
        assert rep["warnings"] and len(chans["/imu/linear_acceleration.x"]) == 3000
    else:
        assert rep["rejected"]


def test_unindexed_file_without_summary(monkeypatch, tmp_path):
    from mcap.writer import IndexType

    n = 2500
    stamps = imu_stamps(n)
    p = imu_file(
        tmp_path / "u.mcap",
        imu_rows(stamps, imu_accel(n, 8)),
        stamps.tolist(),
        index_types=IndexType.NONE,
        repeat_channels=False,
        repeat_schemas=False,
        use_summary_offsets=False,
        use_statistics=False,
    )
    data = p.read_bytes()
    ((rep, chans, _s), _w), spy = both_paths(monkeypatch, tmp_path, data, source="stream")
    assert spy.taken > 0 and not rep["rejected"]
    assert len(chans["/imu/linear_acceleration.x"]) == n
    # cut short after a few chunks (no summary to lean on): the same intact part either way
    cs = mcap_layout.chunks(data)
    ((rep, chans, _s), _w), _spy = both_paths(
        monkeypatch, tmp_path, data[: cs[3]["pos"] + 50], source="stream"
    )
    assert 0 < len(chans["/imu/linear_acceleration.x"]) < n


# --- mapped fields of any ROS 2 type --------------------------------------------------------

PROBE_SCHEMA = """\
std_msgs/Header header
float32 f32
int64 i64
uint64 u64
bool flag
char c
int8[] small
float64[3] triple
string label
geometry_msgs/Vector3[] vecs
uint16 tail
================================================================================
MSG: std_msgs/Header
builtin_interfaces/Time stamp
string frame_id
================================================================================
MSG: builtin_interfaces/Time
int32 sec
uint32 nanosec
================================================================================
MSG: geometry_msgs/Vector3
float64 x
float64 y
float64 z
"""
PROBE_NAME = "rig_msgs/msg/Probe"
PROBE_PATHS = [
    "f32",
    "i64",
    "u64",
    "flag",
    "c",
    "triple",
    "triple.1",
    "triple[2]",
    "vecs.0.y",
    "tail",
    "header.stamp.nanosec",
]


_f32 = st.floats(width=32, allow_nan=False)


@st.composite
def _probe(draw: Any, n_small: int, n_vecs: int, label: str, frame: str) -> dict:
    i64 = st.integers(-(2**63), 2**63 - 1)
    return {
        "header": {
            "stamp": {
                "sec": draw(st.integers(0, 2**31 - 1)),
                "nanosec": draw(st.integers(0, 999_999_999)),
            },
            "frame_id": frame,
        },
        "f32": draw(_f32),
        "i64": draw(i64),
        "u64": draw(st.integers(0, 2**64 - 1)),
        "flag": draw(st.booleans()),
        "c": draw(st.integers(-128, 127)),
        "small": draw(st.lists(st.integers(-128, 127), min_size=n_small, max_size=n_small)),
        "triple": draw(st.lists(st.floats(), min_size=3, max_size=3)),
        "label": label,
        "vecs": [{"x": draw(st.floats()), "y": draw(st.floats()), "z": 0.0} for _ in range(n_vecs)],
        "tail": draw(st.integers(0, 65535)),
    }


@st.composite
def _probe_block(draw: Any) -> tuple[list[bytes], bool]:
    big = draw(st.booleans())
    m = draw(st.integers(1, 10))
    same = draw(st.booleans())
    shape = (
        draw(st.integers(0, 4)),
        draw(st.integers(1, 3)),
        draw(st.sampled_from(["", "a", "probe", "zürich"])),
        draw(st.sampled_from(["", "imu_link", "base"])),
    )
    msgs = []
    for _ in range(m):
        if not same and draw(st.booleans()):
            shape = (
                draw(st.integers(0, 4)),
                draw(st.integers(1, 3)),
                draw(st.sampled_from(["", "a", "probe", "zürich", "ZÜRICH"])),
                draw(st.sampled_from(["", "imu_link", "base", "bbse"])),
            )
        msgs.append(cdr_encode(PROBE_NAME, PROBE_SCHEMA, draw(_probe(*shape)), big))
    return msgs, same


def _general_columns(msgs: list[bytes], paths: list[str]) -> tuple[list[Any], list[Any]]:
    from mcap_ros2._dynamic import generate_dynamic

    dec = generate_dynamic(PROBE_NAME, PROBE_SCHEMA)[PROBE_NAME]
    objs = [dec(m) for m in msgs]
    vals = [np.stack([numeric_array(get_field(o, p)) for o in objs]) for p in paths]
    return vals, [message_stamp_ns(o) for o in objs]


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(block=_probe_block(), even=st.booleans(), gap=st.integers(0, 9), data=st.data())
def test_block_columns_equal_mcap_ros2_message_by_message(block, even, gap, data):
    msgs, same = block
    gaps = (
        [gap] * len(msgs)
        if even
        else data.draw(st.lists(st.integers(0, 9), min_size=len(msgs), max_size=len(msgs)))
    )
    buf, s, e = lay_out(msgs, gaps)
    got = Ros2BlockDecoder(PROBE_NAME, PROBE_SCHEMA).columns(memoryview(buf), s, e, PROBE_PATHS)
    want, stamps = _general_columns(msgs, PROBE_PATHS)
    if same or (
        all(len(m) == len(msgs[0]) and m[:4] == msgs[0][:4] for m in msgs)
        and len({_shape_words(m) for m in msgs}) == 1
    ):
        assert got is not None  # one layout: the fast path must not decline
    if got is None:
        return
    assert got.stamp_ns is not None and got.stamp_ns.tolist() == stamps
    for g, w in zip(got.values, want, strict=True):
        assert g.shape == (len(msgs), w.reshape(len(msgs), -1).shape[1])
        assert g.reshape(-1).view(np.int64).tolist() == w.reshape(-1).view(np.int64).tolist()


def _shape_words(msg: bytes) -> tuple:
    """The length words and string bytes of a Probe payload (an independent small walk)."""
    from mcap_ros2._dynamic import generate_dynamic

    o = generate_dynamic(PROBE_NAME, PROBE_SCHEMA)[PROBE_NAME](msg)
    return (o.header.frame_id, len(o.small), o.label, len(o.vecs))


@pytest.mark.parametrize("big_endian", [False, True])
def test_mapped_fields_read_equal_on_both_paths(monkeypatch, tmp_path, big_endian):
    rng = np.random.default_rng(9)
    n = 1500
    with open(tmp_path / "p.mcap", "wb") as f:
        w = raw_writer(f, 16 << 10)
        sid = w.register_schema(PROBE_NAME, "ros2msg", PROBE_SCHEMA.encode())
        cid = w.register_channel("/probe", "cdr", sid)
        for i in range(n):
            t = int(T0_NS + i * 1_000_000)
            msg = {
                "header": {
                    "stamp": {"sec": t // 10**9, "nanosec": t % 10**9},
                    "frame_id": "probe_link",
                },
                "f32": float(np.float32(rng.standard_normal())),
                "i64": int(i) - 700,
                "u64": 2**64 - 1 - i,
                "flag": bool(i % 3),
                "c": -5,
                "small": [1, 2],
                "triple": rng.standard_normal(3).tolist(),
                "label": "L" if i < 900 else "M",
                "vecs": [{"x": 1.0, "y": float(i), "z": 0.0}],
                "tail": i % 65536,
            }
            w.add_message(
                cid,
                log_time=t + 7,
                publish_time=t,
                sequence=i,
                data=cdr_encode(PROBE_NAME, PROBE_SCHEMA, msg, big_endian),
            )
        w.finish()
    mapping = ChannelMapping(
        uniform=(
            UniformSpec("tri", 3000.0, topic="/probe", field="triple", unit="m"),
            UniformSpec("vy", 1000.0, topic="/probe", field="vecs.0.y", unit="m"),
        ),
        slow=(
            SlowSpec("big", topic="/probe", field="u64", unit="1"),
            SlowSpec("flag", topic="/probe", field="flag", unit="1"),
            SlowSpec("f", topic="/probe", field="f32", unit="1", scale=2.0, offset=1.0),
        ),
    )
    data = (tmp_path / "p.mcap").read_bytes()
    ((rep, chans, slow), _w), spy = both_paths(monkeypatch, tmp_path, data, mapping)
    assert spy.taken > 0 and spy.declined == 0
    assert len(chans["tri"]) == 3 * n and chans["vy"].values.tolist() == list(range(n))
    assert slow["big"].values[0] == float(2**64 - 1)
    assert rep["decoded"] == n


# --- real rosbag2 bags ----------------------------------------------------------------------


def _bags() -> list:
    if not ROSBAG2.is_dir():
        return [pytest.param(None, marks=pytest.mark.skip(reason=f"{ROSBAG2} is absent"))]
    return [pytest.param(p, id=p.name) for p in sorted(ROSBAG2.rglob("*.mcap"))]


@pytest.mark.parametrize("path", _bags())
def test_rosbag2_every_numeric_field_of_every_block(path):
    """Every numeric field of every chunk's block of every CDR channel of a real bag.

    The fast columns equal mcap-ros2-support's decoding of each message; blocks whose
    layouts vary are declined.
    """
    from mcap_ros2._dynamic import generate_dynamic

    rep = IngestReport(units="messages")
    with open(path, "rb") as f:
        sc = ContainerScanner(f, str(path), rep)
        for blk in sc.blocks():
            for cid, g in blk.by_channel():
                ch = sc.channels[cid]
                schema = sc.schemas.get(ch.schema_id)
                if ch.message_encoding != "cdr" or schema is None or g.buf is None:
                    continue
                text = schema.data.decode()
                try:
                    dec = generate_dynamic(schema.name, text)[schema.name]
                except Exception:  # service events: the general path counts bad_schema
                    with pytest.raises(ValueError):
                        Ros2BlockDecoder(schema.name, text)
                    continue
                blockdec = Ros2BlockDecoder(schema.name, text)
                msgs = [bytes(m[4]) for m in g.messages()]
                lay = blockdec.layout(msgs[0])
                assert lay is not None  # every message of these bags decodes
                paths = [
                    ".".join(k)
                    for k, leaf in lay.leaves.items()
                    if leaf.type != "string"
                    and not (leaf.array and leaf.elems == 0)
                    and not (leaf.array and leaf.type in ("uint8", "byte"))
                ]
                got = blockdec.columns(g.buf, g.start, g.end, paths)
                if len({len(m) for m in msgs}) > 1:
                    assert got is None
                    continue
                objs = [dec(m) for m in msgs]
                if got is None:  # only when length words or strings differ
                    assert len({_words(blockdec, m) for m in msgs}) > 1
                    continue
                for p, col in zip(paths, got.values, strict=True):
                    want = np.stack([numeric_array(get_field(o, p)) for o in objs])
                    assert (
                        col.reshape(-1).view(np.int64).tolist()
                        == want.reshape(-1).view(np.int64).tolist()
                    ), p
                if got.stamp_ns is not None:
                    assert got.stamp_ns.tolist() == [message_stamp_ns(o) for o in objs]


def _words(blockdec: Ros2BlockDecoder, msg: bytes) -> tuple:
    lay = blockdec.layout(msg)
    assert lay is not None
    return tuple(msg[w : w + 4] for w in lay.words) + tuple(msg[a : a + k] for a, k in lay.strings)


@pytest.mark.parametrize(
    ("bag", "topic", "fields"),
    [
        (
            "rosbag2_py/test/resources/mcap/convert_a/rewriter_a_0.mcap",
            "b_basictypes",
            [
                "bool_value",
                "byte_value",
                "char_value",
                "float32_value",
                "float64_value",
                "int8_value",
                "uint8_value",
                "int16_value",
                "uint16_value",
                "int32_value",
                "uint32_value",
                "int64_value",
                "uint64_value",
            ],
        ),
        (
            "rosbag2_tests/resources/mcap/cdr_test/cdr_test_0.mcap",
            "/array_topic",
            ["float64_values_default.2", "int32_values.1", "bool_values.0"],
        ),
        (
            "rosbag2_transport/test/resources/mcap/test_bag_for_seek/test_bag_for_seek_0.mcap",
            "topic1",
            ["int32_value", "float64_value"],
        ),
    ],
)
def test_rosbag2_mapped_constant_layout_fields_take_the_fast_path(
    monkeypatch, tmp_path, bag, topic, fields
):
    path = ROSBAG2 / bag
    if not path.is_file():
        pytest.skip(f"{path} is absent")
    mapping = ChannelMapping(
        slow=tuple(SlowSpec(f"s.{f}", topic=topic, field=f, unit="1") for f in fields)
    )
    ((rep, _c, slow), _w), spy = both_paths(monkeypatch, tmp_path, path.read_bytes(), mapping)
    assert spy.taken > 0 and spy.declined == 0
    assert set(slow) == {f"s.{f}" for f in fields}
    assert rep["decoded"] > 0


@pytest.mark.parametrize("path", _bags())
def test_rosbag2_whole_bags_read_the_same(monkeypatch, tmp_path, path):
    both_paths(monkeypatch, tmp_path, path.read_bytes())


def test_varying_strings_fall_back_on_real_bag(monkeypatch, tmp_path):
    """wbag_0's std_msgs/String payloads vary in length: a block reader declines them."""
    path = ROSBAG2 / "rosbag2_py/test/resources/mcap/wbag/wbag_0.mcap"
    if not path.is_file():
        pytest.skip(f"{path} is absent")
    rep = IngestReport(units="messages")
    declined = 0
    with open(path, "rb") as f:
        sc = ContainerScanner(f, str(path), rep)
        for blk in sc.blocks():
            for cid, g in blk.by_channel():
                schema = sc.schemas[sc.channels[cid].schema_id]
                lens = (g.end - g.start).tolist()
                got = Ros2BlockDecoder(schema.name, schema.data.decode()).columns(
                    g.buf, g.start, g.end, []
                )
                if len(set(lens)) > 1:
                    assert got is None
                    declined += 1
    assert declined > 0


# --- the Imu reader alone -------------------------------------------------------------------


@settings(max_examples=100, deadline=None)
@given(
    n=st.integers(1, 12),
    frame=st.text(max_size=12),
    big=st.booleans(),
    gaps=st.lists(st.integers(0, 7), min_size=12, max_size=12),
    vals=st.lists(st.floats(), min_size=36, max_size=36),
    secs=st.lists(st.integers(-(2**31), 2**31 - 1), min_size=12, max_size=12),
)
def test_imu_block_equals_decode_imu_cdr(n, frame, big, gaps, vals, secs):
    stamps = np.asarray(secs[:n], np.int64) * 1_000_000_000 + 999_999_999
    acc = np.asarray(vals[: 3 * n], np.float64).reshape(n, 3)
    msgs = [r.tobytes() for r in imu_cdr_payloads(stamps, acc, frame_id=frame, big_endian=big)]
    buf, s, e = lay_out(msgs, gaps)
    got = decode_imu_cdr_many(memoryview(buf), s, e)
    assert got is not None
    want = [decode_imu_cdr(m) for m in msgs]
    assert got.stamp_ns.tolist() == [w.stamp_ns for w in want] == stamps.tolist()
    assert (
        got.accel.view(np.int64).tolist()
        == np.asarray([w[1:] for w in want], np.float64).view(np.int64).tolist()
    )


# --- hostile schemas ------------------------------------------------------------------------


@pytest.mark.parametrize(
    "text",
    [
        "a/B child\nfloat64 x\n",
        "a/B[] kids\nfloat64 x\n",
        "wstring w\nfloat64 x\n",
        "float64[] xs\nfloat64 x\n",
    ],
)
def test_hostile_layouts_are_left_to_the_general_decoder(monkeypatch, tmp_path, text):
    """Layouts the general decoder refuses are declined, and counted alike.

    Self-nesting types (the general decoder exhausts the recursion limit), a wstring (it
    refuses), an absurd sequence length (it reads past the end).
    """
    from mcap_ros2._dynamic import generate_dynamic

    payload = b"\0\1\0\0" + struct.pack("<I", 0x7FFFFFFF) * 4 + b"\0" * 16
    assert Ros2BlockDecoder("a/msg/B", text).layout(payload) is None
    with pytest.raises((RecursionError, NotImplementedError, struct.error)):
        generate_dynamic("a/msg/B", text)["a/msg/B"](payload)
    with open(tmp_path / "h.mcap", "wb") as f:
        w = raw_writer(f, 4096)
        cid = w.register_channel(
            "/h", "cdr", w.register_schema("a/msg/B", "ros2msg", text.encode())
        )
        for i in range(50):
            w.add_message(cid, log_time=T0_NS + i, publish_time=T0_NS + i, sequence=i, data=payload)
        w.finish()
    mapping = ChannelMapping(slow=(SlowSpec("x", topic="/h", field="x", unit="1"),))
    ((rep, _c, _s), _w), spy = both_paths(
        monkeypatch, tmp_path, (tmp_path / "h.mcap").read_bytes(), mapping
    )
    assert spy.taken == 0 and spy.declined > 0
    assert rep["rejected"] == {"decode_error": 50}


@settings(max_examples=60, deadline=None)
@given(
    vals=st.lists(st.floats(), min_size=1, max_size=20),
    gaps=st.lists(st.integers(0, 9), min_size=20, max_size=20),
    big=st.booleans(),
)
def test_small_payloads_gathered_whole_equal_mcap_ros2(vals, gaps, big):
    """Float64 payloads (12 bytes) at uneven distances: gathered whole, read as decoded."""
    from mcap_ros2._dynamic import generate_dynamic

    msgs = [cdr_encode("std_msgs/msg/Float64", "float64 data\n", {"data": v}, big) for v in vals]
    buf, s, e = lay_out(msgs, gaps)
    got = Ros2BlockDecoder("std_msgs/msg/Float64", "float64 data\n").scalar_many(
        memoryview(buf), s, e, "data"
    )
    dec = generate_dynamic("std_msgs/msg/Float64", "float64 data\n")["std_msgs/msg/Float64"]
    want = np.asarray([float(dec(m).data) for m in msgs], np.float64)
    assert got is not None
    assert got.view(np.int64).tolist() == want.view(np.int64).tolist()

"""The checks of the MCAP CDR fast path, and both clocks of a per-sample stream.

Each block test builds a block of CDR payloads that the fast path's layout checks exist for
(encapsulation headers that differ, equal sizes with different length words, invalid UTF-8
in a later message, ``uint8[]`` fields, bool bytes other than 0/1, stamps outside a header,
``nanosec`` above 2^31) and compares :meth:`Ros2BlockDecoder.columns` with the general path's
reading, message by message, of ``mcap-ros2-support``'s decoder (the reference of must-hold
(2) of issue 11 for every type but Imu); the fast path may decline, never answer otherwise.
Imu blocks are compared with :func:`~rigtools.ingest.mcap.ros2.decode_imu_cdr`, which the
general path of the Imu handler uses; where it and ``mcap-ros2-support`` differ (PL_CDR,
invalid UTF-8 ``frame_id``, a payload cut after ``linear_acceleration``) the general path
of rigtools is the reference, since the fast path must equal it bit for bit.

The clock tests read an Imu stream whose log times lag the header stamps by a known delay
(5 us, written so): the delay must come out as the second clock's ``offset_s`` whichever
clock places the channel.
"""

from __future__ import annotations

import dataclasses
import struct
import warnings
from typing import Any

import cdr_paths
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

from rigtools.demo.mcap_writer import imu_cdr_payloads, write_imu_cdr_mcap
from rigtools.errors import MappingError
from rigtools.ingest import read
from rigtools.ingest.layout import ChannelMapping, SlowSpec, UniformSpec
from rigtools.ingest.mcap import decoders as mcap_decoders
from rigtools.ingest.mcap import reader as mcap_reader
from rigtools.ingest.mcap.cdr import Ros2BlockDecoder, decode_imu_cdr_many, path_parts
from rigtools.ingest.mcap.decoders import get_field, message_stamp_ns
from rigtools.ingest.mcap.ros2 import decode_imu_cdr
from rigtools.ingest.mcap.signal_handlers import Slabs, Thinned, numeric_array

# --- blocks against mcap-ros2-support, message by message -----------------------------------


def _general(name: str, text: str, msgs: list[bytes], paths: list[str]) -> list[Any]:
    """Per message: the fields as ``numeric_array`` makes them and the stamp, or ``None``."""
    from mcap_ros2._dynamic import generate_dynamic

    dec = generate_dynamic(name, text)[name]
    out: list[Any] = []
    for m in msgs:
        try:
            o = dec(bytes(m))
            vals = [numeric_array(get_field(o, p)) for p in paths]
        except Exception:  # undecodable, or no such field: the general path rejects it
            out.append(None)
            continue
        out.append((vals, message_stamp_ns(o)))
    return out


def _agree(name: str, text: str, msgs: list[bytes], paths: list[str], gap: int = 0) -> Any:
    """The fast columns of the block, asserted equal (bits) to the general reading if given."""
    buf, s, e = lay_out(msgs, [gap] * len(msgs))
    got = Ros2BlockDecoder(name, text).columns(memoryview(buf), s, e, paths)
    want = _general(name, text, msgs, paths)
    if got is None:
        return None
    for i, w in enumerate(want):
        assert w is not None, f"message {i}: the general path rejects it, the fast path read it"
        vals, stamp = w
        assert all(v is not None for v in vals), f"message {i}: not numeric on the general path"
        for g, v in zip(got.values, vals, strict=True):
            assert g[i].view(np.int64).tolist() == v.view(np.int64).tolist(), (i, g[i], v)
        assert (None if got.stamp_ns is None else int(got.stamp_ns[i])) == stamp
    return got


F64 = ("std_msgs/msg/Float64", "float64 data\n")


def test_encapsulation_header_differs_within_block():
    """A little- and a big-endian message of one length: read per message, never one way."""
    msgs = [cdr_encode(*F64, {"data": 1.5}, False), cdr_encode(*F64, {"data": 1.5}, True)]
    assert len(msgs[0]) == len(msgs[1]) and msgs[0][:4] != msgs[1][:4]
    assert _agree(*F64, msgs, ["data"]) is None
    # the same byte order throughout is read at once
    assert _agree(*F64, [msgs[1], msgs[1]], ["data"]) is not None


def test_equal_sizes_with_different_length_words():
    """Both payloads 44 bytes, but ``raw`` and ``label`` trade 8 bytes: ``d`` moves."""
    name, text = "pkg/msg/V", "uint8[] raw\nfloat64 d\nstring label\nfloat64 e\n"
    a = cdr_encode(name, text, {"raw": b"\1" * 8, "d": 1.0, "label": "", "e": 2.0}, False)
    b = cdr_encode(name, text, {"raw": b"", "d": 3.0, "label": "abcdefgh", "e": 4.0}, False)
    assert len(a) == len(b) == 44
    assert _agree(name, text, [a, b], ["d", "e"]) is None
    assert _agree(name, text, [a, a, a], ["d", "e", "raw.3"]) is not None


@pytest.mark.parametrize("bad", [b"\xff\xfe", b"\xc3\x28", b"\xe2\x82"])
def test_invalid_utf8_in_a_later_message(bad):
    """mcap-ros2-support refuses the string: the block must be left to it."""
    name, text = "pkg/msg/S", "string label\nfloat64 d\n"
    good = cdr_encode(name, text, {"label": "ab", "d": 1.0}, False)
    broken = good.replace(b"ab\x00", bad + b"\x00")
    assert len(broken) == len(good)
    assert _general(name, text, [broken], ["d"]) == [None]
    assert _agree(name, text, [good, broken, good], ["d"]) is None
    # another ASCII string in a later message, or the first one's UTF-8 bytes, read at once
    other = good.replace(b"ab\x00", b"cd\x00")
    assert _agree(name, text, [good, other, good], ["d"]) is not None
    accent = good.replace(b"ab\x00", "é".encode() + b"\x00")
    assert _agree(name, text, [accent, accent], ["d"]) is not None


@pytest.mark.parametrize("kind", ["uint8", "byte"])
def test_byte_arrays_are_not_numbers(kind):
    """``uint8[]``/``byte[]`` decode as ``bytes``, which no mapped number is made of."""
    name, text = "pkg/msg/B", f"{kind}[] raw\n{kind}[4] fixed\nfloat64 d\n"
    msgs = [cdr_encode(name, text, {"raw": b"\1\2\3", "fixed": b"\4\5\6\7", "d": 2.0}, False)] * 4
    for path in ("raw", "fixed"):
        assert _general(name, text, msgs, [path])[0][0] == [None]  # not numeric
        assert _agree(name, text, msgs, [path]) is None
    got = _agree(name, text, msgs, ["raw.1", "fixed.3", "d"])  # one element is a number
    assert got is not None and got.values[1][:, 0].tolist() == [7.0] * 4


def test_bool_bytes_other_than_one():
    """A CDR bool byte of 2 is ``True`` to the general path: 1.0, not 2.0."""
    name, text = "pkg/msg/F", "bool flag\nfloat64 d\n"
    msgs = []
    for byte in (0, 1, 2, 255):
        m = bytearray(cdr_encode(name, text, {"flag": True, "d": 1.0}, False))
        m[4] = byte
        msgs.append(bytes(m))
    got = _agree(name, text, msgs, ["flag"])
    assert got is not None and got.values[0][:, 0].tolist() == [0.0, 1.0, 1.0, 1.0]


def test_top_level_stamp_ns_is_a_stamp_to_the_general_path():
    """No header, but a ``stamp_ns`` field: the general path stamps by it, so must the fast."""
    name, text = "pkg/msg/T", "int64 stamp_ns\nfloat64 d\n"
    msgs = [cdr_encode(name, text, {"stamp_ns": T0_NS + i, "d": float(i)}, False) for i in range(3)]
    assert _general(name, text, msgs, ["d"])[1][1] == T0_NS + 1
    _agree(name, text, msgs, ["d"])  # declined, or read with those stamps


def test_imu_nanosec_is_unsigned():
    """``nanosec`` is uint32: a value at or above 2^31 must not come out negative."""
    n = 6
    pay = imu_cdr_payloads(imu_stamps(n), imu_accel(n, 2))
    pay = np.array(pay, copy=True)
    for i in range(n):
        pay[i, 8:12] = np.frombuffer(struct.pack("<I", 0xFFFF_FFF0 + i), np.uint8)
    msgs = [bytes(r) for r in pay]
    buf, s, e = lay_out(msgs, [3] * n)
    got = decode_imu_cdr_many(memoryview(buf), s, e)
    want = [decode_imu_cdr(m)[0] for m in msgs]
    assert got is not None and got.stamp_ns.tolist() == want
    assert want[0] == (T0_NS // 10**9) * 10**9 + 0xFFFF_FFF0


def test_float32_signalling_nan_is_silent(tmp_path):
    """The fast path casts float32 to float64 without a warning (the general path has none)."""
    p = tmp_path / "f32.mcap"
    with open(p, "wb") as f:
        w = raw_writer(f, 1 << 20)
        sid = w.register_schema("std_msgs/msg/Float32", "ros2msg", b"float32 data\n")
        cid = w.register_channel("/f", "cdr", sid)
        for i in range(100):
            bits = 0x7F800001 if i == 50 else struct.unpack("<I", struct.pack("<f", i * 0.5))[0]
            w.add_message(
                cid,
                log_time=T0_NS + i * 10**7,
                publish_time=0,
                sequence=i,
                data=b"\0\1\0\0" + struct.pack("<I", bits),
            )
        w.finish()
    with warnings.catch_warnings(), np.errstate(invalid="raise"):
        warnings.simplefilter("error")
        rec = read(p)
    v = rec.slow["/f"].values
    assert np.isnan(v[50]) and v[49] == 24.5
    # the bits Python's float() gives the general path: the quiet NaN of the same payload
    want = struct.unpack(
        "<Q", struct.pack("<d", struct.unpack("<f", struct.pack("<I", 0x7F800001))[0])
    )
    assert int(v.view(np.uint64)[50]) == want[0]


def test_unicode_digits_in_a_path_are_names_not_indices(monkeypatch, tmp_path):
    """``a.²``: no such field on either path (a MappingError), not a crash of int('²')."""
    assert path_parts("a.²") == ("a", "²") and path_parts("v[²]") == ("v[²]",)
    name, text = "pkg/msg/O", "float64[2] a\nfloat64 d\n"
    msgs = [cdr_encode(name, text, {"a": [1.0, 2.0], "d": 3.0}, False)] * 3
    buf, s, e = lay_out(msgs, [0] * 3)
    assert Ros2BlockDecoder(name, text).columns(memoryview(buf), s, e, ["a.²"]) is None
    with pytest.raises(KeyError):
        get_field({"a": [1, 2]}, "a.²")
    p = tmp_path / "o.mcap"
    with open(p, "wb") as f:
        w = raw_writer(f, 1 << 20)
        sid = w.register_schema(name, "ros2msg", text.encode())
        cid = w.register_channel("/o", "cdr", sid)
        for i in range(20):
            w.add_message(cid, log_time=T0_NS + i * 10**6, publish_time=0, sequence=i, data=msgs[0])
        w.finish()
    mapping = ChannelMapping(slow=(SlowSpec("x", topic="/o", field="a.²", unit="1"),))
    orig = mcap_decoders._decoder_for

    def plain(enc: str, schema: Any, generic: bool) -> Any:
        d = orig(enc, schema, generic)
        return d if d is None else dataclasses.replace(d, decode_many=None)

    for fast in (True, False):
        if not fast:
            monkeypatch.setattr(mcap_decoders, "_decoder_for", plain)
        with pytest.raises(MappingError, match="none of the 20 decoded messages has it"):
            read(p, mapping=mapping)


def test_mapped_bool_and_stamp_ns_equal_on_both_paths(monkeypatch, tmp_path):
    """A file of the odd cases above, read through ``ingest`` on both paths."""
    name, text = "pkg/msg/T", "int64 stamp_ns\nbool flag\nfloat64 d\n"
    p = tmp_path / "t.mcap"
    with open(p, "wb") as f:
        w = raw_writer(f, 4096)
        sid = w.register_schema(name, "ros2msg", text.encode())
        cid = w.register_channel("/t", "cdr", sid)
        for i in range(600):
            m = bytearray(
                cdr_encode(
                    name,
                    text,
                    {"stamp_ns": T0_NS + i * 10**6 + 3, "flag": True, "d": float(i)},
                    False,
                )
            )
            m[12] = i % 3
            w.add_message(
                cid, log_time=T0_NS + i * 10**6 + 500_000, publish_time=0, sequence=i, data=bytes(m)
            )
        w.finish()
    mapping = ChannelMapping(
        uniform=(UniformSpec("d", 1000.0, topic="/t", field="d", unit="m"),),
        slow=(SlowSpec("flag", topic="/t", field="flag", unit="1"),),
    )
    ((_rep, chans, slow), _w), _spy = both_paths(monkeypatch, tmp_path, p.read_bytes(), mapping)
    assert slow["flag"].values.tolist() == [float(i % 3 != 0) for i in range(600)]
    # placed by stamp_ns (3 ns after the ms), not by the log time (0.5 ms later)
    assert abs(chans["d"].start_time_s - (T0_NS + 3) * 1e-9) < 1e-6
    assert abs(slow["flag"].time_s[0] - (T0_NS + 3) * 1e-9) < 1e-6


# --- the Imu "all stamps zero" rule ---------------------------------------------------------


def test_imu_stamps_starting_at_zero_are_not_all_zero(monkeypatch, tmp_path):
    """Simulated time from 0: the first stamp is 0, the others are not: the header places."""
    n = 1200
    stamps = np.round(np.arange(n) * 1e9 / FS).astype(np.int64)
    p = imu_file(
        tmp_path / "z0.mcap", imu_rows(stamps, imu_accel(n, 1)), imu_stamps(n).tolist(),
        chunk_size=1 << 20,
    )
    ((rep, chans, _s), _w), spy = both_paths(monkeypatch, tmp_path, p.read_bytes())
    assert spy.taken > 0
    assert not any("all zero" in w for w in rep["warnings"])
    assert chans["/imu/linear_acceleration.x"].start_time_s == 0.0


# --- both clocks ----------------------------------------------------------------------------

DELAY_NS = 5000
X = "/imu/linear_acceleration.x"


@pytest.fixture(scope="module")
def delayed(tmp_path_factory) -> Any:
    """An Imu stream logged 5 us after its header stamps, in chunks, with a Float64 topic."""
    n = 20_000
    path = tmp_path_factory.mktemp("clk") / "delay.mcap"
    return write_imu_cdr_mcap(
        path,
        imu_stamps(n),
        imu_accel(n, 5),
        log_delay_ns=DELAY_NS,
        chunk_size=64 << 10,
        scalars={"/slow/t": (np.arange(0, 20, 0.5) + T0_NS * 1e-9, np.arange(40.0))},
    )


def test_both_clocks_of_an_imu_stream(delayed):
    # float64 seconds near 1.7e9 s resolve 0.24 us: offsets are compared to 0.5 us
    tol = 5e-7
    rec = read(delayed)
    tb = rec.report.timebase
    assert abs(rec.channels[X].start_time_s - T0_NS * 1e-9) < tol  # header stamps place it
    assert abs(tb[f"{X}@log_time"]["offset_s"] - DELAY_NS * 1e-9) < tol
    assert abs(tb[f"{X}@log_time"]["start_time_s"] - (T0_NS + DELAY_NS) * 1e-9) < tol
    assert tb[f"{X}@log_time"]["max_abs_residual_s"] < tol and f"{X}@header" not in tb
    by_log = read(delayed, mcap_clock="log_time")
    tb2 = by_log.report.timebase
    assert abs(by_log.channels[X].start_time_s - (T0_NS + DELAY_NS) * 1e-9) < tol
    assert abs(tb2[f"{X}@header"]["offset_s"] + DELAY_NS * 1e-9) < tol
    assert f"{X}@log_time" not in tb2
    for name, ch in rec.channels.items():  # the same samples either way
        assert (
            ch.values.view(np.int64).tolist()
            == by_log.channels[name].values.view(np.int64).tolist()
        )
    assert rec.slow["/slow/t"].equals(by_log.slow["/slow/t"])


@pytest.mark.parametrize("clock", ["header", "log_time"])
def test_second_clock_equal_on_both_paths(monkeypatch, tmp_path, delayed, clock):
    """The fast and the general path give the same report, second clock included."""
    orig = mcap_reader.ingest

    def with_clock(*a: Any, **k: Any) -> Any:
        return orig(*a, **{**k, "clock": clock})

    monkeypatch.setattr(mcap_reader, "ingest", with_clock)  # read()
    monkeypatch.setattr(cdr_paths, "ingest", with_clock)  # ingest() of both_paths
    ((rep, _c, _s), _w), spy = both_paths(monkeypatch, tmp_path, delayed.read_bytes())
    assert spy.taken > 0
    other = "log_time" if clock == "header" else "header"
    assert f"{X}@{other}" in rep["timebase"]


def test_mapped_channel_keeps_both_clocks(delayed):
    mapping = ChannelMapping(
        uniform=(UniformSpec("ax", FS, topic="/imu", field="linear_acceleration.x", unit="m/s^2"),),
    )
    rec = read(delayed, mapping=mapping)
    tb = rec.report.timebase
    assert abs(tb["ax@log_time"]["offset_s"] - DELAY_NS * 1e-9) < 5e-7
    assert abs(rec.channels["ax"].start_time_s - T0_NS * 1e-9) < 5e-7
    rec2 = read(delayed, mapping=mapping, mcap_clock="log_time")
    assert abs(rec2.channels["ax"].start_time_s - (T0_NS + DELAY_NS) * 1e-9) < 5e-7
    assert abs(rec2.report.timebase["ax@header"]["offset_s"] + DELAY_NS * 1e-9) < 5e-7


def test_clock_name_is_checked(delayed):
    with pytest.raises(ValueError, match="mcap_clock"):
        read(delayed, mcap_clock="publish_time")


def test_parquet_round_trip_keeps_the_second_clock(tmp_path, delayed):
    from rigtools.ingest import write_parquet

    rec = read(delayed)
    out = write_parquet(rec, tmp_path / "r.parquet")
    back = read(out)
    assert back.report.timebase[f"{X}@log_time"] == rec.report.timebase[f"{X}@log_time"]


# --- the handlers' buffers ------------------------------------------------------------------


def test_thinned_keeps_evenly_spread_positions():
    """Positions kept are the multiples of a power-of-two step, at most the limit."""
    th = Thinned(100)
    x = np.arange(10_000, dtype=np.int64) * 7
    for lo in range(0, 10_000, 333):
        th.append(x[lo : lo + 333])
    pos, val = th.take()
    assert 50 < pos.size <= 100
    step = int(pos[1] - pos[0])
    assert pos.tolist() == list(range(0, 10_000, step)) and val.tolist() == (pos * 7).tolist()


def test_slabs_join_to_the_values_appended():
    s = Slabs(np.float64)
    parts = [np.arange(k, dtype=np.float64) + k for k in (5000, 300_000, 1, 270_000)]
    for p in parts:
        s.append(p[::1])
    assert s.take().tolist() == np.concatenate(parts).tolist()


def test_empty_array_is_not_aligned():
    """An empty ``float64[]`` moves nothing: ``b`` follows the length word directly."""
    name, text = "pkg/msg/E", "float64[] v\nuint8 b\nfloat64 d\n"
    msgs = [cdr_encode(name, text, {"v": [], "b": 7, "d": float(i)}, False) for i in range(4)]
    got = _agree(name, text, msgs, ["b", "d"])
    assert got is not None and got.values[0][:, 0].tolist() == [7.0] * 4
    assert got.values[1][:, 0].tolist() == [0.0, 1.0, 2.0, 3.0]


def test_empty_nested_message_takes_one_byte():
    """A field-less message is serialised as one byte (ROS 2's placeholder member)."""
    name = "pkg/msg/H"
    text = "pkg/Nothing e\nuint8 b\nfloat32 f\n" + "=" * 80 + "\nMSG: pkg/Nothing\n"
    msgs = [cdr_encode(name, text, {"e": {}, "b": 9, "f": 0.5 * i}, False) for i in range(4)]
    got = _agree(name, text, msgs, ["b", "f"])
    assert got is not None and got.values[0][:, 0].tolist() == [9.0] * 4
    assert got.values[1][:, 0].tolist() == [0.0, 0.5, 1.0, 1.5]


def test_empty_arrays_read_at_once_on_both_paths(monkeypatch, tmp_path):
    """Chunks whose messages all hold ``v = []`` are read at once and give no sample."""
    name, text = "pkg/msg/A", "std_msgs/Header header\nfloat64[] v\n"
    text += "=" * 80 + "\nMSG: std_msgs/Header\nbuiltin_interfaces/Time stamp\nstring frame_id\n"
    text += "=" * 80 + "\nMSG: builtin_interfaces/Time\nint32 sec\nuint32 nanosec\n"
    p = tmp_path / "a.mcap"
    with open(p, "wb") as f:
        w = raw_writer(f, 2048)
        sid = w.register_schema(name, "ros2msg", text.encode())
        cid = w.register_channel("/a", "cdr", sid)
        for i in range(400):
            t = T0_NS + i * 4 * 10**6
            v = [] if i < 200 else [float(i), -float(i), 0.5, 1.5]  # 4 samples a message
            m = {
                "header": {"stamp": {"sec": t // 10**9, "nanosec": t % 10**9}, "frame_id": "f"},
                "v": v,
            }
            w.add_message(
                cid, log_time=t, publish_time=t, sequence=i, data=cdr_encode(name, text, m, False)
            )
        w.finish()
    mapping = ChannelMapping(uniform=(UniformSpec("v", 1000.0, topic="/a", field="v", unit="1"),))
    buf, s, e = lay_out([cdr_encode(name, text, {"v": []}, False)] * 3, [0, 0, 0])
    got = Ros2BlockDecoder(name, text).columns(memoryview(buf), s, e, ["v"])
    assert got is not None and got.values[0].shape == (3, 0)
    ((rep, chans, _s), _w), spy = both_paths(monkeypatch, tmp_path, p.read_bytes(), mapping)
    # only the chunk holding both kinds falls back (counted twice: ingest and read)
    assert spy.declined <= 2 and spy.taken > 10
    assert len(chans["v"]) == 800 and rep["decoded"] == 400


def test_info_shows_the_second_clock_offset(delayed, capsys):
    from rigtools.cli import main

    assert main(["info", str(delayed)]) == 0
    out = capsys.readouterr().out
    line = next(ln for ln in out.splitlines() if f"{X}@log_time" in ln)
    # 5 us written; float64 seconds near 1.7e9 s resolve 0.24 us
    offset_us = float(line.split("offset ")[1].split(" us from the channel's clock")[0])
    assert abs(offset_us - 5.0) < 0.5

"""MCAP reader on payloads that are valid MCAP but hostile or odd inside.

Hostile JSON (numbers beyond float, deep nesting, schema violations), channel names shared
by several topics, damaged and restarted sample counters, mappings whose field some messages
lack, jittered and non-round Imu rates, and a gzip-wrapped file cut short. Every case checks
that the reader keeps what is intact, counts what is not (with its position) and lets no
exception other than rigtools' own escape.
"""

from __future__ import annotations

import gzip
import json
import struct
import warnings
from pathlib import Path

import numpy as np
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st

from rigtools.demo.mcap_writer import write_accel_mcap, write_imu_mcap
from rigtools.errors import MappingError, NoDataError, PayloadDecodeError
from rigtools.ingest import read
from rigtools.ingest.builder import RecordingBuilder
from rigtools.ingest.layout import ChannelMapping, SlowSpec, UniformSpec
from rigtools.ingest.mcap import handlers, ingest
from rigtools.ingest.mcap.decoders import (
    MAX_SAMPLE_RATE_HZ,
    MIN_SAMPLE_RATE_HZ,
    SLOW_VALUE_SCHEMA,
    accel_batch_file_descriptor_set,
    decode_accel_batch_json,
    decode_accel_batch_protobuf,
    decode_slow_value_json,
    encode_accel_batch_protobuf,
)
from rigtools.ingest.mcap.json import parse_json
from rigtools.ingest.mcap.timing import (
    nominal_rate,
    resync_counter_restarts,
    stamp_grid,
)
from rigtools.ingest.recording import IngestReport
from rigtools.schemas import schema_path

T0 = 1_700_000_000.0
T0_NS = 1_700_000_000_000_000_000
BIG_INT = 10**400  # an integer literal no float holds
DEEP = b"[" * 100_000 + b"]" * 100_000  # nested beyond the JSON parser's recursion limit

pytestmark = pytest.mark.filterwarnings("error::RuntimeWarning")


# --- writing hand-made messages -------------------------------------------------------------


def _write(path: Path, topics: dict[str, tuple[str, list[bytes]]], *,
           stamps: dict[str, list[int]] | None = None, compression: str = "none") -> Path:
    """Write topic -> (kind, payloads), the messages interleaved topic by topic.

    Kinds: ``pb`` / ``json`` (AccelBatch), ``slow`` (SlowValue), ``json:<schema name>``.
    """
    from mcap.writer import CompressionType, Writer

    comp = {"none": CompressionType.NONE, "zstd": CompressionType.ZSTD}[compression]
    with open(path, "wb") as f:
        w = Writer(f, compression=comp, chunk_size=1 << 16)
        w.start()
        cids = {}
        for topic, (kind, _payloads) in topics.items():
            if kind == "pb":
                sid = w.register_schema("rigtools.AccelBatch", "protobuf",
                                        accel_batch_file_descriptor_set())
                cids[topic] = w.register_channel(topic, "protobuf", sid)
                continue
            if kind == "json":
                sid = w.register_schema("rigtools.AccelBatch", "jsonschema",
                                        schema_path("accel_batch.schema.json").read_bytes())
            elif kind == "slow":
                sid = w.register_schema("rigtools.SlowValue", "jsonschema",
                                        json.dumps(SLOW_VALUE_SCHEMA).encode())
            else:
                sid = w.register_schema(kind.split(":", 1)[1], "jsonschema", b"{}")
            cids[topic] = w.register_channel(topic, "json", sid)
        longest = max(len(p) for _k, p in topics.values())
        for i in range(longest):
            for topic, (_kind, payloads) in topics.items():
                if i < len(payloads):
                    t = stamps[topic][i] if stamps else i * 1_000_000
                    w.add_message(cids[topic], log_time=t, publish_time=t, sequence=i,
                                  data=payloads[i])
        w.finish()
    return path


def _batch_json(channel="a", unit="g", rate=1000.0, first=0, stamp=T0_NS, values=(1.0, 2.0),
                **extra) -> dict:
    doc = {"channel": channel, "unit": unit, "sample_rate_Hz": rate,
           "first_sample_index": first, "stamp_ns": stamp, "values": list(values)}
    doc.update(extra)
    return doc


def _good_json_batches(n=10, width=4, rate=1000.0):
    return [json.dumps(_batch_json(first=i * width, stamp=T0_NS + round(i * width / rate * 1e9),
                                   values=[float(i * width + j) for j in range(width)],
                                   rate=rate)).encode() for i in range(n)]


def _slow_json(i, value=None) -> bytes:
    return json.dumps({"name": "speed_rpm", "unit": "rpm", "stamp_ns": T0_NS + i * 10**8,
                       "value": float(i) if value is None else value}).encode()


def _record_at(data: bytes, where: str) -> tuple[int, int]:
    """(opcode, sequence) of the record a ``chunk at byte C +O`` position names (uncompressed)."""
    assert where.startswith("chunk at byte "), where
    cpos, off = (int(x) for x in where.removeprefix("chunk at byte ").split(" +"))
    c = cpos + 9
    clen = struct.unpack_from("<I", data, c + 28)[0]
    records = c + 32 + clen + 8
    op = data[records + off]
    seq = struct.unpack_from("<I", data, records + off + 9 + 2)[0]
    return op, seq


# --- 1. numbers beyond float and deep nesting ------------------------------------------------


@pytest.mark.parametrize("payload", [
    b'{"channel": "a", "unit": "g", "sample_rate_Hz": ' + str(BIG_INT).encode()
    + b', "first_sample_index": 0, "stamp_ns": 0, "values": [1.0]}',
    b'{"channel": "a", "unit": "g", "sample_rate_Hz": 10.0, "first_sample_index": 0, '
    b'"stamp_ns": 0, "values": [1.0, ' + str(BIG_INT).encode() + b"]}",
    DEEP,
])
def test_json_batch_beyond_float_or_too_deep_is_a_payload_error(payload):
    with pytest.raises(PayloadDecodeError, match=r"float range|nested too deeply"):
        decode_accel_batch_json(payload)


def _same_json(fast, ref) -> bool:
    """Whether ``parse_json``'s value ``fast`` is ``json.loads``' value ``ref``.

    NaN equals NaN; an integer beyond the 64-bit range may be the float orjson gives for it
    (``parse_json``'s documented exception) or, where orjson refused the document and the
    standard library parsed it, the integer.
    """
    if isinstance(ref, bool) or ref is None or isinstance(ref, str):
        return type(fast) is type(ref) and fast == ref
    if isinstance(ref, int):
        if -2**63 <= ref < 2**64:
            return type(fast) is int and fast == ref
        return ((type(fast) is float and fast == float(ref))  # orjson parsed the document
                or (type(fast) is int and fast == ref))  # the standard library did
    if isinstance(ref, float):
        return type(fast) is float and (fast == ref or (fast != fast and ref != ref))
    if isinstance(ref, list):
        return (type(fast) is list and len(fast) == len(ref)
                and all(_same_json(a, b) for a, b in zip(fast, ref, strict=True)))
    return (type(fast) is dict and list(fast) == list(ref)
            and all(_same_json(fast[k], ref[k]) for k in ref))


_JSON_SCALARS = (st.none() | st.booleans() | st.text(max_size=8)
                 | st.integers(min_value=-2**70, max_value=2**70)
                 | st.floats(allow_nan=True, allow_infinity=True))
_JSON_DOCS = st.recursive(_JSON_SCALARS, lambda kids: st.lists(kids, max_size=6)
                          | st.dictionaries(st.text(max_size=6), kids, max_size=6),
                          max_leaves=30)


@settings(max_examples=300, deadline=None)
@given(doc=_JSON_DOCS, cut=st.integers(min_value=0, max_value=400),
       byte=st.integers(min_value=0, max_value=255), how=st.sampled_from(["keep", "cut", "flip"]))
def test_parse_json_is_the_standard_parser_on_any_document(doc, cut, byte, how):
    """The fast path (orjson) gives what the standard library gives, damaged or not.

    The same value, or a :class:`PayloadDecodeError` where ``json.loads`` fails (issue 21:
    the faster path must give what the slower one gives).
    """
    data = json.dumps(doc).encode()  # NaN and Infinity tokens and any integer size included
    if how == "cut":
        data = data[: cut % (len(data) + 1)]
    elif how == "flip":
        i = cut % len(data)
        data = data[:i] + bytes([byte]) + data[i + 1:]
    try:
        ref = json.loads(data)
    except (UnicodeDecodeError, ValueError, RecursionError):
        with pytest.raises(PayloadDecodeError):
            parse_json(data, "JSON")
        return
    assert _same_json(parse_json(data, "JSON"), ref)
    assert _same_json(parse_json(memoryview(data), "JSON"), ref)


def test_json_slow_value_beyond_float_is_a_payload_error():
    bad = b'{"name": "x", "unit": "rpm", "stamp_ns": 1, "value": ' + str(BIG_INT).encode() + b"}"
    with pytest.raises(PayloadDecodeError, match="value within the float range"):
        decode_slow_value_json(bad)
    with pytest.raises(PayloadDecodeError, match="nested too deeply"):
        decode_slow_value_json(DEEP)


def test_overflowing_and_deep_payloads_are_counted_where_they_are_and_reading_goes_on(
        tmp_path):
    batches = _good_json_batches()
    batches[3] = json.dumps(_batch_json(first=12, stamp=T0_NS + 12_000_000)).replace(
        "1000.0", str(BIG_INT)).encode()
    batches[6] = DEEP
    slow = [_slow_json(i) for i in range(8)]
    slow[2] = _slow_json(2, value=0.0).replace(b"0.0}", str(BIG_INT).encode() + b"}")
    p = _write(tmp_path / "o.mcap", {"/accel/a": ("json", batches), "/slow/s": ("slow", slow)})
    rec = read(p)
    assert rec.report.rejected == {"decode_error": 3}
    assert rec.report.decoded == 8 + 7
    op, seq = _record_at(p.read_bytes(), rec.report.first_position["decode_error"])
    assert op == 0x05 and seq == 3  # the accel topic is handled first in its chunk
    ch = rec.channels["a"]
    assert ch.valid.sum() == 32 and [(g.start_index, g.n_missing) for g in rec.report.gaps] \
        == [(12, 4), (24, 4)]
    assert len(rec.slow["speed_rpm"]) == 7
    assert any("nested too deeply" in w or "float range" in w for w in rec.report.warnings)


def test_mapped_json_field_beyond_float_or_too_deep_is_counted(tmp_path):
    docs = [json.dumps({"stamp_ns": T0_NS + i * 10**7, "x": float(i)}).encode()
            for i in range(20)]
    docs[5] = json.dumps({"stamp_ns": T0_NS + 5 * 10**7, "x": 0}).replace(
        '"x": 0', f'"x": {BIG_INT}').encode()
    docs[9] = DEEP
    p = _write(tmp_path / "m.mcap", {"/acme": ("json:acme.Reading", docs)})
    mapping = ChannelMapping(slow=(SlowSpec("x_m", topic="/acme", field="x", unit="m"),))
    rec = read(p, mapping=mapping)
    assert rec.report.rejected == {"decode_error": 2} and rec.report.decoded == 18
    assert rec.slow["x_m"].values.tolist() == [float(i) for i in range(20) if i not in (5, 9)]
    assert rec.report.first_position["decode_error"].startswith("chunk at byte ")


# --- 2. one channel name on several topics ----------------------------------------------------


@pytest.mark.parametrize("kind", ["pb", "json"])
def test_same_channel_name_on_two_topics_is_kept_apart(tmp_path, kind):
    def batches(offset):
        out = []
        for i in range(30):
            vals = np.arange(i * 8, i * 8 + 8, dtype=np.float32) + offset
            stamp = T0_NS + i * 8_000_000
            if kind == "pb":
                out.append(encode_accel_batch_protobuf("accel_1", "g", 1000.0, i * 8, stamp,
                                                       vals))
            else:
                out.append(json.dumps(_batch_json("accel_1", first=i * 8, stamp=stamp,
                                                  values=vals.tolist())).encode())
        return out

    p = _write(tmp_path / "two.mcap", {"/accel/a": (kind, batches(0.0)),
                                       "/accel/b": (kind, batches(1000.0))},
               compression="zstd")
    rec = read(p)
    assert sorted(rec.channels) == ["accel_1@/accel/a", "accel_1@/accel/b"]
    assert not rec.report.rejected and rec.report.decoded == 60
    assert rec.channels["accel_1@/accel/a"].values.tolist() == list(range(240))
    assert rec.channels["accel_1@/accel/b"].values.tolist() == [1000.0 + i for i in range(240)]
    (warn,) = [w for w in rec.report.warnings if "kept apart" in w]
    assert "'/accel/a'" in warn and "'/accel/b'" in warn


def test_a_mapping_names_channels_as_it_says_even_when_payloads_collide(tmp_path):
    chans = {"accel_1": (np.arange(64, dtype=np.float32), 1000.0, "g", 0, T0)}
    p = write_accel_mcap(tmp_path / "one.mcap", chans, batch=16)
    rec = read(p)
    assert list(rec.channels) == ["accel_1"]  # a name used once is left alone
    mapping = ChannelMapping(uniform=(UniformSpec("AccX", 1000.0, topic="/accel/accel_1",
                                                  field="values"),))
    assert list(read(p, mapping=mapping).channels) == ["AccX"]


# --- 3. damaged and restarted counters --------------------------------------------------------


def _counter_file(tmp_path, firsts, stamps_s, *, width=100, rate=1000.0, name="c.mcap"):
    payloads, stamps = [], []
    for k, (first, t) in enumerate(zip(firsts, stamps_s, strict=True)):
        ns = round(t * 1e9)
        vals = np.arange(k * width, (k + 1) * width, dtype=np.float32)
        payloads.append(encode_accel_batch_protobuf("acc", "g", rate, int(first), ns, vals))
        stamps.append(ns)
    return _write(tmp_path / name, {"/accel/acc": ("pb", payloads)},
                  stamps={"/accel/acc": stamps}, compression="zstd")


def test_one_absurd_counter_among_a_hundred_is_counted_implausible(tmp_path):
    firsts = [k * 100 for k in range(100)]
    firsts[50] = 10**12
    p = _counter_file(tmp_path, firsts, [T0 + k * 0.1 for k in range(100)])
    rec = read(p)
    ch = rec.channels["acc"]
    assert rec.report.rejected == {"implausible_sample_index": 100}
    assert ch.first_index == 0 and len(ch) == 10_000 and ch.valid.sum() == 9_900
    assert [(g.start_index, g.n_missing, g.kind) for g in rec.report.gaps] == [(5000, 100, "gap")]
    assert np.array_equal(ch.values[ch.valid], np.r_[0:5000, 5100:10_000].astype(float))
    assert not any("resynchronised" in w for w in rec.report.warnings)


def test_counter_restart_halfway_is_resynchronised_and_nothing_is_lost(tmp_path):
    firsts = [k * 100 for k in range(50)] * 2  # back to 0 at batch 50, stamps going on
    p = _counter_file(tmp_path, firsts, [T0 + k * 0.1 for k in range(100)])
    rec = read(p)
    ch = rec.channels["acc"]
    assert not rec.report.rejected and not rec.report.gaps
    assert ch.first_index == 0 and ch.values.tolist() == list(range(10_000))
    assert ch.start_time_s == pytest.approx(T0, abs=1e-6)
    (warn,) = [w for w in rec.report.warnings if "restart" in w]
    assert "went back to 0" in warn and "continue at index 5000" in warn


def test_counter_restart_after_a_pause_leaves_a_gap_marked_restart(tmp_path):
    firsts = [k * 100 for k in range(50)] * 2
    stamps = [T0 + k * 0.1 for k in range(50)] + [T0 + 7.0 + k * 0.1 for k in range(50)]
    p = _counter_file(tmp_path, firsts, stamps)
    rec = read(p)
    ch = rec.channels["acc"]
    assert not rec.report.rejected
    assert [(g.start_index, g.n_missing, g.kind) for g in rec.report.gaps] == \
        [(5000, 2000, "restart")]
    assert ch.valid.sum() == 10_000 and ch.values[7000] == 5000.0
    assert rec.report.timebase["acc"]["max_abs_residual_s"] < 1e-6


def test_a_single_backwards_counter_is_no_restart(tmp_path):
    firsts = [k * 100 for k in range(100)]
    firsts[50] = 0  # corrupt: the next batch continues from 4900, not from 0
    p = _counter_file(tmp_path, firsts, [T0 + k * 0.1 for k in range(100)])
    rec = read(p)
    assert rec.report.rejected == {"duplicate_sample": 100}
    assert [(g.start_index, g.n_missing) for g in rec.report.gaps] == [(5000, 100)]
    assert not any("resynchronised" in w for w in rec.report.warnings)


def test_restart_resync_is_the_same_on_the_fast_and_the_general_path(tmp_path, monkeypatch):
    firsts = [k * 100 for k in range(40)] + [k * 100 for k in range(60)]
    firsts[70] = 10**12
    p = _counter_file(tmp_path, firsts, [T0 + k * 0.1 for k in range(100)])
    fast = read(p)
    orig_init = handlers.BatchHandler.__init__

    def no_fast(self, *a, **kw):
        orig_init(self, *a, **kw)
        self.decode_many = None

    monkeypatch.setattr(handlers.BatchHandler, "__init__", no_fast)
    general = read(p)
    assert fast.report.to_dict() == general.report.to_dict()
    assert fast.channels["acc"].equals(general.channels["acc"])
    assert fast.report.rejected == {"implausible_sample_index": 100}
    assert any("continue at index 4000" in w for w in fast.report.warnings)


def test_resync_leaves_late_rows_and_steady_counters_alone():
    f = np.array([0, 100, 300, 200, 400], np.int64)  # a late batch, stamped as late
    s = np.array([0, 100, 300, 200, 400], np.uint64) * 1_000_000
    w = np.full(5, 100)
    got, restarts = resync_counter_restarts(f, s, w, 1000.0)
    assert got is f and not restarts
    f2 = np.r_[0:500:100, 0:300:100, 2000:2200:100].astype(np.int64)  # restart, then a gap
    s2 = np.r_[0:8, 25:27].astype(np.uint64) * 100_000_000
    got, restarts = resync_counter_restarts(f2, s2, np.full(10, 100), 1000.0)
    assert [(r.row, r.counter, r.index) for r in restarts] == [(5, 0, 500)]
    assert got.tolist() == [0, 100, 200, 300, 400, 500, 600, 700, 2500, 2600]


# --- 4. a mapped field some messages lack -----------------------------------------------------


def _readings(n=100, lacking=(), field="x"):
    return [json.dumps({"stamp_ns": T0_NS + i * 10**7,
                        **({} if i in lacking else {field: float(i)})}).encode()
            for i in range(n)]


@pytest.mark.parametrize("spec", ["slow", "uniform"])
def test_a_message_lacking_the_mapped_field_is_counted_the_rest_read(tmp_path, spec):
    p = _write(tmp_path / "r.mcap", {"/acme": ("json:acme.Reading", _readings(lacking=(42,)))})
    if spec == "slow":
        mapping = ChannelMapping(slow=(SlowSpec("x_m", topic="/acme", field="x"),))
    else:
        mapping = ChannelMapping(uniform=(UniformSpec("X", 100.0, topic="/acme", field="x"),))
    rec = read(p, mapping=mapping)
    assert rec.report.rejected == {"missing_field": 1} and rec.report.decoded == 99
    op, seq = _record_at(p.read_bytes(), rec.report.first_position["missing_field"])
    assert op == 0x05 and seq == 42
    if spec == "slow":
        assert len(rec.slow["x_m"]) == 99
    else:
        ch = rec.channels["X"]
        assert ch.valid.sum() == 99 and not ch.valid[42]
        assert [(g.start_index, g.n_missing) for g in rec.report.gaps] == [(42, 1)]


def test_a_field_no_message_has_is_a_mapping_error_naming_mapping_recording_topic(tmp_path):
    p = _write(tmp_path / "r.mcap", {"/acme": ("json:acme.Reading", _readings(field="y"))})
    mapping = ChannelMapping(slow=(SlowSpec("x_m", topic="/acme", field="x"),),
                             source="site.toml")
    with pytest.raises(MappingError,
                       match=r"site\.toml.*topic '/acme' of .*r\.mcap.*none of the 100"):
        read(p, mapping=mapping)


def test_a_field_numeric_in_no_message_is_a_mapping_error(tmp_path):
    docs = [json.dumps({"stamp_ns": T0_NS + i, "x": "high"}).encode() for i in range(5)]
    p = _write(tmp_path / "r.mcap", {"/acme": ("json:acme.Reading", docs)})
    mapping = ChannelMapping(slow=(SlowSpec("x_m", topic="/acme", field="x"),))
    with pytest.raises(MappingError, match="a scalar numeric field for a slow signal"):
        read(p, mapping=mapping)


# --- 5. Imu rates that are not round, and jittered stamps -------------------------------------


def _imu(tmp_path, stamps, name="imu.mcap"):
    acc = np.random.default_rng(3).standard_normal((stamps.size, 3))
    return write_imu_mcap(tmp_path / name, stamps, acc, log_delay_s=0.002), acc


def test_imu_at_199_7_hz_keeps_its_rate_and_invents_no_gap(tmp_path):
    stamps = T0 + np.arange(3000) / 199.7
    p, acc = _imu(tmp_path, stamps)
    rec = read(p)
    ch = rec.channels["/imu/linear_acceleration.x"]
    assert ch.sample_rate_Hz == 199.7
    assert not rec.report.gaps and not rec.report.rejected
    assert np.array_equal(ch.values, acc[:, 0]) and ch.valid.all()
    assert any("199.7 Hz estimated" in w for w in rec.report.warnings)


def test_imu_at_1_khz_with_0_3_ms_jitter_drops_nothing(tmp_path):
    rng = np.random.default_rng(11)
    stamps = T0 + np.arange(5000) / 1000.0 + rng.uniform(-0.3e-3, 0.3e-3, 5000)
    p, acc = _imu(tmp_path, stamps)
    rec = read(p)
    ch = rec.channels["/imu/linear_acceleration.z"]
    assert ch.sample_rate_Hz == 1000.0 and len(ch) == 5000
    assert not rec.report.gaps and not rec.report.rejected
    assert np.array_equal(ch.values, acc[:, 2])


def test_imu_jittered_with_lost_messages_shows_exactly_those_gaps(tmp_path):
    rng = np.random.default_rng(10)  # a first stamp far off its slot
    n = 5000
    stamps = T0 + np.arange(n) / 1000.0 + rng.uniform(-0.3e-3, 0.3e-3, n)
    lost = [700, 701, 702, 3000]
    keep = np.setdiff1d(np.arange(n), lost)
    p, acc = _imu(tmp_path, stamps[keep])
    rec = read(p)
    ch = rec.channels["/imu/linear_acceleration.y"]
    assert ch.sample_rate_Hz == 1000.0 and not rec.report.rejected
    assert [(g.start_index, g.n_missing) for g in rec.report.gaps[:2]] == [(700, 3), (3000, 1)]
    assert np.array_equal(ch.values[ch.valid], acc[:, 1])


@pytest.mark.parametrize("jitter", [0.0, 0.2, 0.3])
@pytest.mark.parametrize("seed", range(5))
def test_stamp_grid_places_every_sample(seed, jitter):
    rng = np.random.default_rng(seed)
    fs = rng.uniform(50.0, 5000.0)
    n = 4000
    t = (np.arange(n) + rng.uniform(-jitter, jitter, n)) / fs
    for lost in ([], rng.choice(np.arange(1, n), 25, replace=False)):
        keep = np.setdiff1d(np.arange(n), lost)
        g = stamp_grid(T0_NS + np.round(t[keep] * 1e9).astype(np.int64))
        assert g is not None and np.array_equal(g.index, keep - keep[0])
        assert g.method == ("grid" if len(lost) else "order")
        assert abs(g.fitted_rate_Hz / fs - 1) < 1e-4


def test_stamp_grid_keeps_true_duplicates_and_needs_two_stamps():
    s = T0_NS + np.arange(100) * 1_000_000
    g = stamp_grid(np.insert(s, 10, s[10]))
    assert g.index[10] == g.index[11] == 10 and g.index[-1] == 99
    assert stamp_grid(np.full(5, T0_NS)) is None and stamp_grid(s[:1]) is None


def test_nominal_rate_snaps_only_within_a_tenth_of_a_percent():
    assert nominal_rate(400.3) == 400.0 and nominal_rate(25_610.0) == 25_600.0
    assert nominal_rate(199.7) == 199.7 and nominal_rate(199.69999986) == 199.7
    assert nominal_rate(1234.5678) == 1234.568


# --- 6. JSON AccelBatch against its schema ----------------------------------------------------


@pytest.mark.parametrize(("doc", "match"), [
    (_batch_json(values=["1", "2"]), "array of numbers"),
    (_batch_json(values=[True, False]), "array of numbers"),
    (_batch_json(values=[1.0, None]), "array of numbers"),
    (_batch_json(values=[[1.0], [2.0]]), "array of numbers"),
    (_batch_json(gain=2.0), "extra 'gain'"),
    ({k: v for k, v in _batch_json().items() if k != "unit"}, "missing unit"),
    ({k: v for k, v in _batch_json().items() if k != "stamp_ns"}, "missing stamp_ns"),
    (_batch_json(channel=""), "non-empty string channel"),
    (_batch_json(rate=True), "a number sample_rate_Hz"),
    (_batch_json(rate="1000"), "a number sample_rate_Hz"),
    (_batch_json(first=1.5), "first_sample_index as a uint64"),
    (_batch_json(rate=0.0), "sample_rate_Hz from"),
    (_batch_json(rate=-10.0), "sample_rate_Hz from"),
    (_batch_json(rate=float("inf")), "sample_rate_Hz from"),
    (_batch_json(rate=float("nan")), "sample_rate_Hz from"),
    (_batch_json(rate=MIN_SAMPLE_RATE_HZ / 2), "sample_rate_Hz from"),
    (_batch_json(rate=MAX_SAMPLE_RATE_HZ * 2), "sample_rate_Hz from"),
])
def test_json_batch_violating_its_schema_is_refused(doc, match):
    with pytest.raises(PayloadDecodeError, match=match):
        decode_accel_batch_json(json.dumps(doc).encode())


def test_json_batch_keeps_nan_tokens_and_takes_integers_as_numbers():
    got = decode_accel_batch_json(json.dumps(_batch_json(values=[1, 2.5, float("nan")])).encode())
    assert got.values.dtype == np.float32 and got.values[:2].tolist() == [1.0, 2.5]
    assert np.isnan(got.values[2])
    big = decode_accel_batch_json(json.dumps(_batch_json(values=[1e300])).encode())
    assert big.values.tolist() == [np.inf]  # beyond float32: Inf, counted by the builder


_JSON_SCALARS = st.one_of(
    st.floats(allow_nan=False, allow_infinity=False), st.floats(width=32),
    # 2**60 + 2**36 + 1: to float32 directly it rounds up, through float64 (as the schema's
    # float64-then-float32 path does) it ties to even, down
    st.integers(-(2**70), 2**70), st.sampled_from([2**63, 2**64 - 1, -(2**63), 2**60 + 2**36 + 1]),
    st.text(max_size=3), st.booleans(), st.none())
_JSON_VALUES = st.lists(st.one_of(
    _JSON_SCALARS, st.lists(_JSON_SCALARS, max_size=2),
    st.dictionaries(st.text(max_size=2), _JSON_SCALARS, max_size=1)), max_size=8)


def _type_checked_values(raw: list) -> np.ndarray:
    """The values as the schema's check reads them: every element's Python type first."""
    if not set(map(type, raw)) <= {int, float}:
        raise PayloadDecodeError(None, None, "values as an array of numbers", "")
    try:
        values = np.asarray(raw, dtype=np.float64)
    except OverflowError:
        raise PayloadDecodeError(None, None, "values within the float range", "") from None
    with np.errstate(over="ignore"):
        return values.astype(np.float32)


@given(values=_JSON_VALUES)
@example(values=[2**60 + 2**36 + 1])
@example(values=[1.5, True])
@example(values=[2.5, False, 3.5])
@settings(max_examples=500, deadline=None)
def test_json_values_by_numpy_discovery_equal_the_type_checked_path(values):
    """NumPy's type discovery gives what the per-element type check gives.

    The same float32 bits, or a refusal where the check refuses, on any values array:
    numbers of every size, strings, bools, nulls, nested arrays and objects.
    """
    data = json.dumps(_batch_json(values=values)).encode()
    try:
        got: object = decode_accel_batch_json(data).values.view(np.uint32).tolist()
    except PayloadDecodeError:
        got = "refused"
    try:
        want: object = _type_checked_values(parse_json(data, "")["values"]).view(
            np.uint32).tolist()
    except PayloadDecodeError:
        want = "refused"
    assert got == want


@pytest.mark.parametrize("rate", [0.0, -1.0, 1e-9, 1e12, float("nan"), float("inf")])
def test_protobuf_batch_with_an_absurd_rate_is_refused(rate):
    with pytest.raises(PayloadDecodeError, match="sample_rate_Hz from"):
        decode_accel_batch_protobuf(encode_accel_batch_protobuf("a", "g", rate, 0, 1,
                                                                np.ones(3, np.float32)))


def test_slow_value_violating_its_schema_is_refused():
    good = {"name": "x", "unit": "rpm", "stamp_ns": 1, "value": 2.0}
    with pytest.raises(PayloadDecodeError, match="extra 'note'"):
        decode_slow_value_json(json.dumps({**good, "note": "hi"}).encode())
    with pytest.raises(PayloadDecodeError, match="missing value"):
        decode_slow_value_json(json.dumps({k: good[k] for k in good if k != "value"}).encode())
    with pytest.raises(PayloadDecodeError, match="a number value"):
        decode_slow_value_json(json.dumps({**good, "value": True}).encode())


def test_invalid_json_batches_in_a_file_are_counted_and_the_rest_read(tmp_path):
    batches = _good_json_batches(n=8)
    batches[1] = json.dumps(_batch_json(first=4, values=["4", "5", "6", "7"])).encode()
    batches[2] = json.dumps(_batch_json(first=8, values=[8.0, 9.0, 10.0, 11.0],
                                        extra=1)).encode()
    batches[5] = json.dumps(_batch_json(first=20, rate=0.0)).encode()
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        rec = read(_write(tmp_path / "v.mcap", {"/accel/a": ("json", batches)}))
    assert rec.report.rejected == {"decode_error": 3} and rec.report.decoded == 5
    assert rec.channels["a"].valid.sum() == 20


def test_a_file_of_empty_batches_says_so_in_the_no_data_error(tmp_path):
    batches = [json.dumps(_batch_json(first=0, values=[])).encode() for _ in range(3)]
    batches += [encode_accel_batch_protobuf("a", "g", 10.0, 0, 1, np.zeros(0, np.float32))]
    p = _write(tmp_path / "e.mcap", {"/accel/a": ("json", batches[:3]),
                                     "/accel/b": ("pb", batches[3:])})
    with pytest.raises(NoDataError, match="0 messages decoded; rejected empty_batch: 4"):
        read(p)


# --- 7. a gzip-wrapped MCAP cut short ---------------------------------------------------------


def _chunk_ends(data: bytes) -> list[tuple[int, int]]:
    """(end offset, message count) of each Chunk record of an uncompressed-chunk MCAP."""
    out, pos = [], 8
    while pos + 9 <= len(data):
        op, length = struct.unpack_from("<BQ", data, pos)
        if op == 0x06:
            c = pos + 9
            clen = struct.unpack_from("<I", data, c + 28)[0]
            rstart = c + 32 + clen + 8
            rlen = struct.unpack_from("<Q", data, rstart - 8)[0]
            n, q = 0, rstart
            while q < rstart + rlen:
                rop, rl = struct.unpack_from("<BQ", data, q)
                n += rop == 0x05
                q += 9 + rl
            out.append((pos + 9 + length, n))
        pos += 9 + length
        if op == 0x02:
            break
    return out


@pytest.mark.parametrize("cut", [0.3, 0.55, 0.8])
def test_gzip_mcap_cut_short_keeps_the_complete_chunks_and_counts_the_break(tmp_path, cut):
    rng = np.random.default_rng(0)
    chans = {f"accel_{i}": (rng.standard_normal(20_000).astype(np.float32), 10_000.0, "g", 0,
                            T0) for i in (1, 2)}
    plain = write_accel_mcap(tmp_path / "r.mcap", chans, batch=256, chunk_size=16 << 10,
                             compression="none")
    data = plain.read_bytes()
    gz = gzip.compress(data)
    p = tmp_path / "cut.mcap.gz"
    p.write_bytes(gz[: int(len(gz) * cut)])
    rec = read(p)
    assert rec.report.rejected["truncated_stream"] == 1
    delivered = int(rec.report.first_position["truncated_stream"].split()[-1])
    assert 0 < delivered < len(data)
    whole = [n for end, n in _chunk_ends(data) if end <= delivered]
    assert rec.report.decoded == sum(whole) and sum(whole) > 0
    # exactly what the same bytes give uncut by gzip
    q = tmp_path / "prefix.mcap"
    q.write_bytes(data[:delivered])
    ref = read(q)
    assert rec.channels.keys() == ref.channels.keys()
    assert all(rec.channels[k].equals(ref.channels[k]) for k in ref.channels)
    for k, ch in rec.channels.items():
        assert np.array_equal(ch.values[ch.valid], chans[k][0][: ch.valid.sum()])


def test_ingest_through_open_source_counts_a_gzip_cut_in_the_summary(tmp_path):
    from rigtools.ingest.files import open_source

    p = write_accel_mcap(tmp_path / "r.mcap", {"a": (np.ones(5000, np.float32), 100.0, "g",
                                                     0, T0)}, compression="none")
    g = tmp_path / "r.mcap.gz"
    g.write_bytes(gzip.compress(p.read_bytes())[:-40])
    rep = IngestReport(units="messages")
    with open_source(g, rep) as f:
        b = RecordingBuilder(str(g), rep)
        ingest(f, str(g), b, rep, None)
    assert rep.rejected["truncated_stream"] == 1
    assert rep.decoded == 5 and b.n_channels == 1  # the data section was complete

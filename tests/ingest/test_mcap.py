"""MCAP reader: round trips through the rigtools writer, decoders, mappings, ROS 2 messages."""

from __future__ import annotations

import gzip
import io
import json
import re
import shutil

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rigtools.demo.mcap_writer import flatten_run_metadata, write_accel_mcap, write_imu_mcap
from rigtools.errors import MappingError, PayloadDecodeError
from rigtools.ingest import RunMetadata, read
from rigtools.ingest.builder import RecordingBuilder
from rigtools.ingest.layout import ChannelMapping, SlowSpec, UniformSpec, load_mapping
from rigtools.ingest.mcap import ingest, iter_messages
from rigtools.ingest.mcap.decoders import (
    ACCEL_BATCH_FIELDS,
    IMU_SCHEMA_TEXT,
    SchemaRecord,
    accel_batch_file_descriptor_set,
    decode_accel_batch_json,
    decode_accel_batch_protobuf,
    decode_accel_batches_protobuf,
    decode_imu_cdr,
    decoder_for,
    encode_accel_batch_protobuf,
    get_field,
    ros2_scalar_field,
)
from rigtools.ingest.recording import IngestReport
from rigtools.schemas import load_schema, schema_path

FS = 25_600.0
T0 = 1_700_000_000.0


def _channels(n=5000, n_ch=2, first=1000, seed=0):
    rng = np.random.default_rng(seed)
    return {
        f"accel_{i + 1}": (rng.standard_normal(n).astype(np.float32), FS, "m/s^2", first, T0)
        for i in range(n_ch)
    }


def _slow():
    t = T0 + np.arange(12) * 0.25
    return {"PinionSpeed_rpm": (t, np.linspace(1000.0, 1500.0, 12), "rpm"),
            "OilTemp_C": (t, np.full(12, 90.0), "C")}


META = RunMetadata("LS9-90C", "fzg-1", "fzg-c", {"torque_Nm": 302.0, "bulk_temperature_C": 90.0})


def _ingest(path, mapping=None):
    rep = IngestReport(units="messages")
    b = RecordingBuilder(str(path), rep)
    with open(path, "rb") as f:
        meta = ingest(f, str(path), b, rep, mapping)
    return b, rep, meta


# --- the contracts -------------------------------------------------------------------------


def test_proto_file_and_built_descriptor_agree_field_by_field():
    from google.protobuf import descriptor_pb2

    text = schema_path("accel_batch.proto").read_text(encoding="utf-8")
    assert re.search(r"^package\s+rigtools\s*;", text, re.M)
    assert re.search(r'^syntax\s*=\s*"proto3"\s*;', text, re.M)
    assert re.search(r"^message\s+AccelBatch\s*\{", text, re.M)
    parsed = []
    for line in text.splitlines():
        m = re.match(r"\s*(repeated\s+)?(\w+)\s+(\w+)\s*=\s*(\d+)\s*(\[[^\]]*\])?\s*;", line)
        if m:
            parsed.append((m.group(3), int(m.group(4)), m.group(2), bool(m.group(1)),
                           "packed = true" in (m.group(5) or "")))
    fds = descriptor_pb2.FileDescriptorSet.FromString(accel_batch_file_descriptor_set())
    (fd,) = fds.file
    assert (fd.package, fd.syntax, fd.name) == ("rigtools", "proto3", "accel_batch.proto")
    (msg,) = fd.message_type
    assert msg.name == "AccelBatch"
    fdp = descriptor_pb2.FieldDescriptorProto
    proto_type = {"string": "TYPE_STRING", "double": "TYPE_DOUBLE", "uint64": "TYPE_UINT64",
                  "float": "TYPE_FLOAT"}
    built = [(f.name, f.number, fdp.Type.Name(f.type), f.label == fdp.LABEL_REPEATED,
              f.options.packed) for f in msg.field]
    assert built == [(n, k, proto_type[t], rep, packed) for n, k, t, rep, packed in parsed]
    assert [(n, k, t) for n, k, t, _l in ACCEL_BATCH_FIELDS] == [b[:3] for b in built]


def test_json_schema_has_the_same_fields_as_the_proto():
    schema = load_schema("accel_batch.schema.json")
    assert schema["title"] == "rigtools.AccelBatch"
    assert list(schema["properties"]) == [f[0] for f in ACCEL_BATCH_FIELDS]
    assert set(schema["required"]) == {f[0] for f in ACCEL_BATCH_FIELDS}


def test_writer_embeds_the_slow_value_schema_file_and_its_points_conform(tmp_path):
    """The rigtools.SlowValue schema in a written MCAP is data_schemas/slow_value.schema.json."""
    from mcap.reader import make_reader

    from rigtools.ingest.mcap.decoders import (
        SLOW_VALUE_SCHEMA,
        SLOW_VALUE_SCHEMA_FILE,
        SLOW_VALUE_SCHEMA_NAME,
    )
    from rigtools.schemas import iter_errors

    p = write_accel_mcap(tmp_path / "s.mcap", {}, _slow())
    with open(p, "rb") as f:
        messages = list(make_reader(f).iter_messages())
    schemas = {s.id: s for s, _c, _m in messages}
    (schema,) = schemas.values()
    assert (schema.name, schema.encoding) == (SLOW_VALUE_SCHEMA_NAME, "jsonschema")
    assert SLOW_VALUE_SCHEMA_FILE == "slow_value.schema.json"
    assert schema.data == schema_path(SLOW_VALUE_SCHEMA_FILE).read_bytes()
    assert json.loads(schema.data) == SLOW_VALUE_SCHEMA == load_schema(SLOW_VALUE_SCHEMA_FILE)
    assert SLOW_VALUE_SCHEMA["title"] == SLOW_VALUE_SCHEMA_NAME
    assert len(messages) == 24
    for _s, _c, m in messages:
        assert iter_errors(json.loads(m.data), SLOW_VALUE_SCHEMA_FILE) == []
    bad = {"name": "x", "unit": "rpm", "stamp_ns": -1, "value": 1.0}
    assert iter_errors(bad, SLOW_VALUE_SCHEMA_FILE)[0][0] == "$.stamp_ns"


def _pb_class():
    from google.protobuf import descriptor_pb2, descriptor_pool, message_factory

    pool = descriptor_pool.DescriptorPool()
    for f in descriptor_pb2.FileDescriptorSet.FromString(accel_batch_file_descriptor_set()).file:
        pool.Add(f)
    return message_factory.GetMessageClass(pool.FindMessageTypeByName("rigtools.AccelBatch"))


_batches = st.tuples(
    st.text(max_size=12), st.sampled_from(["m/s^2", "g", ""]),
    st.floats(min_value=1e-3, max_value=1e6, allow_nan=False),
    st.integers(0, 2**63 - 1), st.integers(0, 2**64 - 1),
    st.lists(st.floats(width=32, allow_nan=True, allow_infinity=True), max_size=300),
)


@settings(max_examples=150, deadline=None)
@given(_batches)
def test_wire_walker_matches_protobuf_library(batch):
    channel, unit, rate, first, stamp, vals = batch
    values = np.asarray(vals, np.float32)
    cls = _pb_class()
    ref = cls(channel=channel, unit=unit, sample_rate_Hz=rate, first_sample_index=first,
              stamp_ns=stamp, values=values.tolist())
    data = encode_accel_batch_protobuf(channel, unit, rate, first, stamp, values)
    assert data == ref.SerializeToString(deterministic=True)
    got = decode_accel_batch_protobuf(data)
    back = cls.FromString(data)
    assert (got.channel, got.unit, got.sample_rate_Hz, got.first_sample_index, got.stamp_ns) == (
        back.channel, back.unit, back.sample_rate_Hz, back.first_sample_index, back.stamp_ns)
    assert got.values.dtype == np.float32
    assert np.array_equal(got.values.view(np.uint32),
                          np.asarray(back.values, np.float32).view(np.uint32))


def test_wire_walker_values_are_a_view_not_a_copy():
    data = encode_accel_batch_protobuf("a", "g", 100.0, 5, 7, np.arange(64, dtype=np.float32))
    got = decode_accel_batch_protobuf(data)
    assert got.values.base is not None and not got.values.flags.owndata
    assert got.values.tolist() == list(range(64))


def test_wire_walker_reads_what_other_writers_may_produce():
    from google.protobuf.internal import encoder

    # unknown fields, fields out of order, values split into two packed runs, unpacked floats
    base = encode_accel_batch_protobuf("", "", 0.0, 0, 0, np.array([1.0, 2.0], np.float32))
    unknown = b"\x38\x05" + b"\x42\x03abc"  # field 7 varint, field 8 bytes
    tail = encode_accel_batch_protobuf("acc", "g", 50.0, 9, 11, np.array([], np.float32))
    unpacked = b"".join(encoder.TagBytes(6, 5) + np.float32(v).tobytes() for v in (3.0, 4.0))
    data = unknown + base + tail + unpacked + base
    got = decode_accel_batch_protobuf(data)
    ref = _pb_class().FromString(data)
    assert got.values.tolist() == list(ref.values) == [1.0, 2.0, 3.0, 4.0, 1.0, 2.0]
    assert (got.channel, got.unit, got.sample_rate_Hz, got.first_sample_index) == (
        "acc", "g", 50.0, 9)


@pytest.mark.parametrize(("data", "what"), [
    (b"\x0a\x05ab", "5 bytes of field 1"),
    (b"\x19\x00\x00", "8 bytes"),
    (b"\x32\x03\x00\x00\x00", "multiple of 4"),
    (b"\x1f", "wire type"),
    (b"\x20" + b"\xff" * 11, "varint"),
    (b"\x0a\x01a", "sample_rate_Hz"),  # rate absent (0)
])
def test_wire_walker_refuses_malformed_payloads(data, what):
    with pytest.raises(PayloadDecodeError, match=re.escape(what)):
        decode_accel_batch_protobuf(data)


def _packed(messages, pad=b"\x05" * 31):
    buf, starts, ends = b"", [], []
    for m in messages:
        buf += pad
        starts.append(len(buf))
        buf += m
        ends.append(len(buf))
    return memoryview(buf), np.array(starts), np.array(ends)


@pytest.mark.parametrize("even", [True, False])
def test_vectorized_batch_decode_equals_message_by_message(even):
    rng = np.random.default_rng(3)
    msgs = [encode_accel_batch_protobuf("accel_1", "m/s^2", FS, 256 * i, (i * 10_000_019) % 2**64,
                                        rng.standard_normal(256).astype(np.float32))
            for i in range(40)]  # i = 0: counter and stamp fields omitted (proto3 zero)
    buf, s, e = _packed(msgs)
    if not even:
        s, e = s[::-1].copy(), e[::-1].copy()
    cols = decode_accel_batches_protobuf(buf, s, e)
    assert cols is not None
    for i, (a, b) in enumerate(zip(s, e, strict=True)):
        one = decode_accel_batch_protobuf(buf[a:b])
        assert cols.first_sample_index[i] == one.first_sample_index
        assert int(cols.stamp_ns[i]) == one.stamp_ns
        assert np.array_equal(cols.values[i], one.values)
    assert (cols.channel, cols.unit, cols.sample_rate_Hz) == ("accel_1", "m/s^2", FS)


@pytest.mark.parametrize("odd", ["other_channel", "other_length", "extra_field", "empty"])
def test_vectorized_batch_decode_declines_irregular_groups(odd):
    msgs = [encode_accel_batch_protobuf("a", "g", 10.0, 8 * i, i, np.ones(8, np.float32))
            for i in range(1, 5)]
    if odd == "other_channel":
        msgs[2] = encode_accel_batch_protobuf("b", "g", 10.0, 16, 2, np.ones(8, np.float32))
    elif odd == "other_length":
        msgs[2] = encode_accel_batch_protobuf("a", "g", 10.0, 16, 2, np.ones(4, np.float32))
    elif odd == "extra_field":
        msgs[2] += b"\x38\x01"
    else:
        msgs[2] = encode_accel_batch_protobuf("a", "g", 10.0, 16, 2, np.ones(0, np.float32))
    assert decode_accel_batches_protobuf(*_packed(msgs)) is None


def test_json_batch_decoder_reads_nan_tokens_and_refuses_bad_documents():
    doc = {"channel": "a", "unit": "g", "sample_rate_Hz": 10, "first_sample_index": 3,
           "stamp_ns": 4, "values": [1.0, float("nan"), float("inf")]}
    got = decode_accel_batch_json(json.dumps(doc).encode())
    assert got.values.dtype == np.float32 and np.isnan(got.values[1]) and np.isinf(got.values[2])
    with pytest.raises(PayloadDecodeError, match="first_sample_index as a uint64"):
        decode_accel_batch_json(json.dumps({**doc, "first_sample_index": -1}).encode())
    with pytest.raises(PayloadDecodeError, match="a JSON object"):
        decode_accel_batch_json(b"[1, 2")


def test_imu_cdr_decoder_matches_mcap_ros2(tmp_path):
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory

    rng = np.random.default_rng(1)
    stamps = T0 + np.arange(50) / 400.0
    acc = rng.standard_normal((50, 3))
    for frame in ("", "imu", "imu_link_12345"):  # string lengths that move the alignment
        p = write_imu_mcap(tmp_path / f"imu{len(frame)}.mcap", stamps, acc, frame_id=frame)
        with open(p, "rb") as f:
            for _s, _c, msg, dec in make_reader(f, decoder_factories=[DecoderFactory()]) \
                    .iter_decoded_messages():
                got = decode_imu_cdr(msg.data)
                la = dec.linear_acceleration
                assert (got.ax, got.ay, got.az) == (la.x, la.y, la.z)
                assert got.stamp_ns == dec.header.stamp.sec * 10**9 + dec.header.stamp.nanosec


def test_scalar_field_detection():
    assert ros2_scalar_field("float64 data\n") == "data"
    assert ros2_scalar_field("# a comment\nint32 FOO=3\nuint16 value  # the value\n") == "value"
    assert ros2_scalar_field("string data\n") is None
    assert ros2_scalar_field("float64[] data\n") is None
    assert ros2_scalar_field(IMU_SCHEMA_TEXT) is None


def test_get_field_follows_attributes_keys_and_indices():
    from types import SimpleNamespace

    obj = SimpleNamespace(a=SimpleNamespace(b=[1.0, 2.0, {"c": 5}]))
    assert get_field(obj, "a.b.1") == 2.0
    assert get_field(obj, "a.b[2].c") == 5
    with pytest.raises(KeyError, match="no field 'z'"):
        get_field(obj, "a.z")


def test_decoder_factory_answers_none_for_unknown_and_checks_protobuf_descriptor():
    assert decoder_for("a", SchemaRecord(1, "Example", "c", b"\x04\x05\x06")) is None
    assert decoder_for("json", None) is None
    assert decoder_for("protobuf", SchemaRecord(1, "rigtools.AccelBatch", "protobuf",
                                                accel_batch_file_descriptor_set())).kind == "batch"
    from rigtools.errors import SchemaUnusableError

    with pytest.raises(SchemaUnusableError, match=r"accel_batch\.proto"):
        decoder_for("protobuf", SchemaRecord(2, "rigtools.AccelBatch", "protobuf", b"\x0a\x00"))


# --- round trips ---------------------------------------------------------------------------


@pytest.mark.parametrize("encoding", ["protobuf", "json"])
@pytest.mark.parametrize("compression", ["zstd", "lz4", "none"])
def test_round_trip(tmp_path, encoding, compression):
    chans = _channels()
    p = write_accel_mcap(tmp_path / "run.mcap", chans, _slow(), META, encoding=encoding,
                         compression=compression, batch=512, chunk_size=64 * 1024)
    rec = read(p)
    assert rec.provenance.reader == "mcap"
    assert rec.report.units == "messages"
    n_batches = 2 * int(np.ceil(5000 / 512))
    assert rec.report.decoded == n_batches + 24
    assert not rec.report.has_losses and rec.report.warnings == []
    assert rec.metadata == META
    for name, (vals, fs, unit, first, t0) in chans.items():
        ch = rec.channels[name]
        assert (ch.unit, ch.sample_rate_Hz, ch.first_index) == (unit, fs, first)
        assert ch.start_time_s == pytest.approx(t0, abs=1e-6)
        assert np.array_equal(ch.values, vals.astype(np.float64)) and ch.valid.all()
    for name, (t, v, unit) in _slow().items():
        s = rec.slow[name]
        assert s.unit == unit and np.array_equal(s.values, v)
        assert np.allclose(s.time_s, t, atol=1e-6, rtol=0)


def test_protobuf_and_json_recordings_are_identical(tmp_path):
    chans = _channels(n=3000)
    a = read(write_accel_mcap(tmp_path / "a.mcap", chans, _slow(), META, encoding="protobuf"))
    b = read(write_accel_mcap(tmp_path / "b.mcap", chans, _slow(), META, encoding="json"))
    assert a.channels.keys() == b.channels.keys()
    assert all(a.channels[k].equals(b.channels[k]) for k in a.channels)
    assert all(a.slow[k].equals(b.slow[k]) for k in a.slow)


def test_ingest_returns_the_run_metadata_record(tmp_path):
    p = write_accel_mcap(tmp_path / "r.mcap", _channels(n=100), metadata=META)
    _b, _rep, meta = _ingest(p)
    assert meta == flatten_run_metadata(META)
    assert meta["conditions.torque_Nm"] == "302.0" and meta["run_id"] == "LS9-90C"


def test_gzipped_file_reads_the_same(tmp_path):
    p = write_accel_mcap(tmp_path / "r.mcap", _channels(n=2000), _slow(), compression="none")
    gz = tmp_path / "r.mcap.gz"
    with open(p, "rb") as src, gzip.open(gz, "wb") as dst:
        shutil.copyfileobj(src, dst)
    a, b = read(p), read(gz)
    assert all(a.channels[k].equals(b.channels[k]) for k in a.channels)
    assert b.report.decoded == a.report.decoded


def test_iter_messages_matches_mcap_reader(tmp_path):
    from mcap.reader import make_reader

    p = write_accel_mcap(tmp_path / "r.mcap", _channels(n=3000), _slow(), chunk_size=8192)
    rep = IngestReport(units="messages")
    with open(p, "rb") as f:
        ours = [(m.channel_id, m.log_time, m.publish_time, m.sequence, m.data, m.topic)
                for m in iter_messages(f, str(p), rep)]
    with open(p, "rb") as f:
        theirs = [(c.id, m.log_time, m.publish_time, m.sequence, m.data, c.topic)
                  for _s, c, m in make_reader(f).iter_messages(log_time_order=False)]
    assert ours == theirs and not rep.rejected
    with open(p, "rb") as f:
        kinds = {(m.topic, m.schema_name, m.schema_encoding, m.message_encoding)
                 for m in iter_messages(f, str(p), rep)}
    assert ("/accel/accel_1", "rigtools.AccelBatch", "protobuf", "protobuf") in kinds
    assert ("/slow/OilTemp_C", "rigtools.SlowValue", "jsonschema", "json") in kinds


def _write_batches(path, batches, *, topic="/accel/a", rates=None):
    """Write hand-made batches: (first_sample_index, values) in the given order."""
    from mcap.writer import Writer

    with open(path, "wb") as f:
        w = Writer(f)
        w.start()
        sid = w.register_schema("rigtools.AccelBatch", "protobuf",
                                accel_batch_file_descriptor_set())
        cid = w.register_channel(topic, "protobuf", sid)
        for i, (first, vals) in enumerate(batches):
            rate = 1000.0 if rates is None else rates[i]
            stamp = round((T0 + first / rate) * 1e9)
            w.add_message(cid, log_time=stamp, publish_time=stamp, sequence=i,
                          data=encode_accel_batch_protobuf("a", "g", rate, first, stamp,
                                                           np.asarray(vals, np.float32)))
        w.finish()
    return path


def test_batch_with_another_rate_is_dropped_by_the_builder_clock_untouched(tmp_path):
    b = [(0, [0, 1, 2, 3]), (4, [4, 5, 6, 7]), (8, [8, 9, 10, 11])]
    rec = read(_write_batches(tmp_path / "r.mcap", b, rates=[1000.0, 50.0, 1000.0]))
    ch = rec.channels["a"]
    assert rec.report.rejected["inconsistent_channel_layout"] == 4
    assert [(g.start_index, g.n_missing) for g in rec.report.gaps] == [(4, 4)]
    assert ch.start_time_s == pytest.approx(T0, abs=1e-6)
    assert rec.report.timebase["a"]["max_abs_residual_s"] < 1e-6


def test_gaps_and_duplicates_between_batches_are_left_to_the_builder(tmp_path):
    b = [(0, [0, 1, 2, 3]), (4, [4, 5, 6, 7]), (12, [12, 13, 14, 15]), (14, [14, 15, 16, 17])]
    rec = read(_write_batches(tmp_path / "g.mcap", b))
    ch = rec.channels["a"]
    assert ch.first_index == 0 and len(ch) == 18
    assert ch.valid.tolist() == [True] * 8 + [False] * 4 + [True] * 6
    assert [(g.start_index, g.n_missing) for g in rec.report.gaps] == [(8, 4)]
    assert rec.report.rejected["duplicate_sample"] == 2
    assert ch.start_time_s == pytest.approx(T0, abs=1e-6)


def test_batches_out_of_order_are_placed_by_their_sample_index(tmp_path):
    b = [(8, [8, 9, 10, 11]), (0, [0, 1, 2, 3]), (4, [4, 5, 6, 7])]
    rec = read(_write_batches(tmp_path / "o.mcap", b))
    assert rec.channels["a"].values.tolist() == list(range(12))
    assert not rec.report.gaps


def test_batches_of_varying_length_and_empty_batches(tmp_path):
    b = [(0, [0, 1, 2]), (3, []), (3, [3, 4, 5, 6, 7]), (8, [8])]
    rec = read(_write_batches(tmp_path / "v.mcap", b))
    assert rec.channels["a"].values.tolist() == list(range(9))
    assert rec.report.decoded == 3 and rec.report.rejected == {"empty_batch": 1}
    assert rec.report.first_position["empty_batch"].startswith("chunk at byte ")


def test_non_finite_samples_are_kept_marked_invalid_and_counted(tmp_path):
    for enc in ("protobuf", "json"):
        vals = np.arange(2000, dtype=np.float32)
        vals[[5, 700, 1999]] = [np.nan, np.inf, -np.inf]
        p = write_accel_mcap(tmp_path / f"nan_{enc}.mcap",
                             {"acc": (vals, 1000.0, "g", 0, T0)}, encoding=enc)
        rec = read(p)
        ch = rec.channels["acc"]
        assert np.isnan(ch.values[5]) and ch.values[700] == np.inf and ch.values[1999] == -np.inf
        assert ch.valid.sum() == 1997 and not ch.valid[[5, 700, 1999]].any()
        assert rec.report.rejected["non_finite_sample"] == 3


def test_slow_points_out_of_order_are_sorted_and_reported(tmp_path):
    t = T0 + np.array([0.0, 2.0, 1.0, 3.0, 3.0, 5.0, 4.0])
    p = write_accel_mcap(tmp_path / "s.mcap", {}, {"speed_rpm": (t, np.arange(7.0), "rpm")})
    # the writer emits in log-time order; rewrite in the given order to keep it shuffled
    from mcap.writer import Writer

    from rigtools.ingest.mcap.decoders import SLOW_VALUE_SCHEMA

    with open(p, "wb") as f:
        w = Writer(f)
        w.start()
        sid = w.register_schema("rigtools.SlowValue", "jsonschema",
                                json.dumps(SLOW_VALUE_SCHEMA).encode())
        cid = w.register_channel("/slow/speed_rpm", "json", sid)
        for i, (ti, v) in enumerate(zip(t, range(7), strict=True)):
            ns = round(ti * 1e9)
            w.add_message(cid, log_time=ns, publish_time=ns, sequence=i, data=json.dumps(
                {"name": "speed_rpm", "unit": "rpm", "stamp_ns": ns, "value": v}).encode())
        w.finish()
    rec = read(p)
    s = rec.slow["speed_rpm"]
    assert np.all(np.diff(s.time_s) >= 0) and sorted(s.values.tolist()) == list(range(7))
    assert any("went backwards" in w for w in rec.report.warnings)


# --- ROS 2 ----------------------------------------------------------------------------------


def _imu_file(tmp_path, n=800, rate=400.0, jitter=0.0, drop=()):
    rng = np.random.default_rng(7)
    stamps = T0 + np.arange(n) / rate + rng.uniform(-jitter, jitter, n)
    acc = rng.standard_normal((n, 3))
    keep = np.setdiff1d(np.arange(n), drop)
    p = write_imu_mcap(tmp_path / "imu.mcap", stamps[keep], acc[keep], log_delay_s=0.003,
                       scalars={"/pinion_speed_rpm": (T0 + np.arange(10.0), np.arange(10.0))})
    return p, stamps, acc, keep


def test_imu_becomes_three_uniform_channels_with_estimated_rate(tmp_path):
    p, stamps, acc, keep = _imu_file(tmp_path, jitter=2e-5, drop=range(100, 110))
    rec = read(p)
    names = [f"/imu/linear_acceleration.{a}" for a in "xyz"]
    assert sorted(rec.channels) == names
    ch = rec.channels[names[1]]
    assert ch.sample_rate_Hz == 400.0 and ch.unit == "m/s^2"
    assert any("400 Hz estimated" in w for w in rec.report.warnings)
    assert np.array_equal(ch.values[ch.valid], acc[keep, 1])
    assert [(g.start_index, g.n_missing) for g in rec.report.gaps[:1]] == [(100, 10)]
    assert ch.start_time_s == pytest.approx(stamps[0], abs=1e-4)
    s = rec.slow["/pinion_speed_rpm"]
    assert s.values.tolist() == list(range(10))
    assert np.allclose(s.time_s, T0 + np.arange(10.0), atol=1e-6, rtol=0)


def test_imu_through_a_mapping_uses_the_mapping_rate_and_names(tmp_path):
    p, _stamps, acc, _keep = _imu_file(tmp_path)
    mapping = ChannelMapping(
        uniform=(UniformSpec("AccZ", 400.0, topic="/imu", field="linear_acceleration.z",
                             unit="g", scale=1 / 9.80665),),
        slow=(SlowSpec("PinionSpeed_rpm", topic="/pinion_speed_rpm", field="data", unit="rpm"),),
    )
    rec = read(p, mapping=mapping)
    assert sorted(rec.channels) == ["AccZ"] and sorted(rec.slow) == ["PinionSpeed_rpm"]
    ch = rec.channels["AccZ"]
    assert ch.unit == "g" and ch.sample_rate_Hz == 400.0
    assert np.allclose(ch.values, acc[:, 2] / 9.80665, rtol=1e-15)
    assert not any("estimated" in w for w in rec.report.warnings)
    assert rec.slow["PinionSpeed_rpm"].unit == "rpm"


def test_mapping_from_a_toml_file_renames_and_scales_batches(tmp_path):
    p = write_accel_mcap(tmp_path / "r.mcap", _channels(n=2000), _slow(), META)
    toml = tmp_path / "map.toml"
    toml.write_text(
        '[[uniform]]\nchannel = "AccX"\ntopic = "/accel/accel_1"\nfield = "values"\n'
        'sample_rate_Hz = 25600.0\nunit = "g"\nscale = 0.5\n\n'
        '[[slow]]\nname = "speed_rpm"\ntopic = "/slow/PinionSpeed_rpm"\nfield = "value"\n',
        encoding="utf-8")
    rec = read(p, mapping=toml)
    assert sorted(rec.channels) == ["AccX"] and sorted(rec.slow) == ["speed_rpm"]
    vals = _channels(n=2000)["accel_1"][0].astype(np.float64)
    assert np.array_equal(rec.channels["AccX"].values, vals * 0.5)
    assert rec.slow["speed_rpm"].unit == "rpm"
    n_unmapped = int(np.ceil(2000 / 1024)) + 12  # accel_2 batches and OilTemp_C points
    assert rec.report.rejected["not_in_mapping"] == n_unmapped
    assert any("not in the mapping" in w for w in rec.report.warnings)
    assert rec.provenance.layout["source"] == "mapping"
    assert load_mapping(toml).uniform[0].field == "values"


def test_mapping_naming_a_missing_field_is_a_mapping_error(tmp_path):
    p, *_ = _imu_file(tmp_path, n=20)
    mapping = ChannelMapping(slow=(SlowSpec("x", topic="/imu", field="linear_acceleration.w"),))
    with pytest.raises(MappingError, match="no field 'w'"):
        read(p, mapping=mapping)
    bad = ChannelMapping(slow=(SlowSpec("x", topic="/accel/accel_1", field="values"),))
    q = write_accel_mcap(tmp_path / "r.mcap", _channels(n=100))
    with pytest.raises(MappingError, match="field = \"values\""):
        read(q, mapping=bad)


def test_unknown_encoding_is_counted_no_decoder_with_a_warning_naming_it(tmp_path):
    from mcap.writer import Writer

    p = tmp_path / "u.mcap"
    with open(p, "wb") as f:
        w = Writer(f)
        w.start()
        sid = w.register_schema("acme.Thing", "flatbuffer", b"\x00")
        cid = w.register_channel("/thing", "flatbuffer", sid)
        for i in range(7):
            w.add_message(cid, log_time=i, publish_time=i, sequence=i, data=b"\x01\x02")
        w.finish()
    rep = IngestReport(units="messages")
    b = RecordingBuilder(str(p), rep)
    with open(p, "rb") as f:
        ingest(f, str(p), b, rep, None)
    assert rep.rejected["no_decoder"] == 7 and rep.decoded == 0
    (warn,) = [w for w in rep.warnings if "no decoder" in w]
    assert "'/thing'" in warn and "'flatbuffer'" in warn and "'acme.Thing'" in warn


def test_malformed_payloads_are_counted_decode_error(tmp_path):
    from mcap.writer import Writer

    p = tmp_path / "d.mcap"
    good = encode_accel_batch_protobuf("a", "g", 100.0, 0, 1, np.ones(4, np.float32))
    with open(p, "wb") as f:
        w = Writer(f)
        w.start()
        sid = w.register_schema("rigtools.AccelBatch", "protobuf",
                                accel_batch_file_descriptor_set())
        cid = w.register_channel("/a", "protobuf", sid)
        w.add_message(cid, log_time=0, publish_time=0, sequence=0, data=good)
        w.add_message(cid, log_time=1, publish_time=1, sequence=1, data=b"\x32\x07abc")
        w.add_message(cid, log_time=2, publish_time=2, sequence=2, data=good[:-3])
        w.finish()
    rec = read(p)
    assert rec.report.rejected["decode_error"] == 2 and rec.report.decoded == 1
    assert rec.channels["a"].values.tolist() == [1.0] * 4


def test_ingest_accepts_an_in_memory_stream(tmp_path):
    p = write_accel_mcap(tmp_path / "m.mcap", _channels(n=300))
    rep = IngestReport(units="messages")
    b = RecordingBuilder("mem", rep)
    ingest(io.BytesIO(p.read_bytes()), "mem", b, rep, None)
    assert rep.decoded == 2 and not rep.rejected and b.n_channels == 2

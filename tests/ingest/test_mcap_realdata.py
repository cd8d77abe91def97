"""MCAP reader on third-party files: foxglove's conformance suite and real rosbag2 bags.

The files live in ``../shared/realdata`` (see its README.md and each SOURCE.md); they are read
in place, never copied into the project, and every test here skips when the folder is absent.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from realdata_path import REALDATA

from rigtools.errors import NoDataError
from rigtools.ingest import read
from rigtools.ingest.builder import RecordingBuilder
from rigtools.ingest.layout import ChannelMapping, SlowSpec, UniformSpec
from rigtools.ingest.mcap import ingest, iter_messages
from rigtools.ingest.recording import IngestReport

CONFORMANCE = REALDATA / "mcap-conformance"
ROSBAG2 = REALDATA / "mcap-rosbag2"


def _files(folder: Path) -> list:
    if not folder.is_dir():
        return [pytest.param(None, marks=pytest.mark.skip(reason=f"{folder} is absent"))]
    files = sorted(folder.rglob("*.mcap"))
    return [pytest.param(p, id=str(p.relative_to(folder))) for p in files]


def _expected_messages(mcap: Path) -> list[dict]:
    doc = json.loads(mcap.with_suffix(".json").read_text(encoding="utf-8"))
    return [dict(r["fields"]) for r in doc["records"] if r["type"] == "Message"]


def test_the_realdata_inventory_is_complete(realdata):
    assert len(list(CONFORMANCE.rglob("*.mcap"))) == 171
    assert len(list(ROSBAG2.rglob("*.mcap"))) == 20


@pytest.mark.parametrize("path", _files(CONFORMANCE))
def test_conformance_messages_exactly_as_listed(path):
    want = _expected_messages(path)
    rep = IngestReport(units="messages")
    with open(path, "rb") as f:
        got = list(iter_messages(f, str(path), rep))
    as_json = [{"channel_id": str(m.channel_id), "data": [str(b) for b in m.data],
                "log_time": str(m.log_time), "publish_time": str(m.publish_time),
                "sequence": str(m.sequence)} for m in got]
    assert as_json == want
    assert not rep.rejected and not rep.warnings
    assert all(m.topic == "example" and m.message_encoding == "a" for m in got)


@pytest.mark.parametrize("path", _files(CONFORMANCE))
def test_conformance_files_hold_nothing_decodable_and_say_so(path):
    n = len(_expected_messages(path))
    with pytest.raises(NoDataError, match=rf"0 messages decoded; rejected "
                                          rf"{'no_decoder: ' + str(n) if n else 'none'}\)"):
        read(path)
    rep = IngestReport(units="messages")
    with open(path, "rb") as f:
        ingest(f, str(path), RecordingBuilder(str(path), rep), rep, None)
    assert rep.rejected == ({"no_decoder": n} if n else {})
    if n:
        (w,) = rep.warnings
        assert "'example'" in w and "'a'" in w and "'Example'" in w


def test_ten_messages_log_times_out_of_order_are_sorted_by_the_builder(tmp_path):
    """TenMessages log times (0, 2, 1, 3, 3, 5, 4, ...) carried as rigtools slow points."""
    src = CONFORMANCE / "TenMessages" / "TenMessages-ch-chx-mx.mcap"
    if not src.is_file():
        pytest.skip(f"{src} is absent")
    from mcap.writer import Writer

    from rigtools.ingest.mcap.decoders import SLOW_VALUE_SCHEMA

    rep = IngestReport(units="messages")
    with open(src, "rb") as f:
        times = [m.log_time for m in iter_messages(f, str(src), rep)]
    assert times != sorted(times)
    p = tmp_path / "ten.mcap"
    with open(p, "wb") as f:
        w = Writer(f)
        w.start()
        sid = w.register_schema("rigtools.SlowValue", "jsonschema",
                                json.dumps(SLOW_VALUE_SCHEMA).encode())
        cid = w.register_channel("/slow/x", "json", sid)
        for i, t in enumerate(times):
            w.add_message(cid, log_time=t, publish_time=t, sequence=i, data=json.dumps(
                {"name": "x_rpm", "unit": "rpm", "stamp_ns": t, "value": float(i)}).encode())
        w.finish()
    rec = read(p)
    s = rec.slow["x_rpm"]
    assert (s.time_s * 1e9).round().astype(int).tolist() == sorted(times)
    assert sorted(s.values.tolist()) == [float(i) for i in range(len(times))]
    assert any("went backwards" in w for w in rec.report.warnings)


@pytest.mark.parametrize("path", _files(ROSBAG2))
def test_rosbag2_messages_equal_mcap_readers(path):
    from mcap.reader import make_reader

    rep = IngestReport(units="messages")
    with open(path, "rb") as f:
        ours = [(m.channel_id, m.topic, m.message_encoding, m.log_time, m.publish_time,
                 m.sequence, m.data) for m in iter_messages(f, str(path), rep)]
    with open(path, "rb") as f:
        theirs = [(c.id, c.topic, c.message_encoding, m.log_time, m.publish_time, m.sequence,
                   m.data) for _s, c, m in make_reader(f).iter_messages(log_time_order=False)]
    assert ours == theirs
    assert not rep.rejected
    with open(path, "rb") as f:
        stats = make_reader(f).get_summary().statistics
    assert len(ours) == stats.message_count


@pytest.mark.parametrize("path", _files(ROSBAG2))
def test_rosbag2_bags_read_without_crashing_every_message_accounted(path):
    rep = IngestReport(units="messages")
    with open(path, "rb") as f:
        n = sum(1 for _ in iter_messages(f, str(path), rep))
    try:
        rec = read(path)
    except NoDataError as exc:
        assert f"no_decoder: {n}" in str(exc)
    else:
        assert rec.report.decoded + rec.report.n_rejected == n


def test_wrong_rmw_bag_counts_its_messages_as_no_decoder():
    path = ROSBAG2 / "rosbag2_tests/resources/mcap/wrong_rmw_test/wrong_rmw_test_0.mcap"
    if not path.is_file():
        pytest.skip(f"{path} is absent")
    rep = IngestReport(units="messages")
    with open(path, "rb") as f:
        ingest(f, str(path), RecordingBuilder(str(path), rep), rep, None)
    assert rep.rejected == {"no_decoder": 7} and rep.decoded == 0
    assert any("'wrong_format'" in w and "'/test_topic'" in w for w in rep.warnings)
    with pytest.raises(NoDataError, match=r"rejected no_decoder: 7\)"):
        read(path)


def _ros2_reference(path: Path, topic: str) -> list:
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory

    with open(path, "rb") as f:
        return [(m.log_time, d) for _s, c, m, d in
                make_reader(f, decoder_factories=[DecoderFactory()])
                .iter_decoded_messages(topics=[topic], log_time_order=False)]


@pytest.mark.parametrize(("bag", "topic", "field"), [
    ("rosbag2_tests/resources/mcap/cdr_test/cdr_test_0.mcap", "/test_topic", "int32_value"),
    ("rosbag2_tests/resources/mcap/cdr_test/cdr_test_0.mcap", "/array_topic",
     "float64_values_default.2"),
    ("rosbag2_py/test/resources/mcap/convert_a/rewriter_a_0.mcap", "b_basictypes",
     "uint8_value"),
])
def test_mapped_ros2_fields_equal_mcap_ros2_decoding(bag, topic, field):
    path = ROSBAG2 / bag
    if not path.is_file():
        pytest.skip(f"{path} is absent")
    from rigtools.ingest.mcap.decoders import get_field

    ref = _ros2_reference(path, topic)
    mapping = ChannelMapping(slow=(SlowSpec("probe", topic=topic, field=field, unit="1"),))
    rec = read(path, mapping=mapping)
    s = rec.slow["probe"]
    want_t = np.sort(np.asarray([t for t, _d in ref], np.float64)) * 1e-9
    assert np.allclose(s.time_s, want_t, rtol=0, atol=1e-6)  # no header: the log times
    assert s.values.tolist() == [float(get_field(d, field)) for _t, d in
                                 sorted(ref, key=lambda x: x[0])]
    assert rec.report.decoded == len(ref)
    assert rec.report.rejected["not_in_mapping"] > 0


def test_mapped_ros2_array_field_as_a_uniform_channel():
    path = ROSBAG2 / "rosbag2_tests/resources/mcap/cdr_test/cdr_test_0.mcap"
    if not path.is_file():
        pytest.skip(f"{path} is absent")
    mapping = ChannelMapping(uniform=(UniformSpec(
        "defaults", 1000.0, topic="/array_topic", field="float64_values_default"),))
    rec = read(path, mapping=mapping)
    ch = rec.channels["defaults"]
    assert ch.sample_rate_Hz == 1000.0
    assert [3.1415, 0.0, -3.1415] == ch.values[:3].tolist()

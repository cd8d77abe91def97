"""Layouts from DBC attributes and from user mapping files; CAN assembly on in-memory frames."""

import numpy as np
import pytest

from rigtools.errors import MappingError
from rigtools.ingest import IngestReport, Provenance, RunMetadata
from rigtools.ingest.builder import RecordingBuilder
from rigtools.ingest.can.assembly import assemble_can
from rigtools.ingest.can.dbc import load_dbc
from rigtools.ingest.can.frames import CanFrameBatch
from rigtools.ingest.layout import can_layout, load_mapping
from rigtools.schemas import schema_path

USER_DBC = """VERSION ""

NS_ :

BS_:

BU_: IMU

BO_ 1792 IMU_ACC: 4 IMU
 SG_ Cnt : 0|8@1+ (1,0) [0|255] "" IMU
 SG_ AccZ : 8|16@1- (0.001,0) [-32.768|32.767] "g" IMU

BO_ 1793 DRIVE: 2 IMU
 SG_ Speed : 0|16@1+ (1,0) [0|65535] "rpm" IMU
"""

MAPPING = """
[run]
run_id = "user-run-7"
gear_set = "fzg-c"
conditions = { torque_Nm = 183.4, bulk_temperature_C = 90.0 }

[[uniform]]
channel = "accel_z"
message = "IMU_ACC"
samples = ["AccZ"]
counter = "Cnt"
sample_rate_Hz = 1000.0
unit = "m/s^2"
scale = 9.80665

[[slow]]
name = "speed_rpm"
message = 1793
signal = "Speed"
"""


def _frames(db, name, rows, t, ids=None):
    msg = db.get_message_by_name(name)
    data = np.array([list(msg.encode(r)) for r in rows], np.uint8)
    n = len(rows)
    return CanFrameBatch(
        np.asarray(t, float), np.full(n, msg.frame_id if ids is None else ids, np.uint32),
        np.zeros(n, bool), np.zeros(n, bool), np.full(n, msg.length, np.uint8), data,
        np.zeros(n, np.int16), np.arange(n, dtype=np.int64), "line",
    )


def _assemble(db, layout, batches):
    rep = IngestReport()
    b = RecordingBuilder("mem", rep)
    assemble_can(batches, layout, b, rep)
    return b.build(RunMetadata(), Provenance("mem", "0" * 64, 0, "test", {}, rep)), rep


def test_user_dbc_through_a_mapping_with_unit_conversion_and_counter_wrap(tmp_path):
    (tmp_path / "user.dbc").write_text(USER_DBC)
    (tmp_path / "map.toml").write_text(MAPPING)
    db = load_dbc(tmp_path / "user.dbc")
    mapping = load_mapping(tmp_path / "map.toml")
    assert mapping.run.run_id == "user-run-7" and mapping.run.conditions["torque_Nm"] == 183.4
    layout = can_layout(db, mapping, "user.dbc")
    n = 600  # 8-bit counter wraps twice
    g = np.round(np.sin(np.arange(n) / 10), 3)
    rows = [{"Cnt": i % 256, "AccZ": g[i]} for i in range(n)]
    del rows[300:305]  # five lost frames
    t = [10 + i / 1000 for i in range(n) if not 300 <= i < 305]
    speed = _frames(db, "DRIVE", [{"Speed": 1500}, {"Speed": 1501}], [10.0, 10.1])
    rec, rep = _assemble(db, layout, [_frames(db, "IMU_ACC", rows, t), speed])
    ch = rec.channels["accel_z"]
    assert ch.unit == "m/s^2" and len(ch) == n
    assert ch.valid.sum() == n - 5 and not ch.valid[300:305].any()
    want = np.array([r * 0.001 for r in np.round(g / 0.001)]) * 9.80665
    np.testing.assert_array_equal(ch.values[ch.valid], want[ch.valid])
    assert [(x.start_index, x.n_missing) for x in rep.gaps] == [(300, 5)]
    assert rec.slow["speed_rpm"].values.tolist() == [1500.0, 1501.0]
    assert rep.decoded == n - 5 + 2


def test_reference_layout_from_dbc_attributes_counts_every_frame():
    db = load_dbc(schema_path("rig_reference.dbc"))
    layout = can_layout(db, None, "rig_reference.dbc")
    assert [u.spec.channel for u in layout.uniform] == ["accel_1", "accel_2", "accel_3", "accel_4"]
    assert {s.spec.name for s in layout.slow} >= {"PinionSpeed_rpm", "Torque_Nm", "BulkTemp_C"}
    rows = [{"Acc1_Counter": c, "Acc1_S0": 0.015 * c, "Acc1_S1": 0.0, "Acc1_S2": -0.015}
            for c in [0, 1, 2, 2, 3]]
    acc = _frames(db, "ACC1", rows, [0.0, 1 / 8533, 2 / 8533, 2 / 8533, 3 / 8533])
    unknown = _frames(db, "ACC1", rows[:2], [0, 0], ids=0x7FF)
    short = _frames(db, "TORQUE", [{"Torque_Nm": 1.0}], [0.0])
    short = CanFrameBatch(short.timestamp_s, short.arbitration_id, short.is_extended,
                          short.is_fd, np.array([1], np.uint8), short.data, short.channel,
                          short.position, "line")
    rec, rep = _assemble(db, layout, [acc, unknown, short])
    assert rep.rejected == {"id_not_in_dbc": 2, "dlc_shorter_than_dbc": 1, "duplicate_frame": 1}
    assert len(rec.channels["accel_1"]) == 12
    assert rec.channels["accel_1"].values[::3].tolist() == [0.0, 0.015, 0.03, 0.045]


@pytest.mark.parametrize(
    ("text", "match"),
    [
        ("[[uniform]]\nchannel='a'\nmessage='M'\nsamples=['x']\nsample_rate_Hz=10\ncolour='red'\n",
         r"map\.toml at line 6: .*'colour' was unexpected"),
        (
            "[[uniform]]\nchannel='a'\nmessage='M'\nsamples=['x']\n",
            r"'sample_rate_Hz' is a required",
        ),
        ("[[slow]]\nname='s'\nmessage='M'\n", r"map\.toml.*expected keys and values allowed"),
        ("[[uniform]\n", r"map\.toml: expected a TOML mapping file"),
    ],
)
def test_malformed_mapping_names_file_key_and_line(tmp_path, text, match):
    p = tmp_path / "map.toml"
    p.write_text(text)
    with pytest.raises(MappingError, match=match):
        load_mapping(p)


def test_mapping_naming_a_missing_signal_is_refused(tmp_path):
    (tmp_path / "user.dbc").write_text(USER_DBC)
    (tmp_path / "map.toml").write_text(MAPPING.replace('"AccZ"', '"AccQ"'))
    with pytest.raises(MappingError, match="no signal 'AccQ'"):
        can_layout(load_dbc(tmp_path / "user.dbc"), load_mapping(tmp_path / "map.toml"))


def test_counter_restart_is_a_restart_gap_and_nothing_after_it_is_lost():
    db = load_dbc(schema_path("rig_reference.dbc"))
    layout = can_layout(db, None, "rig_reference.dbc")
    counters = [*range(1000, 1100), *range(0, 100)]
    rows = [{"Acc1_Counter": c, "Acc1_S0": 0.0, "Acc1_S1": 0.015, "Acc1_S2": 0.03}
            for c in counters]
    t = [i * 3 / 25600 for i in range(100)] + [1.0 + i * 3 / 25600 for i in range(100)]
    rec, rep = _assemble(db, layout, [_frames(db, "ACC1", rows, t)])
    ch = rec.channels["accel_1"]
    assert ch.valid.sum() == 600
    assert [g.kind for g in rep.gaps] == ["restart"]
    assert any("restarted" in w for w in rep.warnings)


def test_non_finite_numbers_in_a_mapping_are_refused(tmp_path):
    p = tmp_path / "map.toml"
    p.write_text(MAPPING.replace("scale = 9.80665", "scale = nan"))
    with pytest.raises(MappingError, match=r"line \d+: expected a finite number for uniform\[0\]"):
        load_mapping(p)


def test_mcap_only_mapping_on_a_can_log_says_so(tmp_path):
    p = tmp_path / "map.toml"
    p.write_text("[[uniform]]\nchannel='a'\ntopic='/imu'\nfield='x'\nsample_rate_Hz=100\n")
    db = load_dbc(schema_path("rig_reference.dbc"))
    with pytest.raises(MappingError, match="only MCAP entries"):
        can_layout(db, load_mapping(p))


def test_same_layout_on_two_buses_gives_two_channels_not_one_interleaved():
    import dataclasses

    db = load_dbc(schema_path("rig_reference.dbc"))
    layout = can_layout(db, None, "rig_reference.dbc")
    rows = [{"Acc1_Counter": c, "Acc1_S0": 0.015 * c, "Acc1_S1": 0.0, "Acc1_S2": 0.0}
            for c in range(50)]
    t = [c * 3 / 25600 for c in range(50)]
    a = _frames(db, "ACC1", rows, t)
    b = dataclasses.replace(_frames(db, "ACC1", [dict(r, Acc1_S1=1.5) for r in rows], t),
                            channel=np.ones(50, np.int16))
    rec, rep = _assemble(db, layout, [a, b])
    assert set(rec.channels) == {"accel_1@bus0", "accel_1@bus1"}
    assert rec.channels["accel_1@bus0"].values[1::3].tolist() == [0.0] * 50
    assert rec.channels["accel_1@bus1"].values[1::3].tolist() == [1.5] * 50
    assert not rep.rejected and any("kept apart" in w for w in rep.warnings)

"""Campaign manifests and the observations table, on a small synthetic campaign.

The campaign is built in a temporary folder from :func:`rigtools.demo.synthetic.synthetic_run`:
run A as MCAP (1.5 s, torque and temperature given as numbers), run B as a reference-layout BLF
with ten frames of accel_1 dropped (conditions read from its slow signals), run C a file that
does not exist.

Truth: the synthetic mode is an SDOF mapped to a digital filter by impulse invariance (poles
exact), so its damping ratio is the nominal one; f_n = 2950 Hz sits clear of the mesh
harmonics and sidebands at 1500 rpm (400 Hz).
"""

from __future__ import annotations

import json
import math
import re
from pathlib import Path

import numpy as np
import pandas as pd
import pyarrow.parquet as pq
import pytest

from rigtools.campaign import (
    FLAGS,
    load_campaign,
    observation_columns,
    observe_campaign,
    read_observations,
    to_frame,
    validate_observations,
    write_observations,
)
from rigtools.campaign.observation_table import METADATA_KEY, SCHEMA_METADATA_KEY
from rigtools.demo.can_writer import encode_reference_frames, write_can_log
from rigtools.demo.mcap_writer import write_accel_mcap
from rigtools.demo.synthetic import synthetic_run
from rigtools.errors import CampaignError
from rigtools.schemas import load_schema

F_N = 2950.0
ZETA = 0.02
FS = 25_600.0
SPEED = 1500.0
Z1 = 16
AMPS = (4.0, 1.5, 0.8)  # synthetic mesh harmonics on accel_1 (accel_2: / 1.3)


def write_mcap_run(path: Path, *, seed: int, duration_s: float = 1.5, **kw) -> Path:
    run = synthetic_run(duration_s, rng=seed, n_channels=2, f_n_Hz=F_N, zeta=ZETA, **kw)
    chans = {k: (v, run.sample_rate_Hz, "m/s^2", 0, run.start_time_s)
             for k, v in run.channels.items()}
    return write_accel_mcap(path, chans, run.slow, None)


def write_blf_run(path: Path, *, seed: int, drop_accel_1: int = 0, duration_s: float = 1.5,
                  **kw) -> Path:
    run = synthetic_run(duration_s, rng=seed, n_channels=2, f_n_Hz=F_N, zeta=ZETA, **kw)
    slow = {name: vals for name, (_, vals, _) in run.slow.items()}
    frames = encode_reference_frames([run.channels["accel_1"], run.channels["accel_2"]], slow,
                                     start_time_s=run.start_time_s, rng=1)
    if drop_accel_1:
        keep = np.ones(len(frames), bool)
        acc1 = np.flatnonzero(frames.arbitration_id == 256)
        keep[acc1[2000:2000 + drop_accel_1]] = False
        frames = frames.take(keep)
    return write_can_log(path, frames, "blf", engine="rigtools")


CAMPAIGN = """\
[campaign]
name = "synthetic study"
gear_set = "fzg-c"

[sensors]
accel = ["accel_1", "accel_2"]
speed = "PinionSpeed_rpm"

[thermal]
reference_temperature_C = 20.0
housing = "fixed-centre-distance"

[analysis]
nperseg = 2048
min_step_duration_s = 0.5

[[run]]
id = "A"
file = "runs/a.mcap"
torque_Nm = 302.0
bulk_temperature_C = 90.0
speed_rpm = 1500.0

[[run]]
id = "B"
file = "runs/b.blf"
torque_Nm = "Torque_Nm"
bulk_temperature_C = "BulkTemp_C"

[[run]]
id = "C"
file = "runs/missing.mcap"
torque_Nm = 100.0
"""


@pytest.fixture(scope="module")
def campaign_dir(tmp_path_factory) -> Path:
    d = tmp_path_factory.mktemp("campaign")
    (d / "runs").mkdir()
    write_mcap_run(d / "runs" / "a.mcap", seed=1)
    write_blf_run(d / "runs" / "b.blf", seed=2, drop_accel_1=10, torque_Nm=150.0,
                  bulk_temperature_C=70.0)
    (d / "study.toml").write_text(CAMPAIGN, encoding="utf-8")
    return d


@pytest.fixture(scope="module")
def observed(campaign_dir):
    return observe_campaign(load_campaign(campaign_dir / "study.toml"))


def rows(df: pd.DataFrame, **eq) -> pd.DataFrame:
    sel = np.ones(len(df), bool)
    for k, v in eq.items():
        sel &= (df[k] == v).to_numpy(dtype=bool, na_value=False)
    return df[sel]


# --------------------------------------------------------------------------------------------
# the campaign manifest


def test_campaign_loads_with_paths_relative_to_the_file(campaign_dir):
    c = load_campaign(campaign_dir / "study.toml")
    assert c.name == "synthetic study" and c.gear_set == "fzg-c"
    assert (c.pinion_teeth, c.wheel_teeth) == (16, 24)
    assert [r.id for r in c.runs] == ["A", "B", "C"]
    assert c.runs[0].file == campaign_dir / "runs" / "a.mcap"
    assert c.runs[0].torque_Nm == 302.0 and c.runs[1].torque_Nm == "Torque_Nm"
    assert c.runs[0].line == 17 and c.runs[2].line == 30
    assert c.sensors.speed == "PinionSpeed_rpm" and c.sensors.accel == ("accel_1", "accel_2")
    assert c.thermal.housing == "fixed-centre-distance"
    assert c.analysis.nperseg == 2048 and c.analysis.prominence_dB == 6.0  # default kept
    json.dumps(c.to_dict())  # JSON-ready
    with pytest.raises(AttributeError):
        c.name = "other"  # frozen


def test_gear_set_may_be_a_path_of_the_users_own(tmp_path):
    from models.geometry.gear_sets import gear_set_path

    (tmp_path / "gears").mkdir()
    text = gear_set_path("fzg-c").read_text().replace('name = "fzg-c"', 'name = "mine"')
    (tmp_path / "gears" / "mine.toml").write_text(text)
    body = CAMPAIGN.replace('gear_set = "fzg-c"', 'gear_set = "gears/mine.toml"')
    (tmp_path / "c.toml").write_text(body)
    c = load_campaign(tmp_path / "c.toml")
    assert c.gear.name == "mine" and c.gear_set_path == str(tmp_path / "gears" / "mine.toml")
    assert c.pinion_teeth == 16


_BAD = [
    # (replace this, with this, error naming ...)
    ('torque_Nm = "Torque_Nm"', 'torque_nm = "Torque_Nm"',
     r"at line 27: .*found unknown key 'torque_nm' \(did you mean 'torque_Nm'\?\)"),
    ("[thermal]", "[thermals]", r"at line 9: .*found unknown key 'thermals'"),
    ('speed = "PinionSpeed_rpm"', 'speed = "PinionSpeed_rpm"\ndbc = "nope.dbc"',
     r"at line 8: expected sensors.dbc to name an existing file.*'nope.dbc'"),
    ('housing = "fixed-centre-distance"', 'housing = "floating"',
     r"at line 11: .*thermal.housing.*'floating' is not one of"),
    ("bulk_temperature_C = 90.0", "bulk_temperature_C = true",
     r"at line 21: .*run\[0\].bulk_temperature_C.*True is not of type"),
    ("bulk_temperature_C = 90.0", "bulk_temperature_C = nan",
     r"at line 21: expected a finite number for run\[0\].bulk_temperature_C, found nan"),
    ('id = "B"', 'id = "A"', r"at line 25: expected a unique run id, found 'A' again "
     r"\(first in run 1, line 18\)"),
    ('file = "runs/b.blf"\n', "", r"at line 24: expected key 'file' in \[\[run\]\]"),
    ('gear_set = "fzg-c"', 'gear_set = "fzg-x"', r"at line 3: .*shipped gear set.*'fzg-x'"),
    ("nperseg = 2048", "nperseg = 2048.5", r"at line 14: .*analysis.nperseg"),
    ("nperseg = 2048", "nperseg = = 2048", r"at line 14, column 11: expected a TOML file"),
]


@pytest.mark.parametrize(("old", "new", "match"), _BAD, ids=[b[2][:24] for b in _BAD])
def test_bad_campaign_names_the_key_and_its_line(tmp_path, old, new, match):
    assert old in CAMPAIGN
    p = tmp_path / "bad.toml"
    p.write_text(CAMPAIGN.replace(old, new, 1))
    with pytest.raises(CampaignError, match=match) as exc:
        load_campaign(p)
    assert str(exc.value).startswith(str(p))


def test_missing_campaign_file_is_a_campaign_error(tmp_path):
    with pytest.raises(CampaignError, match="no such file"):
        load_campaign(tmp_path / "none.toml")


def test_campaign_error_survives_pickling(tmp_path):
    import pickle

    p = tmp_path / "bad.toml"
    p.write_text(CAMPAIGN.replace("[thermal]", "[thermals]"))
    with pytest.raises(CampaignError) as exc:
        load_campaign(p)
    back = pickle.loads(pickle.dumps(exc.value))
    assert str(back) == str(exc.value) and back.position == "line 9"


# --------------------------------------------------------------------------------------------
# the table


def test_natural_frequency_recovered_near_the_synthetic_truth(observed):
    df = observed.table
    modes = rows(df, quantity="natural_frequency", peak_kind="structural", mode_index=0)
    assert set(zip(modes.run_id, modes.channel, strict=True)) == {
        ("A", "accel_1"), ("A", "accel_2"), ("B", "accel_1"), ("B", "accel_2")}
    zd = ZETA
    for r in modes.itertuples():
        assert 0 < r.f_n_std_Hz < 10
        assert abs(r.f_n_Hz - F_N) < max(3 * r.f_n_std_Hz, 5.0), (r.run_id, r.channel, r.f_n_Hz)
        assert 0 < r.zeta_std < 0.005
        # 1.5 s records: the scatter of zeta over seeds is about 0.002 (11 %)
        assert abs(r.zeta - zd) < max(3 * r.zeta_std, 0.3 * zd), (r.run_id, r.channel, r.zeta)
        assert r.prominence_dB > 20 and not r.flag_low_snr
    # the mean over four channels, within the combined uncertainty
    assert abs(modes.f_n_Hz.mean() - F_N) < 3 * math.sqrt((modes.f_n_std_Hz**2).sum()) / 4 + 1


def test_rms_matches_the_time_domain_rms_of_the_samples(observed, campaign_dir):
    from rigtools.ingest import read

    rec = read(campaign_dir / "runs" / "a.mcap")
    df = observed.table
    for ch in ("accel_1", "accel_2"):
        row = rows(df, run_id="A", channel=ch, quantity="rms").iloc[0]
        x = rec.channels[ch].values
        np.testing.assert_allclose(row.rms_m_s2, np.std(x), rtol=2e-3)
        np.testing.assert_allclose(row.rms_parseval_m_s2, row.rms_m_s2, rtol=0.05)
        assert row.n_windows > 10 and row.status == "ok"


def test_arms_per_speed_step_near_the_synthetic_harmonics(observed):
    df = observed.table
    arms = rows(df, run_id="A", quantity="arms")
    assert list(arms.channel) == ["accel_1", "accel_2"]
    assert (arms.step_index == 0).all() and (arms.status != "failed").all()
    assert not arms.flag_gaps.any()
    for r, gain in zip(arms.itertuples(), (1.0, 1 / 1.3), strict=True):
        np.testing.assert_allclose(r.step_speed_rpm, SPEED, rtol=1e-3)
        np.testing.assert_allclose(r.mesh_frequency_Hz, Z1 * SPEED / 60, rtol=1e-3)
        np.testing.assert_allclose([r.a1_m_s2, r.a2_m_s2, r.a3_m_s2],
                                   np.array(AMPS) * gain, rtol=0.1)
        np.testing.assert_allclose(r.arms_m_s2, math.hypot(r.a1_m_s2, r.a2_m_s2, r.a3_m_s2))
        assert 0 <= r.step_start_s < r.step_stop_s <= 1.5
        assert r.n_windows >= 1


def test_conditions_as_numbers_or_read_from_slow_signals(observed):
    df = observed.table
    a = rows(df, run_id="A", quantity="run").iloc[0]
    assert (a.torque_Nm, a.bulk_temperature_C, a.speed_rpm) == (302.0, 90.0, 1500.0)
    assert np.isnan(a.oil_temperature_C)
    b = rows(df, run_id="B", quantity="run").iloc[0]
    assert abs(b.torque_Nm - 150.0) < 0.5  # mean of the Torque_Nm slow signal
    assert abs(b.bulk_temperature_C - 70.0) < 0.1
    assert abs(b.speed_rpm - SPEED) < 0.5  # no speed given: the mean of [sensors] speed
    np.testing.assert_allclose(b.mesh_frequency_Hz, Z1 * b.speed_rpm / 60)
    # every row of a run carries its conditions
    assert (rows(df, run_id="B").torque_Nm == b.torque_Nm).all()


def test_gaps_are_flagged_on_the_channel_and_its_steps(observed):
    df = observed.table
    b1 = rows(df, run_id="B", channel="accel_1", quantity="rms").iloc[0]
    assert b1.flag_gaps and b1.n_invalid == 30 and b1.n_gaps == 1 and b1.status == "flagged"
    assert "gaps" in b1.quality_flags.split(";")
    b2 = rows(df, run_id="B", channel="accel_2", quantity="rms").iloc[0]
    assert not b2.flag_gaps and b2.n_invalid == 0 and b2.status == "ok"
    step = rows(df, run_id="B", channel="accel_1", quantity="arms").iloc[0]
    assert step.flag_gaps and step.flag_windows_dropped and step.n_gaps == 1
    run = rows(df, run_id="B", quantity="run").iloc[0]
    assert run.n_gaps == 1 and run.flag_gaps and "30 sample(s) missing" in run.message


def test_missing_run_file_is_flagged_and_the_others_succeed(observed):
    assert observed.n_analysed == 2
    (failed,) = observed.failures
    assert failed.run_id == "C" and "missing.mcap" in failed.error
    assert "no such file" in failed.error
    df = observed.table
    c = rows(df, run_id="C")
    assert len(c) == 1
    row = c.iloc[0]
    assert row.quantity == "run" and row.status == "failed" and row.quality_flags == "run_failed"
    assert "missing.mcap" in row.message and row.torque_Nm == 100.0
    assert row.source_sha256 is None and row.source_file == "runs/missing.mcap"
    for run_id in ("A", "B"):
        assert rows(df, run_id=run_id, quantity="run").iloc[0].status != "failed"


def test_provenance_on_every_row(observed, campaign_dir):
    import hashlib

    from rigtools import __version__

    df = observed.table
    a = rows(df, run_id="A")
    digest = hashlib.sha256((campaign_dir / "runs" / "a.mcap").read_bytes()).hexdigest()
    assert (a.source_sha256 == digest).all() and (a.reader == "mcap").all()
    assert (df.rigtools_version == __version__).all()
    assert (df.campaign == "synthetic study").all()


def test_table_is_valid_against_the_schema_and_round_trips(observed, tmp_path):
    df = observed.table
    assert list(df.columns) == list(observation_columns())
    assert validate_observations(df) == []
    assert set(df.quantity) == {"run", "rms", "natural_frequency", "arms"}
    for flags in df.quality_flags:
        assert all(f in FLAGS for f in flags.split(";") if f)
    out = write_observations(observed, tmp_path / "obs.parquet")
    kv = pq.read_schema(out).metadata
    assert json.loads(kv[SCHEMA_METADATA_KEY.encode()]) == load_schema("observations.schema.json")
    meta = json.loads(kv[METADATA_KEY.encode()])
    assert meta["campaign"]["campaign"]["name"] == "synthetic study"
    assert meta["gear"] == {"name": "fzg-c", "z1": 16, "z2": 24}
    assert "numpy" in meta["versions"]
    assert [r["analysed"] for r in meta["runs"]] == [True, True, False]
    back = read_observations(out)
    pd.testing.assert_frame_equal(back, df)
    assert back.attrs["rigtools"]["campaign"]["analysis"]["nperseg"] == 2048
    assert validate_observations(back) == []


def test_validation_catches_a_broken_table(observed):
    df = observed.table.copy()
    i = int(np.flatnonzero(df.quantity == "natural_frequency")[0])
    df.loc[i, "f_n_Hz"] = np.nan
    errors = validate_observations(df)
    assert errors and errors[0][0] == f"$[{i}].f_n_Hz"
    df2 = observed.table.copy()
    df2.loc[0, "quantity"] = "power"
    assert any("'power' is not one of" in m for _, m in validate_observations(df2))
    df3 = observed.table.assign(extra_col=1.0)
    assert validate_observations(df3)[0] == ("$", "columns not in the schema: ['extra_col']")


def test_to_frame_fills_every_column_with_its_dtype():
    df = to_frame([{"campaign": "c", "run_id": "r", "quantity": "run", "status": "ok",
                    "quality_flags": "", "message": "", "source_file": "x",
                    "rigtools_version": "0"}])
    assert df.dtypes["f_n_Hz"] == np.float64 and np.isnan(df.f_n_Hz[0])
    assert str(df.dtypes["n_windows"]) == "Int64" and df.n_windows.isna()[0]
    assert str(df.dtypes["flag_low_snr"]) == "boolean"
    assert validate_observations(df) == []


# --------------------------------------------------------------------------------------------
# channels that fail, flags


def test_failed_channels_get_failed_rows_and_low_snr_is_flagged(tmp_path):
    run = synthetic_run(1.0, rng=4, n_channels=2, f_n_Hz=F_N)
    t = run.start_time_s
    chans = {"accel_1": (run.channels["accel_1"], FS, "m/s^2", 0, t),
             "accel_dead": (np.full(run.channels["accel_1"].size, 0.3), FS, "m/s^2", 0, t),
             "accel_g": (run.channels["accel_2"] / 9.80665, FS, "g", 0, t)}
    write_accel_mcap(tmp_path / "r.mcap", chans, None, None)  # no slow signals at all
    (tmp_path / "c.toml").write_text("""\
[campaign]
name = "edge cases"
gear_set = "fzg-c"
[sensors]
accel = ["accel_1", "accel_dead", "accel_g", "accel_9"]
speed = "PinionSpeed_rpm"
[analysis]
nperseg = 2048
low_snr_dB = 60
[[run]]
id = "R"
file = "r.mcap"
speed_rpm = 1500.0
torque_Nm = "Torque_Nm"
""")
    obs = observe_campaign(load_campaign(tmp_path / "c.toml"))
    df = obs.table
    assert validate_observations(df) == []
    assert obs.n_analysed == 1
    dead = rows(df, channel="accel_dead", quantity="rms").iloc[0]
    assert dead.status == "failed" and "constant" in dead.quality_flags
    assert "constant" in dead.message
    missing = rows(df, channel="accel_9", quantity="rms").iloc[0]
    assert missing.status == "failed" and missing.quality_flags == "channel_missing"
    # a channel in g: RMS converted to m/s^2 at the edge
    g = rows(df, channel="accel_g", quantity="rms").iloc[0]
    np.testing.assert_allclose(g.rms_m_s2, np.std(run.channels["accel_2"]), rtol=2e-3)
    # every mode is under the 60 dB threshold: flagged, not dropped
    modes = rows(df, quantity="natural_frequency")
    assert len(modes) >= 2 and modes.flag_low_snr.all() and (modes.status == "flagged").all()
    # the speed signal is missing: Arms rows fail, naming it, on the analysed channels
    arms = rows(df, quantity="arms")
    assert set(arms.channel) == {"accel_1", "accel_g"}
    assert (arms.status == "failed").all() and (arms.quality_flags == "speed_missing").all()
    assert "PinionSpeed_rpm" in arms.message.iloc[0]
    run_row = rows(df, quantity="run").iloc[0]
    assert {"condition_unresolved", "channel_missing"} <= set(run_row.quality_flags.split(";"))
    assert np.isnan(run_row.torque_Nm) and "Torque_Nm" in run_row.message
    assert any("accel_9" in w for w in obs.runs[0].warnings)


def test_no_run_analysed(tmp_path):
    (tmp_path / "c.toml").write_text(CAMPAIGN)
    obs = observe_campaign(load_campaign(tmp_path / "c.toml"))
    assert obs.n_analysed == 0 and len(obs.failures) == 3
    assert list(obs.table.quantity) == ["run"] * 3
    assert validate_observations(obs.table) == []


# --------------------------------------------------------------------------------------------
# ramped run-ups, run status from its rows (review findings)


def test_ramped_run_up_gives_arms_along_the_ramp_and_flags_the_swept_mesh_line(tmp_path):
    from scipy.signal import lfilter

    from rigtools.cli.observe import format_summary

    n0, n1, dur, st = 600.0, 3000.0, 2.0, 1_763_800_000.0
    n = int(FS * dur)
    t = np.arange(n) / FS
    rpm = n0 + (n1 - n0) * t / dur
    theta = np.cumsum(rpm / 60.0) / FS  # pinion revolutions
    x = sum(a * np.sin(2 * np.pi * h * Z1 * theta) for h, a in zip((1, 2, 3), AMPS, strict=True))
    rng = np.random.default_rng(0)
    # plus a structural resonance (white noise through an SDOF at F_N), so the run has a mode
    r, wd = math.exp(-ZETA * 2 * math.pi * F_N / FS), 2 * math.pi * F_N / FS
    x = x + rng.normal(0.0, 1.0, n) + 0.05 * lfilter([1.0], [1.0, -2 * r * math.cos(wd), r * r],
                                                      rng.normal(0.0, 1.0, n))
    ts = np.arange(0.0, dur, 0.05)
    slow = {"PinionSpeed_rpm": (st + ts, n0 + (n1 - n0) * ts / dur, "rpm")}
    write_accel_mcap(tmp_path / "ramp.mcap", {"accel_1": (x, FS, "m/s^2", 0, st)}, slow, None)
    (tmp_path / "c.toml").write_text("""\
[campaign]
name = "ramp"
gear_set = "fzg-c"
[sensors]
accel = ["accel_1"]
speed = "PinionSpeed_rpm"
[[run]]
id = "R"
file = "ramp.mcap"
torque_Nm = 300.0
""")
    obs = observe_campaign(load_campaign(tmp_path / "c.toml"))
    df = obs.table
    assert validate_observations(df) == []
    arms = rows(df, quantity="arms")
    # no plateau: Arms per window along the ramp, not a failed no_speed_step row
    assert len(arms) >= 10 and (arms.segment == "ramp").all() and (arms.status == "ok").all()
    assert list(arms.step_index) == list(range(len(arms)))
    assert arms.step_speed_rpm.is_monotonic_increasing
    assert arms.step_speed_rpm.min() < 1400 and arms.step_speed_rpm.max() > 2500
    mid = 0.5 * (arms.step_start_s + arms.step_stop_s)
    np.testing.assert_allclose(arms.step_speed_rpm, n0 + (n1 - n0) * mid / dur, rtol=0.02)
    np.testing.assert_allclose(arms.mesh_frequency_Hz, Z1 * arms.step_speed_rpm / 60, rtol=1e-9)
    for col, amp in zip(("a1_m_s2", "a2_m_s2", "a3_m_s2"), AMPS, strict=True):
        np.testing.assert_allclose(arms[col].median(), amp, rtol=0.05)
    np.testing.assert_allclose(arms.arms_m_s2.median(), math.sqrt(sum(a * a for a in AMPS)),
                               rtol=0.05)
    # the swept mesh line is not reported as a clean mode
    modes = rows(df, quantity="natural_frequency")
    assert len(modes) >= 1
    assert (modes.status == "flagged").all()
    assert all("speed_varies" in f.split(";") for f in modes.quality_flags)
    assert all("swept mesh line" in m for m in modes.message)
    run_row = rows(df, quantity="run").iloc[0]
    assert run_row.status == "flagged" and "speed_varies" in run_row.quality_flags
    line = format_summary(obs).splitlines()[1].split()
    # no clean mode: the summary shows the lowest flagged one, marked (issue 17 item 7)
    lowest = modes.sort_values("mode_index").groupby("channel").head(1).f_n_Hz.median()
    assert line[1] == "flagged" and line[3] == f"0/{len(modes)}"
    assert line[4] == f"{lowest:.1f}*"
    assert line[6] == "ramp"


def test_steady_speed_arms_rows_are_steps_and_modes_not_speed_varies(observed):
    df = observed.table
    arms = rows(df, run_id="A", quantity="arms")
    assert len(arms) and (arms.segment == "step").all()
    modes = rows(df, quantity="natural_frequency")
    assert not any("speed_varies" in f for f in modes.quality_flags)


@pytest.fixture(scope="module")
def problem_campaign(tmp_path_factory) -> Path:
    """Runs: clean; a dead (constant) channel; a clipped channel; no speed signal."""
    d = tmp_path_factory.mktemp("problems")
    run = synthetic_run(1.0, rng=5, n_channels=2, f_n_Hz=F_N, zeta=ZETA)
    t = run.start_time_s
    a1, a2 = run.channels["accel_1"], run.channels["accel_2"]
    lim = 0.5 * float(np.max(np.abs(a2)))
    variants = {
        "clean": {"accel_1": a1, "accel_2": a2},
        "dead": {"accel_1": a1, "accel_2": np.full(a2.size, 0.3)},
        "clip": {"accel_1": a1, "accel_2": np.clip(a2, -lim, lim)},
        "nospeed": {"accel_1": a1, "accel_2": a2},
    }
    toml = ['[campaign]\nname = "problems"\ngear_set = "fzg-c"\n[sensors]\n'
            'accel = ["accel_1", "accel_2"]\nspeed = "PinionSpeed_rpm"\n'
            '[analysis]\nnperseg = 2048\nmin_step_duration_s = 0.5\n']
    for rid, ch in variants.items():
        slow = {k: v for k, v in run.slow.items() if rid != "nospeed" or k != "PinionSpeed_rpm"}
        write_accel_mcap(d / f"{rid}.mcap", {k: (v, FS, "m/s^2", 0, t) for k, v in ch.items()},
                         slow, None)
        toml.append(f'[[run]]\nid = "{rid}"\nfile = "{rid}.mcap"\ntorque_Nm = 302.0\n')
    (d / "c.toml").write_text("\n".join(toml))
    return d


@pytest.fixture(scope="module")
def problems(problem_campaign):
    return observe_campaign(load_campaign(problem_campaign / "c.toml"))


def test_run_status_is_flagged_when_a_row_of_the_run_fails_or_is_flagged(problems):
    df = problems.table
    assert validate_observations(df) == []
    assert problems.n_analysed == 4
    run = {r.run_id: r for r in rows(df, quantity="run").itertuples()}
    assert run["clean"].status == "ok" and run["clean"].quality_flags == ""
    # a dead channel: its rms row failed, the run is flagged and says which channel and why
    assert rows(df, run_id="dead", channel="accel_2", quantity="rms").iloc[0].status == "failed"
    assert run["dead"].status == "flagged" and "constant" in run["dead"].quality_flags
    assert "accel_2: rms failed (constant)" in run["dead"].message
    # a clipped channel
    assert run["clip"].status == "flagged" and run["clip"].flag_clipping
    assert "accel_2" in run["clip"].message and "clipping" in run["clip"].message
    # no speed signal: Arms rows fail, the run is flagged and warns, naming the run
    arms = rows(df, run_id="nospeed", quantity="arms")
    assert len(arms) == 2 and (arms.quality_flags == "speed_missing").all()
    assert run["nospeed"].status == "flagged" and "speed_missing" in run["nospeed"].quality_flags
    r = next(r for r in problems.runs if r.run_id == "nospeed")
    assert any(w.startswith("nospeed: ") and "PinionSpeed_rpm" in w for w in r.warnings)


def test_clipped_channel_peaks_are_flagged_and_not_clean_modes(problems):
    from rigtools.cli.observe import format_summary

    df = problems.table
    clipped = rows(df, run_id="clip", channel="accel_2", quantity="natural_frequency")
    other = rows(df, run_id="clip", channel="accel_1", quantity="natural_frequency")
    assert len(clipped) >= 1 and len(other) >= 1
    assert clipped.flag_clipping.all() and (clipped.status == "flagged").all()
    assert all("clipping" in f.split(";") for f in clipped.quality_flags)
    assert not other.flag_clipping.any()
    lines = {ln.split()[0]: ln.split() for ln in format_summary(problems).splitlines()[1:]}
    n_clean = int((rows(df, run_id="clip", quantity="natural_frequency").status == "ok").sum())
    assert n_clean == int((other.status == "ok").sum())
    assert lines["clip"][3] == f"{n_clean}/{len(clipped) + len(other)}"


def test_observe_warns_on_stderr_when_the_speed_signal_is_missing(problem_campaign, tmp_path,
                                                                  capsys):
    from rigtools.cli import main

    out = tmp_path / "o.parquet"
    assert main(["observe", str(problem_campaign / "c.toml"), "-o", str(out)]) == 0
    err = capsys.readouterr().err
    assert re.search(r"rigtools: warning: nospeed: speed signal 'PinionSpeed_rpm'", err)
    assert "warning: clean" not in err
    assert validate_observations(read_observations(out)) == []

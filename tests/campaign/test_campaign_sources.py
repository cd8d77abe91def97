"""Campaigns as they really are (issue 19 item 2): per-run sensors, globs, ``[report]``.

Also the observe split (``observe_run`` = ``read_run`` + ``observe_recording``) and the spectra
it keeps.

The mixed campaign holds two loggers: run ``M`` an MCAP file (channels ``accel_1``,
``accel_2``, from :func:`rigtools.demo.mcap_writer.write_accel_mcap`) and run ``T`` a BLF of
the triaxial CAN layout (:mod:`rigtools.demo.triax_can`: its own DBC and mapping, channels
``accel_x``, ``accel_y``, ``accel_z``). Neither layout is the campaign's: each run names its
own ``dbc``/``map``/``format``/``accel``. Without them the triaxial log decodes nothing with
the reference DBC (every frame ``id_not_in_dbc``).

Truth: :func:`rigtools.demo.synthetic.synthetic_run`'s single mode at 2950 Hz (an SDOF mapped
to a digital filter by impulse invariance), clear of the mesh lines at 1500 rpm (400 Hz).
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from rigtools.campaign import (
    Sensors,
    load_campaign,
    observe_campaign,
    observe_recording,
    observe_run,
    read_run,
    to_frame,
)
from rigtools.demo.can_writer import write_can_log
from rigtools.demo.mcap_writer import write_accel_mcap
from rigtools.demo.synthetic import synthetic_run
from rigtools.demo.triax_can import encode_triax_frames, write_triax_layout
from rigtools.errors import CampaignError, RecordingFormatError

F_N = 2950.0
DURATION_S = 1.0


def write_mcap(path: Path, *, seed: int) -> Path:
    run = synthetic_run(DURATION_S, rng=seed, n_channels=2, f_n_Hz=F_N)
    chans = {k: (v, run.sample_rate_Hz, "m/s^2", 0, run.start_time_s)
             for k, v in run.channels.items()}
    return write_accel_mcap(path, chans, run.slow, None)


def write_triax_blf(path: Path, dbc: Path, *, seed: int) -> Path:
    run = synthetic_run(DURATION_S, rng=seed, n_channels=3, f_n_Hz=F_N)
    acc = np.column_stack([run.channels[f"accel_{i}"] for i in (1, 2, 3)])
    frames = encode_triax_frames(acc, {"PinionSpeed_rpm": 1500.0, "Torque_Nm": 150.0,
                                       "BulkTemp_C": 70.0, "OilTemp_C": 65.0},
                                 dbc=dbc, start_time_s=run.start_time_s)
    return write_can_log(path, frames, "blf", engine="rigtools")


MIXED = """\
[campaign]
name = "two loggers"
gear_set = "fzg-c"

[sensors]
speed = "PinionSpeed_rpm"

[analysis]
nperseg = 2048
min_step_duration_s = 0.5

[report]
title = "two loggers, one report"
f_n_rel_tolerance = 0.02
f_n_z_tolerance = 3.0
backlash_range_um = [5.0, 40.0]
min_margin_um = 0.0

[[run]]
id = "M"
file = "mcap/m.mcap"
format = "mcap"
accel = ["accel_1", "accel_2"]
torque_Nm = 302.0
bulk_temperature_C = 90.0
speed_rpm = 1500.0

[[run]]
id = "T"
file = "can/t.blf"
dbc = "layout/triax.dbc"
map = "layout/triax-map.toml"
format = "blf"
accel = ["accel_x", "accel_y"]
torque_Nm = "Torque_Nm"
bulk_temperature_C = "BulkTemp_C"
"""


@pytest.fixture(scope="module")
def mixed_dir(tmp_path_factory) -> Path:
    d = tmp_path_factory.mktemp("mixed")
    for sub in ("mcap", "can", "layout"):
        (d / sub).mkdir()
    dbc, _mapping = write_triax_layout(d / "layout")
    write_mcap(d / "mcap" / "m.mcap", seed=1)
    write_triax_blf(d / "can" / "t.blf", dbc, seed=2)
    (d / "mixed.toml").write_text(MIXED, encoding="utf-8")
    return d


@pytest.fixture(scope="module")
def mixed(mixed_dir):
    return load_campaign(mixed_dir / "mixed.toml")


@pytest.fixture(scope="module")
def mixed_observed(mixed):
    return observe_campaign(mixed)


# --------------------------------------------------------------------------------------------
# per-run sensors


def test_runs_override_the_sensors_key_by_key(mixed, mixed_dir):
    m, t = mixed.runs
    assert mixed.sensors == Sensors(speed="PinionSpeed_rpm")
    assert m.overrides == ("format", "accel") and t.overrides == ("dbc", "map", "format", "accel")
    sm, st = mixed.sensors_for(m), mixed.sensors_for(t)
    assert sm == Sensors(speed="PinionSpeed_rpm", format="mcap", accel=("accel_1", "accel_2"))
    assert st == Sensors(dbc=mixed_dir / "layout" / "triax.dbc",
                         mapping=mixed_dir / "layout" / "triax-map.toml", format="blf",
                         accel=("accel_x", "accel_y"), speed="PinionSpeed_rpm")
    d = mixed.to_dict()
    json.dumps(d)
    assert d["run"][0]["sensors"] == {"format": "mcap", "accel": ["accel_1", "accel_2"]}
    assert d["run"][1]["sensors"]["dbc"] == str(mixed_dir / "layout" / "triax.dbc")
    assert d["sensors"]["format"] is None


def test_an_empty_dbc_or_map_drops_the_campaigns(mixed_dir, tmp_path):
    text = MIXED.replace('speed = "PinionSpeed_rpm"',
                         'speed = "PinionSpeed_rpm"\ndbc = "layout/triax.dbc"\n'
                         'map = "layout/triax-map.toml"\nformat = "blf"', 1)
    text = text.replace('format = "mcap"', 'format = "mcap"\ndbc = ""\nmap = ""', 1)
    p = mixed_dir / "dropping.toml"
    p.write_text(text, encoding="utf-8")
    c = load_campaign(p)
    m, t = c.runs
    assert c.sensors_for(m).dbc is None and c.sensors_for(m).mapping is None
    assert c.sensors_for(m).format == "mcap"
    assert c.sensors_for(t).dbc == mixed_dir / "layout" / "triax.dbc"


def test_an_mcap_run_and_a_can_run_of_another_layout_decode_in_one_campaign(mixed,
                                                                           mixed_observed):
    assert [r.analysed for r in mixed_observed.runs] == [True, True], [
        r.error for r in mixed_observed.runs]
    df = mixed_observed.table
    rms = df[df.quantity == "rms"]
    assert set(zip(rms.run_id, rms.channel, strict=True)) == {
        ("M", "accel_1"), ("M", "accel_2"), ("T", "accel_x"), ("T", "accel_y")}
    assert (rms.status != "failed").all()
    run_rows = df[df.quantity == "run"].set_index("run_id")
    assert run_rows.loc["T", "reader"] == "blf" and run_rows.loc["M", "reader"] == "mcap"
    assert run_rows.loc["T", "n_rejected"] == 0
    # conditions named as slow signals come from the triax layout's mapping
    assert run_rows.loc["T", "torque_Nm"] == pytest.approx(150.0, abs=0.02)
    assert run_rows.loc["T", "bulk_temperature_C"] == pytest.approx(70.0, abs=0.01)
    modes = df[(df.quantity == "natural_frequency") & (df.mode_index == 0)]
    assert set(modes.run_id) == {"M", "T"}
    assert np.all(np.abs(modes.f_n_Hz - F_N) < 15.0), modes[["run_id", "channel", "f_n_Hz"]]


def test_without_its_overrides_the_can_run_decodes_nothing(mixed_dir):
    text = MIXED.replace('dbc = "layout/triax.dbc"\nmap = "layout/triax-map.toml"\n', "")
    p = mixed_dir / "no-overrides.toml"
    p.write_text(text, encoding="utf-8")
    c = load_campaign(p)
    res = observe_run(c, c.run("T"))
    assert not res.analysed and "id_not_in_dbc" in (res.error or "")


def test_a_forced_format_is_the_reader_used(mixed_dir):
    p = mixed_dir / "forced.toml"
    p.write_text(MIXED.replace('format = "blf"', 'format = "candump"'), encoding="utf-8")
    c = load_campaign(p)
    res = observe_run(c, c.run("T"))
    assert not res.analysed and "t.blf" in (res.error or "")
    # the same file read by content is fine
    p.write_text(MIXED.replace('format = "blf"\n', ""), encoding="utf-8")
    c = load_campaign(p)
    assert c.sensors_for(c.run("T")).format is None
    assert read_run(c, c.run("T")).provenance.reader == "blf"


def test_a_missing_channel_of_a_runs_accel_names_the_run_table(mixed_dir):
    p = mixed_dir / "missing-channel.toml"
    p.write_text(MIXED.replace('accel = ["accel_x", "accel_y"]',
                               'accel = ["accel_x", "accel_q"]'), encoding="utf-8")
    c = load_campaign(p)
    res = observe_run(c, c.run("T"))
    failed = [r for r in res.rows if r["quantity"] == "rms" and r["status"] == "failed"]
    assert [r["channel"] for r in failed] == ["accel_q"]
    assert "named in [[run]] accel" in failed[0]["message"]


_BAD_OVERRIDES = [
    ('dbc = "layout/triax.dbc"', 'dbc = "layout/nope.dbc"',
     r"at line 31: expected run.dbc to name an existing file .*'layout/nope.dbc': no such file"),
    ('map = "layout/triax-map.toml"', 'map = "nope.toml"',
     r"at line 32: expected run.map to name an existing file .*'nope.toml'"),
    ('format = "blf"', 'format = "BLF"',
     r"at line 33: expected run.format to be one of mcap, parquet, blf, .*found 'BLF' "
     r"\(did you mean 'blf'\?\)"),
    ('format = "mcap"', 'format = ""', r"at line 22: .*run\[0\].format"),
    ('accel = ["accel_x", "accel_y"]', "accel = []", r"at line 34: .*run\[1\].accel"),
    ('accel = ["accel_x", "accel_y"]', 'accel = "accel_x"', r"at line 34: .*run\[1\].accel"),
    ('speed = "PinionSpeed_rpm"', 'speed = "PinionSpeed_rpm"\nformat = "mdf"',
     r"at line 7: expected sensors.format to be one of mcap, .*found 'mdf'"),
]


@pytest.mark.parametrize(("old", "new", "match"), _BAD_OVERRIDES,
                         ids=[b[2][:28] for b in _BAD_OVERRIDES])
def test_bad_run_override_names_the_key_and_its_line(mixed_dir, tmp_path, old, new, match):
    assert old in MIXED
    p = mixed_dir / "bad.toml"
    p.write_text(MIXED.replace(old, new, 1), encoding="utf-8")
    with pytest.raises(CampaignError, match=match) as exc:
        load_campaign(p)
    assert str(exc.value).startswith(str(p))


# --------------------------------------------------------------------------------------------
# run files by glob


GLOBBED = """\
[campaign]
name = "globbed"
gear_set = "fzg-c"

[[run]]
id = "LS9-{stem}"
file = "runs/ls9_*.mcap"
torque_Nm = 302.0

[[run]]
id = "ls7"
file = "runs/ls7_?0c.mcap"
torque_Nm = 183.4

[[run]]
id = "single"
file = "runs/ls5_90c.mcap"
"""


@pytest.fixture()
def glob_dir(tmp_path) -> Path:
    (tmp_path / "runs").mkdir()
    for name in ("ls9_90c", "ls9_120c", "ls9_60c", "ls7_90c", "ls7_60c", "ls7_120c"):
        (tmp_path / "runs" / f"{name}.mcap").write_bytes(b"")
    (tmp_path / "runs" / "ls9_notes.txt").write_text("not a run")
    (tmp_path / "runs" / "ls9_dir.mcap").mkdir()  # folders never match
    (tmp_path / "g.toml").write_text(GLOBBED, encoding="utf-8")
    return tmp_path


def test_a_glob_expands_to_one_run_per_file_sorted(glob_dir):
    c = load_campaign(glob_dir / "g.toml")
    assert [r.id for r in c.runs] == ["LS9-ls9_120c", "LS9-ls9_60c", "LS9-ls9_90c",
                                      "ls7-ls7_60c", "ls7-ls7_90c", "single"]
    r = c.run("LS9-ls9_60c")
    assert r.file == glob_dir / "runs" / "ls9_60c.mcap"
    assert r.file_as_written == "runs/ls9_60c.mcap" and r.pattern == "runs/ls9_*.mcap"
    assert r.torque_Nm == 302.0 and r.line == 5
    assert c.run("ls7-ls7_90c").torque_Nm == 183.4 and c.run("ls7-ls7_90c").line == 10
    assert c.run("single").pattern is None  # a plain file that does not exist: kept
    assert c.to_dict()["run"][0]["pattern"] == "runs/ls9_*.mcap"


def test_an_absolute_glob_and_recursive_glob(glob_dir):
    (glob_dir / "runs" / "deep").mkdir()
    (glob_dir / "runs" / "deep" / "ls9_30c.mcap").write_bytes(b"")
    absolute = f'"{(glob_dir / "runs").as_posix()}/**/ls9_*0c.mcap"'
    text = GLOBBED.replace('"runs/ls9_*.mcap"', absolute)
    (glob_dir / "g.toml").write_text(text, encoding="utf-8")
    c = load_campaign(glob_dir / "g.toml")
    ids = [r.id for r in c.runs if r.id.startswith("LS9")]
    assert ids == ["LS9-ls9_30c", "LS9-ls9_120c", "LS9-ls9_60c", "LS9-ls9_90c"]
    assert c.run("LS9-ls9_30c").file_as_written == "runs/deep/ls9_30c.mcap"


def test_a_file_whose_name_holds_a_bracket_is_a_plain_file(tmp_path):
    (tmp_path / "run[1].mcap").write_bytes(b"")
    (tmp_path / "c.toml").write_text('[campaign]\nname = "x"\ngear_set = "fzg-c"\n\n'
                                     '[[run]]\nid = "a"\nfile = "run[1].mcap"\n')
    c = load_campaign(tmp_path / "c.toml")
    assert [r.id for r in c.runs] == ["a"] and c.runs[0].pattern is None


def test_a_glob_matching_nothing_names_its_line(glob_dir):
    text = GLOBBED.replace('"runs/ls7_?0c.mcap"', '"runs/ls8_*.mcap"')
    p = glob_dir / "g.toml"
    p.write_text(text, encoding="utf-8")
    with pytest.raises(CampaignError, match=r"g\.toml at line 12: expected the glob in run.file "
                       r"to match at least one file .*found 'runs/ls8_\*\.mcap': no match"):
        load_campaign(p)


def test_duplicate_ids_after_expansion_name_both_lines(glob_dir):
    text = GLOBBED.replace('id = "single"', 'id = "ls7-ls7_90c"')
    p = glob_dir / "g.toml"
    p.write_text(text, encoding="utf-8")
    with pytest.raises(CampaignError, match=r"at line 16: expected a unique run id, found "
                       r"'ls7-ls7_90c' again \(first in run 2 from 'runs/ls7_90c.mcap', "
                       r"line 11\)"):
        load_campaign(p)
    # two matches of one pattern giving one id: both name the same [[run]]
    text = GLOBBED.replace('id = "LS9-{stem}"', 'id = "LS9-{stem}"\n').replace(
        '"runs/ls9_*.mcap"', '"runs/ls9_*"')
    (glob_dir / "runs" / "ls9_90c.blf").write_bytes(b"")
    p.write_text(text, encoding="utf-8")
    with pytest.raises(CampaignError, match=r"at line 6: expected a unique run id, found "
                       r"'LS9-ls9_90c' \(from 'runs/ls9_90c.mcap'\) again \(first in run 1 "
                       r"from 'runs/ls9_90c.blf', line 6\)"):
        load_campaign(p)


# --------------------------------------------------------------------------------------------
# [report]


def test_the_report_block_is_kept_raw_with_its_lines(mixed):
    assert mixed.report == {"title": "two loggers, one report", "f_n_rel_tolerance": 0.02,
                            "f_n_z_tolerance": 3.0, "backlash_range_um": [5.0, 40.0],
                            "min_margin_um": 0.0}
    assert mixed.line_of("report") == 12
    assert mixed.line_of("report.title") == 13
    assert mixed.line_of("report.backlash_range_um") == 16
    assert mixed.line_of("report.min_margin_um") == 17
    assert mixed.to_dict()["report"] == mixed.report


def test_no_report_block_is_none(tmp_path):
    (tmp_path / "c.toml").write_text('[campaign]\nname = "x"\ngear_set = "fzg-c"\n\n'
                                     '[[run]]\nid = "a"\nfile = "a.mcap"\n')
    c = load_campaign(tmp_path / "c.toml")
    assert c.report is None and c.to_dict()["report"] is None and c.line_of("report.x") is None


_BAD_REPORT = [
    ("f_n_rel_tolerance = 0.02", "f_n_rel_tolerance = 0.0",
     r"at line 14: .*report.f_n_rel_tolerance.*less than or equal to the minimum of 0"),
    ("f_n_z_tolerance = 3.0", "f_n_z_tolerance = -1.0", r"at line 15: .*report.f_n_z_tolerance"),
    ("backlash_range_um = [5.0, 40.0]", "backlash_range_um = [40.0, 5.0]",
     r"at line 16: expected backlash_range_um = \[lo, hi\] with lo < hi \(um\), "
     r"found \[40.0, 5.0\]"),
    ("backlash_range_um = [5.0, 40.0]", "backlash_range_um = [5.0]",
     r"at line 16: .*report.backlash_range_um"),
    ("min_margin_um = 0.0", 'min_margin_um = "zero"', r"at line 17: .*report.min_margin_um"),
    ("min_margin_um = 0.0", "min_margin_um = inf",
     r"at line 17: expected a finite number for report.min_margin_um, found inf"),
    ('title = "two loggers, one report"', 'titel = "x"',
     r"at line 13: expected one of the keys title, f_n_rel_tolerance, .* in \[report\], "
     r"found unknown key 'titel' \(did you mean 'title'\?\)"),
]


@pytest.mark.parametrize(("old", "new", "match"), _BAD_REPORT,
                         ids=[b[2][:28] for b in _BAD_REPORT])
def test_bad_report_block_names_the_key_and_its_line(mixed_dir, old, new, match):
    assert old in MIXED
    p = mixed_dir / "bad-report.toml"
    p.write_text(MIXED.replace(old, new, 1), encoding="utf-8")
    with pytest.raises(CampaignError, match=match):
        load_campaign(p)


# --------------------------------------------------------------------------------------------
# the observe split


def test_observe_run_is_read_run_then_observe_recording(mixed, mixed_observed):
    for run, whole in zip(mixed.runs, mixed_observed.runs, strict=True):
        rec = read_run(mixed, run)
        split = observe_recording(mixed, run, rec)
        assert split == whole  # rows, status, warnings (spectra compare apart)
        assert to_frame(list(split.rows)).equals(to_frame(list(whole.rows)))
        assert split.spectra.keys() == whole.spectra.keys()
        for ch, (f, psd, unit) in whole.spectra.items():
            f2, psd2, unit2 = split.spectra[ch]
            np.testing.assert_array_equal(f2, f)
            np.testing.assert_array_equal(psd2, psd)
            assert unit2 == unit


def test_spectra_are_the_welch_psds_of_the_analysed_channels(mixed_observed):
    m, t = mixed_observed.runs
    assert set(m.spectra) == {"accel_1", "accel_2"} and set(t.spectra) == {"accel_x", "accel_y"}
    for ch, (f, psd, unit) in {**m.spectra, **t.spectra}.items():
        assert unit == "(m/s^2)^2/Hz"
        assert f.dtype == np.float64 and psd.dtype == np.float64
        assert f.shape == psd.shape == (2048 // 2 + 1,)
        assert f[0] == 0.0 and f[-1] == pytest.approx(12_800.0)
        assert np.all(psd >= 0)
        # the mode is the tallest structural feature above the mesh lines
        band = f > 2000
        assert abs(f[band][np.argmax(psd[band])] - F_N) < 2 * (f[1] - f[0]), ch


def test_a_run_that_cannot_be_read_is_a_failed_run_and_read_run_raises(mixed_dir):
    p = mixed_dir / "missing.toml"
    p.write_text(MIXED.replace('file = "can/t.blf"', 'file = "can/none.blf"'),
                 encoding="utf-8")
    c = load_campaign(p)
    res = observe_run(c, c.run("T"))
    assert not res.analysed and res.spectra == {} and "none.blf" in (res.error or "")
    with pytest.raises(RecordingFormatError, match=r"none\.blf: expected a recording file, "
                       "found no such file"):
        read_run(c, c.run("T"))
    with pytest.raises(RecordingFormatError, match=r"none\.blf"):
        observe_run(c, c.run("T"), raise_errors=True)

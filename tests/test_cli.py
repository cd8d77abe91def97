"""The rigtools command line: ingest, info, exit codes, warnings on stderr."""

import json

import numpy as np
import pytest

from rigtools.cli import EXIT_UNUSABLE, main
from rigtools.demo.can_writer import encode_reference_frames, write_can_log
from rigtools.ingest import read


@pytest.fixture()
def blf_file(tmp_path):
    rng = np.random.default_rng(3)
    chans = [np.round(rng.normal(0, 100, 3 * 2000)) * 0.015 for _ in range(4)]
    frames = encode_reference_frames(chans, {"Torque_Nm": 302.0, "PinionSpeed_rpm": 1500.0},
                                     rng=2)
    return write_can_log(tmp_path / "run.blf", frames, "blf"), chans, frames


def test_ingest_writes_parquet_that_reads_back_exactly(tmp_path, blf_file, capsys):
    path, chans, _ = blf_file
    out = tmp_path / "run.parquet"
    assert main(["ingest", str(path), "-o", str(out)]) == 0
    cap = capsys.readouterr()
    assert "wrote" in cap.out and "4 channel(s)" in cap.out
    assert cap.err == ""  # nothing lost, nothing to warn about
    direct = read(path)
    back = read(out)
    assert back.equals(direct)
    np.testing.assert_array_equal(back.channels["accel_2"].values, chans[1])


def test_info_prints_channels_rates_counts_and_gaps(blf_file, capsys):
    path, _, _ = blf_file
    assert main(["info", str(path)]) == 0
    out = capsys.readouterr().out
    for text in ("accel_1", "25600", "6000", "Torque_Nm", "decoded", "rejected  none",
                 "gaps      none"):
        assert text in out
    assert main(["info", "--json", str(path)]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert [c["n_samples"] for c in doc["channels"]] == [6000] * 4


def test_usable_with_losses_exits_zero_with_warnings(tmp_path, blf_file, capsys):
    _, _, frames = blf_file
    keep = np.ones(len(frames), bool)
    acc1 = np.flatnonzero(frames.arbitration_id == 256)
    keep[acc1[100:110]] = False  # ten frames lost: a gap of 30 samples
    lossy = write_can_log(tmp_path / "lossy.blf", frames.take(keep), "blf")
    assert main(["info", str(lossy)]) == 0
    cap = capsys.readouterr()
    assert "30 sample(s) missing from index 300" in cap.out
    assert "rigtools: warning: 1 gap(s) in sample counters, 30 sample(s) missing" in cap.err


@pytest.mark.parametrize(
    ("content", "match"),
    [(b"", "an empty file"), (b"\x00\x01garbage" * 10, "expected content or a suffix")],
)
def test_unusable_input_exits_non_zero_naming_the_file(tmp_path, capsys, content, match):
    p = tmp_path / "bad.bin"
    p.write_bytes(content)
    assert main(["info", str(p)]) == EXIT_UNUSABLE
    err = capsys.readouterr().err
    assert err.startswith("rigtools: error: ") and "bad.bin" in err and match in err


def test_missing_file_and_bad_arguments(tmp_path, capsys):
    assert main(["info", str(tmp_path / "nope.blf")]) == EXIT_UNUSABLE
    assert "no such file" in capsys.readouterr().err
    with pytest.raises(SystemExit) as exc:
        main(["ingest", "x.blf"])  # -o is required
    assert exc.value.code == 2


def test_debug_re_raises(tmp_path):
    p = tmp_path / "empty.mcap"
    p.write_bytes(b"")
    from rigtools.errors import RecordingFormatError

    with pytest.raises(RecordingFormatError, match="empty"):
        main(["--debug", "info", str(p)])


@pytest.mark.parametrize("target", ["missing/dir/out.parquet", "."])
def test_unwritable_output_is_an_error_not_a_traceback(tmp_path, blf_file, capsys, target):
    path, _, _ = blf_file
    out = tmp_path / target
    assert main(["ingest", str(path), "-o", str(out)]) == EXIT_UNUSABLE
    err = capsys.readouterr().err
    assert err.startswith("rigtools: error: ") and "Traceback" not in err


def test_sample_level_losses_are_reported_in_samples(tmp_path, capsys):
    from rigtools.demo.mcap_writer import write_accel_mcap

    vals = np.arange(3000, dtype=float)
    vals[10:60] = np.nan
    p = write_accel_mcap(tmp_path / "nan.mcap", {"accel_1": (vals, 1000.0, "m/s^2", 0, 1.7e9)},
                         batch=100)
    assert main(["info", str(p)]) == 0
    cap = capsys.readouterr()
    assert "50 samples rejected: non_finite_sample" in cap.err
    assert main(["info", "--json", str(p)]) == 0
    json.loads(capsys.readouterr().out)  # strict JSON: no bare NaN


def test_round_trip_is_exact_with_a_mapping_too(tmp_path, blf_file):
    path, chans, _ = blf_file
    m = tmp_path / "map.toml"
    m.write_text(
        "[run]\nrun_id = 'mapped'\nconditions = { torque_Nm = 302.0 }\n\n"
        "[[uniform]]\nchannel = 'pinion_radial'\nmessage = 'ACC1'\n"
        "samples = ['Acc1_S0', 'Acc1_S1', 'Acc1_S2']\ncounter = 'Acc1_Counter'\n"
        "sample_rate_Hz = 25600.0\nunit = 'g'\nscale = 0.10197162129779283\n\n"
        "[[slow]]\nname = 'torque_Nm'\nmessage = 'TORQUE'\nsignal = 'Torque_Nm'\n"
    )
    out = tmp_path / "mapped.parquet"
    assert main(["ingest", str(path), "--map", str(m), "-o", str(out)]) == 0
    direct = read(path, mapping=m)
    assert read(out).equals(direct)
    assert set(direct.channels) == {"pinion_radial"}
    assert direct.channels["pinion_radial"].unit == "g"
    np.testing.assert_allclose(direct.channels["pinion_radial"].values, chans[0] / 9.80665,
                               rtol=1e-15)
    assert direct.metadata.run_id == "mapped"
    # Frames of messages the mapping does not use are counted, not dropped silently.
    assert direct.report.rejected["message_not_in_layout"] > 0

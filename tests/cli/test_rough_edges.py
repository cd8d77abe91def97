"""What a new user hit first (issue 17, must-hold 7), each a test.

``demo --duration`` out of range and ``--seed`` below zero refused before any work (exit 2,
the range in the help); ``demo --help`` complete; a directory given as a recording named a
directory; ``--format`` a choice (exit 2, listed in the help); output paths checked before
the input is read (suffix: exit 2 naming the accepted ones; folder missing: exit 3);
``observe`` summarising the frequencies its table holds when every mode is flagged.
"""

from __future__ import annotations

import numpy as np
import pytest

import rigtools.cli.ingest
import rigtools.cli.observe
from rigtools.campaign import Observations, RunObservations, to_frame
from rigtools.cli import EXIT_UNUSABLE, EXIT_USAGE, main
from rigtools.cli.observe import format_summary
from rigtools.demo.can_writer import encode_reference_frames, write_can_log
from rigtools.ingest.registry import READERS


@pytest.fixture(scope="module")
def blf(tmp_path_factory: pytest.TempPathFactory):
    chans = [np.zeros(3 * 300) + k for k in range(4)]
    frames = encode_reference_frames(chans, {"Torque_Nm": 302.0}, rng=2)
    return write_can_log(tmp_path_factory.mktemp("edges") / "run.blf", frames, "blf")


def usage_error(capsys: pytest.CaptureFixture[str], argv: list[str]) -> str:
    with pytest.raises(SystemExit) as exc:
        main(argv)
    assert exc.value.code == EXIT_USAGE
    err = capsys.readouterr().err
    assert "Traceback" not in err and "usage: rigtools" in err
    return err


# --------------------------------------------------------------------------------------------
# demo


@pytest.mark.parametrize("duration", ["-1", "0", "nan", "inf", "100000", "1", "60.5"])
def test_demo_duration_out_of_range_is_refused_before_any_work(tmp_path, capsys, duration):
    out = tmp_path / "demo-out"
    err = usage_error(capsys, ["demo", "-o", str(out), "--duration", duration])
    assert "argument --duration" in err
    assert not out.exists()  # no empty folder left behind


def test_demo_negative_seed_is_a_usage_error(tmp_path, capsys):
    out = tmp_path / "demo-out"
    err = usage_error(capsys, ["demo", "-o", str(out), "--seed", "-1"])
    assert "argument --seed: must be an integer >= 0" in err
    assert not out.exists()


def test_demo_help_is_whole_and_states_the_range(capsys):
    with pytest.raises(SystemExit) as exc:
        main(["demo", "--help"])
    assert exc.value.code == 0
    text = " ".join(capsys.readouterr().out.split())
    # the description is the module docstring's paragraph, to its last word
    assert "point a copy at your own runs, and run rigtools run on it." in text
    assert "options:" in text and "Generates an FZG-C options:" not in text
    assert "length of each FZG-C run in seconds, 1.5 to 60 (default by size)" in text


def test_demo_output_that_cannot_be_a_folder(tmp_path, capsys):
    a_file = tmp_path / "a_file"
    a_file.write_text("x")
    assert main(["demo", "-o", str(a_file / "sub"), "--duration", "2"]) == EXIT_UNUSABLE
    assert f"cannot create the folder: {a_file} is a file" in capsys.readouterr().err


# --------------------------------------------------------------------------------------------
# reading: a directory, --format


@pytest.mark.parametrize("command", ["info", "ingest", "spectrum"])
def test_a_directory_given_as_the_recording_is_named_a_directory(tmp_path, capsys, command):
    argv = [command, str(tmp_path)]
    if command == "ingest":
        argv += ["-o", str(tmp_path / "out.parquet")]
    assert main(argv) == EXIT_UNUSABLE
    err = capsys.readouterr().err
    assert f"{tmp_path}: expected a recording file, found a directory" in err
    assert "no such file" not in err


@pytest.mark.parametrize(("option", "what"), [("--dbc", "a DBC file"),
                                              ("--map", "a mapping file")])
def test_a_directory_given_as_dbc_or_mapping_is_named_a_directory(blf, tmp_path, capsys,
                                                                   option, what):
    assert main(["info", str(blf), option, str(tmp_path)]) == EXIT_UNUSABLE
    assert f"{tmp_path}: expected {what}, found a directory" in capsys.readouterr().err


def test_format_is_a_choice(blf, capsys):
    err = usage_error(capsys, ["info", str(blf), "--format", "foo"])
    assert "argument --format: invalid choice: 'foo'" in err
    for name in READERS:
        assert repr(name) in err
    with pytest.raises(SystemExit):
        main(["info", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    assert "force a reader, one of: " + ", ".join(sorted(READERS)) in text
    assert main(["info", str(blf), "--format", "blf"]) == 0


# --------------------------------------------------------------------------------------------
# output paths, checked first


def _never_read(monkeypatch: pytest.MonkeyPatch, module: object, name: str) -> None:
    def refuse(*args: object, **kw: object) -> None:
        raise AssertionError("the input was read before the output path was checked")

    monkeypatch.setattr(module, name, refuse)


def test_ingest_output_folder_missing_is_refused_before_reading(blf, tmp_path, capsys,
                                                                monkeypatch):
    _never_read(monkeypatch, rigtools.cli.ingest, "read_from_args")
    out = tmp_path / "nonexistent" / "x.parquet"
    assert main(["ingest", str(blf), "-o", str(out)]) == EXIT_UNUSABLE
    err = capsys.readouterr().err
    assert f"{out}: cannot write the file: no such folder {out.parent}" in err
    assert "Traceback" not in err and "arrow" not in err.lower()


def test_ingest_output_that_is_a_folder(blf, tmp_path, capsys, monkeypatch):
    _never_read(monkeypatch, rigtools.cli.ingest, "read_from_args")
    assert main(["ingest", str(blf), "-o", str(tmp_path)]) == EXIT_UNUSABLE
    assert "expected a file to write, found a folder" in capsys.readouterr().err


@pytest.mark.parametrize("name", ["out.csv", "out.PARQUET.txt", "out"])
def test_ingest_output_suffix_is_checked(blf, tmp_path, capsys, name):
    err = usage_error(capsys, ["ingest", str(blf), "-o", str(tmp_path / name)])
    assert "argument -o/--output" in err and "accepted: .parquet" in err
    assert not (tmp_path / name).exists()


def test_ingest_honours_a_suffix_in_capitals(blf, tmp_path, capsys):
    out = tmp_path / "run.Parquet"
    assert main(["ingest", str(blf), "-o", str(out)]) == 0
    assert out.read_bytes()[:4] == b"PAR1"


def test_observe_output_is_checked_before_the_campaign(tmp_path, capsys, monkeypatch):
    _never_read(monkeypatch, rigtools.cli.observe, "load_campaign")
    camp = tmp_path / "c.toml"
    camp.write_text("[campaign]\n")
    err = usage_error(capsys, ["observe", str(camp), "-o", str(tmp_path / "obs.csv")])
    assert "accepted: .parquet" in err
    out = tmp_path / "missing" / "obs.parquet"
    assert main(["observe", str(camp), "-o", str(out)]) == EXIT_UNUSABLE
    assert "no such folder" in capsys.readouterr().err


# --------------------------------------------------------------------------------------------
# observe: the summary shows the frequencies the table holds


def _observations(statuses: list[str]) -> Observations:
    rows = [{"campaign": "c", "run_id": "R1", "quantity": "run", "status": "flagged"}]
    for i, (ch, status) in enumerate(zip(["accel_1", "accel_2"], statuses, strict=True)):
        rows.append({"campaign": "c", "run_id": "R1", "channel": ch, "quantity": "rms",
                     "status": "ok", "rms_m_s2": 1.0})
        rows.append({"campaign": "c", "run_id": "R1", "channel": ch,
                     "quantity": "natural_frequency", "mode_index": 0, "status": status,
                     "f_n_Hz": 2843.0 + i, "zeta": 0.03, "quality_flags": "at_mesh_line"})
    table = to_frame(rows)
    return Observations(table, (RunObservations("R1", "r1.mcap", tuple(rows), True),))


def test_observe_summary_shows_flagged_frequencies_marked():
    text = format_summary(_observations(["flagged", "flagged"]))
    line = next(ln for ln in text.splitlines() if ln.startswith("R1"))
    assert line.split()[3:6] == ["0/2", "2843.5*", "0.0300*"]  # not 'f_n Hz -'
    assert "* no clean mode in the run" in text


def test_observe_summary_prefers_clean_modes():
    text = format_summary(_observations(["ok", "flagged"]))
    line = next(ln for ln in text.splitlines() if ln.startswith("R1"))
    assert line.split()[3:6] == ["1/2", "2843.0", "0.0300"]
    assert "*" not in text


def test_observe_summary_skips_rows_without_a_fitted_frequency():
    obs = _observations(["ok", "ok"])
    row = {"campaign": "c", "run_id": "R1", "channel": "accel_1", "quantity": "natural_frequency",
           "mode_index": -1, "status": "ok", "f_n_Hz": None, "zeta": None}
    rows = (*obs.runs[0].rows, row)
    obs = Observations(to_frame(rows), (RunObservations("R1", "r1.mcap", rows, True),))
    line = next(ln for ln in format_summary(obs).splitlines() if ln.startswith("R1"))
    assert line.split()[4:6] == ["2843.5", "0.0300"]


def test_demo_generation_counts_its_runs_in_the_log(tmp_path, capsys, monkeypatch):
    """Without a terminal, one line per generated run, counted 1..n (the pipeline stubbed).

    The reduced demo: 8 FZG-C runs and the run-up; with ``--no-runup`` the 8 runs alone.
    """
    import rigtools.cli.demo as demo_cli

    monkeypatch.setattr(demo_cli, "run_pipeline", lambda *a, **k: 0)
    assert main(["demo", "-o", str(tmp_path / "d"), "--size", "ci", "--duration", "1.5"]) == 0
    lines = [ln for ln in capsys.readouterr().err.splitlines() if "generate [" in ln]
    assert [ln.split("[")[1].split("]")[0] for ln in lines] == [f"{i}/9" for i in range(1, 10)]
    assert main(["demo", "-o", str(tmp_path / "e"), "--size", "ci", "--duration", "1.5",
                 "--no-runup"]) == 0
    lines = [ln for ln in capsys.readouterr().err.splitlines() if "generate [" in ln]
    assert [ln.split("[")[1].split("]")[0] for ln in lines] == [f"{i}/8" for i in range(1, 9)]

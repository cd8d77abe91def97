"""One error story at the command line: every subcommand, every error class it can meet.

Exit 3 and one line ``rigtools: error: <message>`` on stderr for every error rigtools raises on
purpose (:class:`rigtools.errors.RigtoolsError`, the whole tree) and every error the physics
raises on purpose (:class:`models.errors.ModelError`), and for files that cannot be read or
written; exit 2 with argparse's usage message for bad arguments; a traceback only for a bug.

Two kinds of test:

- real inputs, per subcommand (``ingest``, ``info``, ``spectrum``, ``observe``, ``demo``), that
  trigger each error reachable from it: a damaged or unsupported file, a bad DBC, a bad
  mapping, a file that decodes to nothing, an unwritable output, a malformed campaign, an
  impossible gear set in a campaign, a signal too short or constant, a missing speed signal;
- every class of the error tree raised from inside each subcommand (its ``run`` replaced), so
  that an error class no file reaches today still meets the same story.
"""

from __future__ import annotations

import subprocess
import sys
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest

import rigtools.cli
from models.errors import GeometryError, ModelError
from models.geometry.gear_sets import gear_set_path
from models.thermal.thermoelastic import ThermalJamError
from rigtools.cli import EXIT_UNUSABLE, EXIT_USAGE, main
from rigtools.demo.can_writer import encode_reference_frames, write_can_log
from rigtools.demo.mcap_writer import write_accel_mcap
from rigtools.errors import (
    CampaignError,
    ConstantSignalError,
    DbcError,
    InsufficientDataError,
    MappingError,
    MissingSpeedError,
    NoDataError,
    PayloadDecodeError,
    RecordingFormatError,
    RigtoolsError,
    SchemaUnusableError,
    SignalError,
    UnsupportedFormatError,
)

FS = 25_600.0


# --------------------------------------------------------------------------------------------
# what every failure looks like


def assert_one_line_error(err: str, *fragments: str) -> str:
    """Check that ``err`` holds exactly one error line, with ``fragments``, and no traceback."""
    assert "Traceback" not in err, err
    lines = err.splitlines()
    errors = [ln for ln in lines if ln.startswith("rigtools: error: ")]
    assert len(errors) == 1, err
    assert all(ln.startswith(("rigtools: error: ", "rigtools: warning: ")) for ln in lines), err
    for f in fragments:
        assert f in errors[0], (f, errors[0])
    return errors[0]


def fails(capsys: pytest.CaptureFixture[str], argv: list[str], *fragments: str) -> str:
    """``main(argv)`` exits 3 with one error line naming ``fragments``; returns the line."""
    assert main(argv) == EXIT_UNUSABLE
    return assert_one_line_error(capsys.readouterr().err, *fragments)


# --------------------------------------------------------------------------------------------
# inputs


def mcap_file(path: Path, values: dict[str, np.ndarray], slow: dict | None = None) -> Path:
    chans = {k: (v, FS, "m/s^2", 0, 1.7e9) for k, v in values.items()}
    return write_accel_mcap(path, chans, slow, None)


@pytest.fixture(scope="module")
def inputs(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    d = tmp_path_factory.mktemp("errors")
    rng = np.random.default_rng(7)
    out: dict[str, Path] = {"dir": d}
    out["empty"] = d / "empty.mcap"
    out["empty"].write_bytes(b"")
    out["garbage"] = d / "garbage.bin"
    out["garbage"].write_bytes(b"\x00\x01garbage" * 10)
    out["bad_magic"] = d / "bad_magic.mcap"
    out["bad_magic"].write_bytes(b"\x89MCAX0\r\n" + bytes(64))
    out["blf_bad_signature"] = d / "bad.blf"
    out["blf_bad_signature"].write_bytes(b"LOGX" + bytes(140))
    out["missing"] = d / "missing.blf"
    # a CAN log whose identifiers are all absent from the reference DBC: nothing decodes
    out["unknown_ids"] = d / "unknown_ids.log"
    out["unknown_ids"].write_text("(1700000000.000000) can0 7AA#0102030405060708\n"
                                  "(1700000000.001000) can0 7AB#0102030405060708\n")
    chans = [np.round(rng.normal(0, 100, 3 * 500)) * 0.015 for _ in range(4)]
    frames = encode_reference_frames(chans, {"Torque_Nm": 302.0, "PinionSpeed_rpm": 1500.0},
                                     rng=2)
    out["blf"] = write_can_log(d / "run.blf", frames, "blf")
    out["bad_dbc"] = d / "bad.dbc"
    out["bad_dbc"].write_text('VERSION ""\nBO_ 12 X: 8 Vector__XXX\n'
                              ' SG_ a : 0|8@1+ (1,0) [0|0] "" X Y Z\n')
    out["bad_map"] = d / "bad_map.toml"
    out["bad_map"].write_text("[[uniform]\n")
    out["unknown_key_map"] = d / "unknown_key_map.toml"
    out["unknown_key_map"].write_text(
        "[[uniform]]\nchannel = 'a'\nmessage = 'ACC1'\nsamples = ['Acc1_S0']\n"
        "counter = 'Acc1_Counter'\nsample_rate_Hz = 25600.0\ncolour = 'red'\n")
    # analysable noise with no speed signal; a dead (constant) channel; a short one
    out["noise"] = mcap_file(d / "noise.mcap", {"accel_1": rng.normal(0, 1, int(0.5 * FS))})
    out["dead"] = mcap_file(d / "dead.mcap", {"accel_1": np.zeros(int(0.5 * FS))})
    out["short"] = mcap_file(d / "short.mcap", {"accel_1": rng.normal(0, 1, 1000)})
    # campaigns
    runs = d / "runs"
    runs.mkdir()
    mcap_file(runs / "noise.mcap", {"accel_1": rng.normal(0, 1, int(0.5 * FS))})
    mcap_file(runs / "dead.mcap", {"accel_1": np.zeros(int(0.5 * FS))})
    out["campaign_ok_no_speed"] = d / "no_speed.toml"
    out["campaign_ok_no_speed"].write_text(campaign('"fzg-c"', ["runs/noise.mcap"]))
    out["campaign_all_fail"] = d / "all_fail.toml"
    out["campaign_all_fail"].write_text(
        campaign('"fzg-c"', ["runs/dead.mcap", "runs/nothing.mcap", "garbage.bin"]))
    out["campaign_bad_key"] = d / "bad_key.toml"
    out["campaign_bad_key"].write_text(
        campaign('"fzg-c"', ["runs/noise.mcap"]).replace("torque_Nm", "torque_NM"))
    out["campaign_not_toml"] = d / "not_toml.toml"
    out["campaign_not_toml"].write_text("[campaign\nname = 'x'\n")
    # an impossible gear set: a two-tooth pinion (models raises GeometryError)
    gears = gear_set_path("fzg-c").read_text().replace("teeth = 16", "teeth = 2", 1)
    (d / "two_teeth.toml").write_text(gears)
    out["campaign_bad_gears"] = d / "bad_gears.toml"
    out["campaign_bad_gears"].write_text(campaign('"two_teeth.toml"', ["runs/noise.mcap"]))
    out["a_file"] = d / "a_file"
    out["a_file"].write_text("not a folder")
    return out


def campaign(gear_set: str, files: list[str]) -> str:
    runs = "".join(f'\n[[run]]\nid = "R{i}"\nfile = "{f}"\ntorque_Nm = 100.0\n'
                   for i, f in enumerate(files))
    return (f'[campaign]\nname = "errors"\ngear_set = {gear_set}\n\n'
            '[sensors]\nspeed = "PinionSpeed_rpm"\n\n[analysis]\nnperseg = 2048\n' + runs)


# --------------------------------------------------------------------------------------------
# real inputs: ingest and info share the reader, so the same files fail both the same way

READ_ERRORS = [
    # (input, extra options, fragments of the one error line)
    ("empty", [], ["empty.mcap at byte 0: expected a non-empty recording, found an empty file"]),
    ("garbage", [], ["garbage.bin at byte 0: expected content or a suffix of a supported "
                     "format"]),
    ("bad_magic", [], ["bad_magic.mcap at byte 0: expected the MCAP magic"]),
    ("blf_bad_signature", [], ["bad.blf at byte 0: expected the BLF signature b'LOGG'"]),
    ("missing", [], ["missing.blf: expected a recording file, found no such file"]),
    ("unknown_ids", [], ["expected at least one decodable channel or slow signal, found none",
                         "id_not_in_dbc: 2"]),
    ("blf", ["--dbc", "bad_dbc"], ["bad.dbc at line 3", "expected a valid DBC file"]),
    ("blf", ["--map", "bad_map"], ["bad_map.toml: expected a TOML mapping file"]),
    ("blf", ["--map", "unknown_key_map"], ["unknown_key_map.toml at line 7",
                                           "'colour' was unexpected"]),
]


def _argv(inputs: dict[str, Path], options: list[str]) -> list[str]:
    return [str(inputs[o]) if o in inputs else o for o in options]


@pytest.mark.parametrize(("name", "options", "fragments"), READ_ERRORS,
                         ids=[f"{r[0]}{''.join(r[1][1:2])}" for r in READ_ERRORS])
@pytest.mark.parametrize("command", ["ingest", "info", "spectrum"])
def test_reading_errors_are_one_line_with_exit_3(inputs, capsys, command, name, options,
                                                   fragments, tmp_path):
    argv = [command, str(inputs[name]), *_argv(inputs, options)]
    if command == "ingest":
        argv += ["-o", str(tmp_path / "out.parquet")]
    fails(capsys, argv, *fragments)
    assert not (tmp_path / "out.parquet").exists()


def test_the_error_classes_behind_the_reading_errors(inputs):
    """The inputs above do raise the classes they stand for (so the table covers the tree)."""
    from rigtools.ingest import read

    for name, cls in [("empty", RecordingFormatError), ("garbage", UnsupportedFormatError),
                      ("bad_magic", RecordingFormatError), ("unknown_ids", NoDataError)]:
        with pytest.raises(cls):
            read(inputs[name])
    with pytest.raises(DbcError):
        read(inputs["blf"], dbc=inputs["bad_dbc"])
    for m in ("bad_map", "unknown_key_map"):
        with pytest.raises(MappingError):
            read(inputs["blf"], mapping=inputs[m])


@pytest.mark.parametrize("target", ["missing/dir/out.parquet", "."])
def test_ingest_to_an_unwritable_output(inputs, capsys, tmp_path, target):
    fails(capsys, ["ingest", str(inputs["blf"]), "-o", str(tmp_path / target)])


# --------------------------------------------------------------------------------------------
# spectrum: signals that cannot be analysed, a channel that is not there, no speed signal


@pytest.mark.parametrize(("name", "warning"), [
    ("dead", "`values` is constant"),
    ("short", "`nperseg` must be <= len(x)=1000, was 4096"),
])
def test_spectrum_of_a_signal_that_cannot_be_analysed(inputs, capsys, name, warning):
    assert main(["spectrum", str(inputs[name])]) == EXIT_UNUSABLE
    err = capsys.readouterr().err
    line = assert_one_line_error(err, f"{name}.mcap: no channel could be analysed")
    assert f"rigtools: warning: channel 'accel_1': {warning}" in err, err
    assert line == err.splitlines()[-1]


def test_spectrum_of_a_channel_that_is_not_there(inputs, capsys):
    fails(capsys, ["spectrum", str(inputs["noise"]), "--channel", "accel_9"],
          "no channel 'accel_9' (the recording holds: accel_1)")


def test_spectrum_without_the_speed_signal_warns_and_goes_on(inputs, capsys):
    assert main(["spectrum", str(inputs["noise"]), "--nperseg", "2048", "--z1", "16"]) == 0
    err = capsys.readouterr().err
    assert err.splitlines() == [
        f"rigtools: warning: {inputs['noise']}: --z1 given but no slow signal "
        "'PinionSpeed_rpm' (the recording holds: none): mesh harmonics are not told apart"]


# --------------------------------------------------------------------------------------------
# observe: the campaign file, the gear set it names, runs that fail, a missing speed signal


@pytest.mark.parametrize(("name", "fragments"), [
    ("campaign_bad_key", ["bad_key.toml at line 14: ", "unknown key 'torque_NM' (did you mean "
                          "'torque_Nm'?)"]),
    ("campaign_not_toml", ["not_toml.toml at line 1, column 10: expected a TOML file"]),
    ("campaign_bad_gears", ["bad_gears.toml at line 3: expected a gear set that loads",
                            "pinion.teeth` = 2: must be an integer >= 5"]),
    ("missing", ["missing.blf: expected a campaign file, found no such file"]),
])
def test_observe_a_malformed_campaign(inputs, capsys, tmp_path, name, fragments):
    out = tmp_path / "obs.parquet"
    fails(capsys, ["observe", str(inputs[name]), "-o", str(out)], *fragments)
    assert not out.exists()


def test_an_impossible_gear_set_is_a_model_error_inside_the_campaign_error(inputs):
    from rigtools.campaign import load_campaign

    with pytest.raises(CampaignError) as exc:
        load_campaign(inputs["campaign_bad_gears"])
    assert isinstance(exc.value.__cause__, GeometryError)


def test_observe_when_no_run_can_be_analysed(inputs, capsys, tmp_path):
    out = tmp_path / "obs.parquet"
    assert main(["observe", str(inputs["campaign_all_fail"]), "-o", str(out)]) == EXIT_UNUSABLE
    err = capsys.readouterr().err
    assert "Traceback" not in err
    lines = err.splitlines()
    # one line per failed run (the campaign goes on), then the one error of the command
    runs = [ln for ln in lines if ln.startswith("rigtools: error: run ")]
    assert [ln.split(" failed: ")[0] for ln in runs] == [
        f"rigtools: error: run 'R{i}'" for i in range(3)]
    assert "dead.mcap: no channel could be analysed" in runs[0]
    assert "nothing.mcap: expected a recording file, found no such file" in runs[1]
    assert "garbage.bin at byte 0: expected content or a suffix" in runs[2]
    assert lines[-1] == (f"rigtools: error: {inputs['campaign_all_fail']}: no run could be "
                         "analysed")
    assert all(ln.startswith(("rigtools: error: ", "rigtools: warning: ")) for ln in lines)
    assert out.exists()  # the failures are on record


def test_observe_without_the_speed_signal_warns_and_goes_on(inputs, capsys, tmp_path):
    assert main(["observe", str(inputs["campaign_ok_no_speed"]), "-o",
                 str(tmp_path / "obs.parquet")]) == 0
    err = capsys.readouterr().err
    assert "Traceback" not in err and "rigtools: error" not in err
    assert "rigtools: warning: R0: speed signal 'PinionSpeed_rpm' unusable, no Arms: order " \
           "analysis needs speed signal 'PinionSpeed_rpm'" in err


# --------------------------------------------------------------------------------------------
# demo


def test_demo_into_a_file_instead_of_a_folder(inputs, capsys):
    fails(capsys, ["demo", "-o", str(inputs["a_file"]), "--duration", "2"], "a_file")


@pytest.mark.parametrize("duration", ["0", "-1", "nan", "x"])
def test_demo_bad_duration_is_a_usage_error(capsys, duration):
    with pytest.raises(SystemExit) as exc:
        main(["demo", "--duration", duration])
    assert exc.value.code == EXIT_USAGE
    assert "--duration" in capsys.readouterr().err


# --------------------------------------------------------------------------------------------
# every error class from inside every subcommand

ARGV = {
    "ingest": ["ingest", "run.blf", "-o", "out.parquet"],
    "info": ["info", "run.blf"],
    "spectrum": ["spectrum", "run.blf"],
    "observe": ["observe", "campaign.toml", "-o", "obs.parquet"],
    "demo": ["demo", "-o", "demo-out"],
}

#: One instance of every class of the error tree (rigtools.errors), the physics' errors, and
#: an unreadable file; messages spanning lines must still print as one.
ERRORS: list[BaseException] = [
    RecordingFormatError("run.blf", 72, "a BLF object header", "b'XXXX'"),
    UnsupportedFormatError("run.xyz", 0, "a supported format", "b'??'"),
    PayloadDecodeError("run.mcap", 100, "an AccelBatch payload", "3 bytes"),
    SchemaUnusableError("run.mcap", 40, "a usable schema", "a schema that does not parse"),
    DbcError("rig.dbc", "line 3", "a valid DBC file", "cantools: bad\nsyntax"),
    MappingError("map.toml", "line 2", "a known signal", "'Acc9'"),
    NoDataError("run.blf", None, "at least one decodable channel", "none"),
    CampaignError("c.toml", "line 4", "a unique run id", "'A' again"),
    SignalError("nperseg", "an integer >= 2", "1"),
    InsufficientDataError("nperseg", "<= len(x)=10", "4096"),
    ConstantSignalError("x", detail="is constant"),
    MissingSpeedError("PinionSpeed_rpm", ("accel_1",), "not in the recording"),
    ModelError("`torque_Nm` must be finite,\n   was nan"),
    GeometryError("pinion.teeth", 2, "must be an integer >= 5"),
    ThermalJamError(5000.0, 3e8, 2e-5, 1e-5),
    FileNotFoundError(2, "No such file or directory", "run.blf"),
    PermissionError(13, "Permission denied", "out.parquet"),
]


def _raiser(exc: BaseException) -> Callable[..., int]:
    def run(args: object) -> int:
        raise exc

    return run


@pytest.mark.parametrize("exc", ERRORS, ids=lambda e: type(e).__name__)
@pytest.mark.parametrize("command", sorted(ARGV))
def test_every_error_class_from_every_subcommand(monkeypatch, capsys, command, exc):
    monkeypatch.setattr(getattr(rigtools.cli, command), "run", _raiser(exc))
    line = fails(capsys, ARGV[command])
    if isinstance(exc, OSError):
        assert line == f"rigtools: error: {exc.filename}: {exc.strerror}"
    else:
        assert line == "rigtools: error: " + " ".join(
            part.strip() for part in str(exc).splitlines())
    assert isinstance(exc, RigtoolsError | ModelError | OSError)
    # --debug re-raises it, traceback and all
    with pytest.raises(type(exc)):
        main(["--debug", *ARGV[command]])


@pytest.mark.parametrize("command", sorted(ARGV))
def test_a_bug_keeps_its_traceback(monkeypatch, command):
    monkeypatch.setattr(getattr(rigtools.cli, command), "run",
                        _raiser(KeyError("a bug, not an input error")))
    with pytest.raises(KeyError, match="a bug"):
        main(ARGV[command])


def test_the_tree_is_covered():
    """Every exception class rigtools.errors exports has an instance in ERRORS."""
    import rigtools.errors as errors

    classes = {getattr(errors, n) for n in errors.__all__}
    classes = {c for c in classes if isinstance(c, type) and issubclass(c, Exception)}
    covered = {type(e) for e in ERRORS}
    assert classes - covered == {errors.RigtoolsError, errors.LocatedError}


# --------------------------------------------------------------------------------------------
# the console script itself, in a fresh interpreter


@pytest.mark.parametrize(("argv", "fragment"), [
    (["info", "{empty}"], "expected a non-empty recording"),
    (["observe", "{campaign_bad_gears}", "-o", "{dir}/obs.parquet"],
     "expected a gear set that loads"),
])
def test_the_console_script_prints_one_line_and_no_traceback(inputs, argv, fragment):
    args = [a.format(**{k: str(v) for k, v in inputs.items()}) for a in argv]
    proc = subprocess.run(
        [sys.executable, "-c", "import sys; from rigtools.cli import main; "
         "sys.exit(main(sys.argv[1:]))", *args], capture_output=True, text=True, timeout=300)
    assert proc.returncode == EXIT_UNUSABLE, proc.stderr
    assert proc.stdout == ""
    assert_one_line_error(proc.stderr, fragment)

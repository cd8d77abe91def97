"""``rigtools spectrum`` output and options (issue 17, must-holds 3 and 7).

Machine-readable output (``--json``, ``--csv``) parsed back; the text table aligned whatever
a channel's name; ``--response``, the frequency range and the dB scale; plots in the format
their suffix names, mesh orders labelled and the legend off the axes; a Welch window too long
refused before any work.
"""

from __future__ import annotations

import csv
import io
import json
import time
from pathlib import Path

import numpy as np
import pytest

from rigtools.cli import EXIT_UNUSABLE, EXIT_USAGE, main
from rigtools.cli.spectrum import MAX_NPERSEG, PLOT_SUFFIXES
from rigtools.cli.spectrum_tables import CSV_COLUMNS
from rigtools.demo.mcap_writer import write_accel_mcap
from rigtools.demo.synthetic import synthetic_run

F_N = 2950.0
LONG = "/imu/linear_acceleration.x"
MODE_KEYS = {"channel", "f_n_Hz", "f_n_sd_Hz", "zeta", "zeta_sd", "response", "kind", "flags"}


@pytest.fixture(scope="module")
def run_file(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Two accelerometers, one named like a ROS topic field; mesh 400 Hz, a mode at F_N."""
    run = synthetic_run(1.5, rng=1, n_channels=2, f_n_Hz=F_N)
    names = {"accel_1": "accel_1", "accel_2": LONG}
    chans = {names[k]: (v, run.sample_rate_Hz, "m/s^2", 0, run.start_time_s)
             for k, v in run.channels.items()}
    return write_accel_mcap(tmp_path_factory.mktemp("spectrum") / "run.mcap", chans, run.slow,
                            None)


ARGS = ["--nperseg", "2048", "--mesh-frequency-Hz", "400"]


def _json(capsys: pytest.CaptureFixture[str], argv: list[str]) -> dict:
    assert main(argv) == 0
    cap = capsys.readouterr()
    assert cap.err == ""
    return json.loads(cap.out)  # the whole of stdout is the document


def test_json_holds_channels_lines_and_modes(run_file, capsys):
    doc = _json(capsys, ["spectrum", str(run_file), "--json", *ARGS])
    assert {"source", "welch", "channels", "lines", "modes"} <= set(doc)
    assert doc["welch"]["nperseg"] == 2048 and doc["mesh_frequency_Hz"] == 400.0
    assert sorted(c["channel"] for c in doc["channels"]) == sorted(["accel_1", LONG])
    assert all(c["unit"] == "m/s^2" and c["sample_rate_Hz"] == 25600.0 and c["rms_time"] > 0
               for c in doc["channels"])
    for ch in ("accel_1", LONG):
        mesh = [ln for ln in doc["lines"] if ln["channel"] == ch and ln["kind"] == "mesh_harmonic"]
        assert [ln["order"] for ln in mesh][:3] == [1, 2, 3]
        assert [ln["label"] for ln in mesh][:3] == ["1x mesh", "2x mesh", "3x mesh"]
        assert mesh[0]["f_Hz"] == pytest.approx(400.0, abs=2.0)
        (mode,) = [m for m in doc["modes"] if m["channel"] == ch]
        assert set(mode) == MODE_KEYS
        assert mode["kind"] == "structural" and isinstance(mode["flags"], list)
        assert mode["response"] == "acceleration"  # auto: the unit is m/s^2
        assert mode["f_n_Hz"] == pytest.approx(F_N, rel=0.02)
        assert 0 < mode["zeta_sd"] < mode["zeta"] < 0.05 and mode["f_n_sd_Hz"] > 0


def test_json_with_a_response_override(run_file, capsys):
    # synthetic_run's resonance is the mode's acceleration response: told so, the fit finds F_N
    doc = _json(capsys, ["spectrum", str(run_file), "--json", "--response", "acceleration",
                         *ARGS])
    for mode in doc["modes"]:
        assert mode["response"] == "acceleration"
        assert abs(mode["f_n_Hz"] - F_N) < max(3 * mode["f_n_sd_Hz"], 5.0)
    # the override is what is fitted, whatever the channel's unit says
    doc = _json(capsys, ["spectrum", str(run_file), "--json", "--response", "displacement",
                         *ARGS])
    assert doc["modes"] and all(m["response"] == "displacement" for m in doc["modes"])


def test_csv_holds_the_same_records(run_file, capsys):
    doc = _json(capsys, ["spectrum", str(run_file), "--json", *ARGS])
    assert main(["spectrum", str(run_file), "--csv", *ARGS]) == 0
    cap = capsys.readouterr()
    assert cap.err == ""
    reader = csv.DictReader(io.StringIO(cap.out))
    assert reader.fieldnames == list(CSV_COLUMNS)
    rows = list(reader)
    by = {k: [r for r in rows if r["record"] == k] for k in ("channel", "line", "mode")}
    assert len(rows) == sum(map(len, by.values()))
    assert [r["channel"] for r in by["channel"]] == [c["channel"] for c in doc["channels"]]
    assert len(by["line"]) == len(doc["lines"])
    assert len(by["mode"]) == len(doc["modes"])
    for row, mode in zip(by["mode"], doc["modes"], strict=True):
        assert row["channel"] == mode["channel"] and row["kind"] == "structural"
        assert float(row["f_n_Hz"]) == mode["f_n_Hz"] and float(row["zeta"]) == mode["zeta"]
        assert float(row["f_n_sd_Hz"]) == mode["f_n_sd_Hz"]
        assert row["response"] == mode["response"]
        assert row["flags"].split(";") == (mode["flags"] or [""])
        assert row["f_Hz"] == "" and row["unit"] == ""  # cells that do not apply are empty
    assert [int(r["order"]) for r in by["line"] if r["kind"] == "mesh_harmonic"][:3] == [1, 2, 3]
    with pytest.raises(SystemExit) as exc:
        main(["spectrum", str(run_file), "--csv", "--json"])
    assert exc.value.code == EXIT_USAGE


def test_text_columns_stay_aligned_with_a_long_channel_name(run_file, capsys):
    assert main(["spectrum", str(run_file), *ARGS]) == 0
    out = capsys.readouterr().out.splitlines()
    header = next(ln for ln in out if ln.startswith("channel") and "unit" in ln)
    rows = [ln for ln in out if ln.startswith(("accel_1", LONG)) and "m/s^2" in ln]
    assert len(rows) == 2
    for row in rows:
        assert row.split()[1] == "m/s^2"  # not '/imu/linear_acceleration.xm/s^2'
        assert row.index("m/s^2") == header.index("unit")
        assert row.index("25600") + len("25600") == header.index("rate Hz") + len("rate Hz")
    peak_header = next(ln for ln in out if ln.startswith("channel") and "kind" in ln)
    peaks = [ln for ln in out if ln.startswith(("accel_1", LONG)) and "m/s^2" not in ln]
    kinds = {ln.index(k) for ln in peaks for k in ("mesh_harmonic", "structural") if k in ln}
    assert kinds == {peak_header.index("kind")}


def test_frequency_range_limits_the_peaks(run_file, capsys):
    doc = _json(capsys, ["spectrum", str(run_file), "--json", *ARGS, "--f-min-Hz", "2000",
                         "--f-max-Hz", "5000"])
    assert doc["lines"] == [] or all(2000 <= ln["f_Hz"] <= 5000 for ln in doc["lines"])
    assert len(doc["modes"]) == 2  # the mode at F_N is inside
    for lo, hi in (("3000", "2000"), ("2000", "2000")):
        with pytest.raises(SystemExit) as exc:
            main(["spectrum", str(run_file), "--f-min-Hz", lo, "--f-max-Hz", hi])
        assert exc.value.code == EXIT_USAGE
        assert "--f-max-Hz: must be > --f-min-Hz" in capsys.readouterr().err


@pytest.mark.parametrize(("suffix", "magic"), [(".png", b"\x89PNG"), (".svg", b"<svg"),
                                               (".pdf", b"%PDF"), (".jpg", b"\xff\xd8\xff"),
                                               (".JPEG", b"\xff\xd8\xff")])
def test_plot_is_written_in_the_format_its_suffix_names(run_file, tmp_path, capsys, suffix,
                                                         magic):
    out = tmp_path / f"psd{suffix}"
    assert main(["spectrum", str(run_file), *ARGS, "--db", "--plot", str(out)]) == 0
    assert f"wrote {out}" in capsys.readouterr().out
    data = out.read_bytes()
    assert (magic in data[:400]) if suffix == ".svg" else data.startswith(magic)


@pytest.mark.parametrize("name", ["psd.gif", "psd", "psd.png.txt"])
def test_plot_suffix_not_written_is_a_usage_error(run_file, tmp_path, capsys, name):
    with pytest.raises(SystemExit) as exc:
        main(["spectrum", str(run_file), "--plot", str(tmp_path / name)])
    assert exc.value.code == EXIT_USAGE
    err = capsys.readouterr().err
    assert "argument --plot" in err and "accepted: " + ", ".join(PLOT_SUFFIXES) in err
    assert not (tmp_path / name).exists()


def test_unwritable_plot_is_refused_before_reading(tmp_path, capsys):
    # the input does not exist: the error names the plot, so nothing was read
    missing_input = tmp_path / "never_read.mcap"
    assert main(["spectrum", str(missing_input), "--plot",
                 str(tmp_path / "no" / "such" / "psd.png")]) == EXIT_UNUSABLE
    err = capsys.readouterr().err
    assert "psd.png: cannot write the file: no such folder" in err
    assert "never_read" not in err


def test_plot_labels_mesh_orders_and_keeps_the_legend_off_the_axes(run_file):
    from rigtools.analysis import analyse_recording
    from rigtools.ingest import read
    from rigtools.plots.spectrum import plot_spectrum

    analysis = analyse_recording(read(run_file), nperseg=2048, mesh_frequency_Hz=400.0)
    for db in (False, True):
        fig = plot_spectrum(analysis, "run", db=db, f_range_Hz=(100.0, 6000.0))
        ax = fig.axes[0]
        labels = {t.get_text() for t in ax.texts}
        assert {"1x mesh", "2x mesh", "3x mesh"} <= labels
        assert ax.get_xlim() == (100.0, 6000.0)
        assert ("dB" in ax.get_ylabel()) == db
        (legend,) = fig.legends
        fig.canvas.draw()
        renderer = fig.canvas.get_renderer()
        box, axes_box = legend.get_window_extent(renderer), ax.get_window_extent(renderer)
        assert not box.overlaps(axes_box), (box, axes_box)  # the legend covers no peak
        assert any(t.get_text().startswith("accel_1: f_n 29") for t in legend.get_texts())


def test_a_window_too_long_is_refused_before_any_work(tmp_path, capsys):
    started = time.perf_counter()
    with pytest.raises(SystemExit) as exc:
        main(["spectrum", str(tmp_path / "never_read.mcap"), "--nperseg", "100000000"])
    assert exc.value.code == EXIT_USAGE
    assert time.perf_counter() - started < 5.0
    err = capsys.readouterr().err
    assert f"--nperseg: must be an integer <= {MAX_NPERSEG}" in err
    with pytest.raises(SystemExit):
        main(["spectrum", "--help"])
    assert f"16 to {MAX_NPERSEG}" in " ".join(capsys.readouterr().out.split())


def test_response_choices_are_listed_and_checked(run_file, capsys):
    with pytest.raises(SystemExit) as exc:
        main(["spectrum", str(run_file), "--response", "jerk"])
    assert exc.value.code == EXIT_USAGE
    assert "invalid choice: 'jerk'" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        main(["spectrum", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    assert "{auto,acceleration,velocity,displacement}" in text
    for option in ("--f-min-Hz", "--f-max-Hz", "--db", "--json", "--csv"):
        assert option in text


def test_no_analysable_channel_still_prints_json(tmp_path, capsys):
    dead = write_accel_mcap(tmp_path / "dead.mcap",
                            {"accel_1": (np.zeros(6000), 25600.0, "m/s^2", 0, 1.7e9)})
    assert main(["spectrum", str(dead), "--json"]) == EXIT_UNUSABLE
    cap = capsys.readouterr()
    doc = json.loads(cap.out)
    assert doc["modes"] == [] and doc["channels"][0]["error"]
    assert "constant" in doc["channels"][0]["flags"]
    assert "no channel could be analysed" in cap.err

"""The analysis command line: ``rigtools spectrum`` and ``rigtools observe``; exit codes."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

from rigtools.campaign import read_observations, validate_observations
from rigtools.cli import EXIT_UNUSABLE, main
from rigtools.demo.can_writer import encode_reference_frames, write_can_log
from rigtools.demo.mcap_writer import write_accel_mcap
from rigtools.demo.synthetic import synthetic_run
from rigtools.errors import CampaignError

F_N = 2950.0
FS = 25_600.0


def mcap_run(path: Path, seed: int = 1, duration_s: float = 1.5, dead: bool = False) -> Path:
    run = synthetic_run(duration_s, rng=seed, n_channels=2, f_n_Hz=F_N)
    chans = {k: (v, run.sample_rate_Hz, "m/s^2", 0, run.start_time_s)
             for k, v in run.channels.items()}
    if dead:
        chans = {k: (np.zeros_like(v[0]), *v[1:]) for k, v in chans.items()}
    return write_accel_mcap(path, chans, run.slow, None)


def blf_run(path: Path, seed: int = 2, duration_s: float = 1.5) -> Path:
    run = synthetic_run(duration_s, rng=seed, n_channels=4, f_n_Hz=F_N, torque_Nm=200.0)
    slow = {name: vals for name, (_, vals, _) in run.slow.items()}
    frames = encode_reference_frames([run.channels[f"accel_{i}"] for i in range(1, 5)], slow,
                                     start_time_s=run.start_time_s, rng=1)
    return write_can_log(path, frames, "blf", engine="rigtools")


CAMPAIGN = """\
[campaign]
name = "cli study"
gear_set = "fzg-c"

[sensors]
accel = ["accel_1", "accel_2"]
speed = "PinionSpeed_rpm"

[analysis]
nperseg = 2048
min_step_duration_s = 0.5

[[run]]
id = "LS9-90C"
file = "runs/a.mcap"
torque_Nm = 302.0
bulk_temperature_C = 90.0
speed_rpm = 1500.0

[[run]]
id = "LS5-70C"
file = "runs/b.blf"
torque_Nm = "Torque_Nm"
bulk_temperature_C = 70.0

[[run]]
id = "LS7-80C"
file = "runs/lost.mcap"
"""


@pytest.fixture(scope="module")
def files(tmp_path_factory) -> dict[str, Path]:
    d = tmp_path_factory.mktemp("cli")
    (d / "runs").mkdir()
    out = {"mcap": mcap_run(d / "runs" / "a.mcap"), "blf": blf_run(d / "runs" / "b.blf"),
           "dead": mcap_run(d / "dead.mcap", dead=True, duration_s=0.5), "dir": d}
    (d / "study.toml").write_text(CAMPAIGN)
    out["campaign"] = d / "study.toml"
    return out


# --------------------------------------------------------------------------------------------
# rigtools spectrum


def _peak_lines(out: str, channel: str) -> list[list[str]]:
    """The peak rows of ``channel``: f, +-, prom, kind, f_n, +-, zeta, +-, then the notes."""
    return [ln.split() for ln in out.splitlines()
            if ln.startswith(channel) and len(ln.split()) >= 10 and "m/s^2" not in ln]


def test_spectrum_prints_rms_and_the_resonance_per_channel(files, capsys):
    # synthetic_run's resonance is the mode's acceleration response under an m/s^2 unit: the
    # fit follows the unit (no --response)
    assert main(["spectrum", str(files["mcap"]), "--nperseg", "2048",
                 "--mesh-frequency-Hz", "400"]) == 0
    cap = capsys.readouterr()
    assert cap.err == ""
    out = cap.out
    assert "nperseg 2048 (12.5 Hz bins)" in out
    header = next(ln for ln in out.splitlines() if ln.startswith("channel") and "RMS" in ln)
    assert "RMS time" in header and "RMS PSD" in header
    for ch in ("accel_1", "accel_2"):
        chan_line = next(ln for ln in out.splitlines() if ln.startswith(ch) and "m/s^2" in ln)
        assert chan_line.split()[2] == "25600"
        peaks = _peak_lines(out, ch)
        kinds = [p[4] for p in peaks]
        assert kinds[:3] == ["mesh_harmonic"] * 3  # 400, 800, 1200 Hz
        assert [" ".join(p[9:]) for p in peaks[:3]] == ["1x mesh", "2x mesh", "3x mesh"]
        (structural,) = [p for p in peaks if p[4] == "structural"]
        f_n, f_std, zeta = float(structural[5]), float(structural[6]), float(structural[7])
        assert abs(f_n - F_N) < max(3 * f_std, 5.0)
        assert 0.01 < zeta < 0.03


def test_spectrum_of_one_channel_of_a_can_log_with_a_plot(files, tmp_path, capsys):
    png = tmp_path / "psd.png"
    assert main(["spectrum", str(files["blf"]), "--channel", "accel_3", "--plot",
                 str(png)]) == 0
    out = capsys.readouterr().out
    assert f"wrote {png}" in out
    assert "accel_3" in out and "accel_1" not in out
    data = png.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n" and len(data) > 10_000


def test_spectrum_plot_uses_no_pyplot(files):
    from matplotlib import _pylab_helpers

    from rigtools.analysis import analyse_recording
    from rigtools.ingest import read
    from rigtools.plots.spectrum import plot_spectrum

    fig = plot_spectrum(analyse_recording(read(files["mcap"]), nperseg=2048), "a")
    assert type(fig.canvas).__name__ == "FigureCanvasAgg"
    assert "accel_1: f_n 29" in fig.legends[0].get_texts()[0].get_text()
    assert not _pylab_helpers.Gcf.get_all_fig_managers()


def test_spectrum_exit_codes(files, tmp_path, capsys):
    assert main(["spectrum", str(files["mcap"]), "--channel", "accel_7"]) == EXIT_UNUSABLE
    err = capsys.readouterr().err
    assert err.startswith("rigtools: error: ") and "'accel_7'" in err and "accel_1" in err
    assert main(["spectrum", str(files["dead"])]) == EXIT_UNUSABLE
    cap = capsys.readouterr()
    assert "constant" in cap.out and "rigtools: warning: channel 'accel_1'" in cap.err
    assert "no channel could be analysed" in cap.err
    assert main(["spectrum", str(tmp_path / "none.mcap")]) == EXIT_UNUSABLE
    assert "no such file" in capsys.readouterr().err
    with pytest.raises(SystemExit) as exc:
        main(["spectrum"])
    assert exc.value.code == 2


@pytest.mark.parametrize(("option", "value", "message"), [
    ("--nperseg", "1", "--nperseg: must be an integer >= 16"),
    ("--nperseg", "abc", "--nperseg: not an integer"),
    ("--prominence-dB", "nan", "--prominence-dB: must be finite"),
    ("--prominence-dB", "-3", "--prominence-dB: must be >= 0"),
    ("--mesh-frequency-Hz", "inf", "--mesh-frequency-Hz: must be finite"),
    ("--mesh-frequency-Hz", "0", "--mesh-frequency-Hz: must be > 0"),
    ("--mesh-frequency-Hz", "-400", "--mesh-frequency-Hz: must be > 0"),
    ("--z1", "0", "--z1: must be an integer >= 1"),
])
def test_spectrum_rejects_bad_options_with_exit_2(files, capsys, option, value, message):
    with pytest.raises(SystemExit) as exc:
        main(["spectrum", str(files["mcap"]), option, value])
    assert exc.value.code == 2
    assert message in capsys.readouterr().err


def test_spectrum_derives_the_mesh_frequency_from_speed_and_z1(files, capsys):
    # synthetic run: z1 = 16 at 1500 rpm, mesh 400 Hz
    assert main(["spectrum", str(files["mcap"]), "--nperseg", "2048", "--z1", "16"]) == 0
    cap = capsys.readouterr()
    assert cap.err == ""
    assert "mesh frequency 400 Hz = z1 16 x mean PinionSpeed_rpm" in cap.out
    # 1.5 s at nperseg 2048: few averages, flagged
    chan_line = next(ln for ln in cap.out.splitlines()
                     if ln.startswith("accel_1") and "m/s^2" in ln)
    dof = float(chan_line.split()[4])
    assert ("low_dof" in chan_line) == (dof < 35)
    kinds = [p[4] for p in _peak_lines(cap.out, "accel_1")]
    assert kinds[:3] == ["mesh_harmonic"] * 3
    # an explicit mesh frequency wins; a missing speed signal is a warning, not an error
    assert main(["spectrum", str(files["mcap"]), "--nperseg", "2048", "--z1", "16",
                 "--mesh-frequency-Hz", "400"]) == 0
    assert "mesh frequency 400 Hz = " not in capsys.readouterr().out
    assert main(["spectrum", str(files["mcap"]), "--nperseg", "2048", "--z1", "16",
                 "--speed-signal", "NoSuch_rpm"]) == 0
    err = capsys.readouterr().err
    assert "--z1 given but no slow signal 'NoSuch_rpm'" in err


# --------------------------------------------------------------------------------------------
# rigtools observe


def test_observe_writes_the_table_and_reports_the_failed_run(files, tmp_path, capsys):
    out = tmp_path / "obs.parquet"
    assert main(["observe", str(files["campaign"]), "-o", str(out)]) == 0
    cap = capsys.readouterr()
    # the failed run: on stderr with its file and the reason, the others analysed
    assert re.search(r"rigtools: error: run 'LS7-80C' failed: .*runs/lost.mcap: .*no such file",
                     cap.err)
    assert "\r" not in cap.err  # no progress bar when stderr is not a terminal
    assert f"wrote {out}: " in cap.out and "2 of 3 run(s) analysed, 1 failed" in cap.out
    lines = {ln.split()[0]: ln.split() for ln in cap.out.splitlines() if ln.startswith("LS")}
    assert lines["LS9-90C"][1] == "ok" and lines["LS9-90C"][2] == "2/2"
    assert abs(float(lines["LS9-90C"][4]) - F_N) < 10
    assert lines["LS7-80C"][1] == "failed"
    df = read_observations(out)
    assert validate_observations(df) == []
    failed = df[df.run_id == "LS7-80C"]
    assert list(failed.status) == ["failed"] and "lost.mcap" in failed.message.iloc[0]
    b = df[(df.run_id == "LS5-70C") & (df.quantity == "run")].iloc[0]
    assert abs(b.torque_Nm - 200.0) < 0.5 and b.bulk_temperature_C == 70.0


def test_observe_exits_3_when_no_run_can_be_analysed(files, tmp_path, capsys):
    camp = tmp_path / "c.toml"
    camp.write_text(CAMPAIGN)  # no runs/ folder next to it
    out = tmp_path / "obs.parquet"
    assert main(["observe", str(camp), "-o", str(out)]) == EXIT_UNUSABLE
    err = capsys.readouterr().err
    assert err.count("rigtools: error: run ") == 3
    assert "no run could be analysed" in err
    assert len(read_observations(out)) == 3  # the failures are on record


def test_observe_bad_campaign_names_key_and_line(tmp_path, capsys):
    camp = tmp_path / "c.toml"
    camp.write_text(CAMPAIGN.replace('speed_rpm = 1500.0', 'speed_RPM = 1500.0'))
    assert main(["observe", str(camp), "-o", str(tmp_path / "o.parquet")]) == EXIT_UNUSABLE
    err = capsys.readouterr().err
    assert err.startswith(f"rigtools: error: {camp} at line 18: ")
    assert "unknown key 'speed_RPM' (did you mean 'speed_rpm'?)" in err
    assert not (tmp_path / "o.parquet").exists()
    with pytest.raises(CampaignError, match="line 18"):
        main(["--debug", "observe", str(camp), "-o", str(tmp_path / "o.parquet")])


def test_observe_progress_bar_on_a_terminal(files, tmp_path, capsys, monkeypatch):
    import sys

    pytest.importorskip("tqdm")
    camp = tmp_path / "c.toml"
    camp.write_text(CAMPAIGN.replace("runs/", str(files["dir"] / "runs") + "/"))
    bar = re.compile(r"observe:\s+\d+%\|[^|\n]*\| [0-3]/3 \[")  # tqdm's l_bar|bar| n/total [
    # forced on with --progress (stderr is not a terminal under capsys)
    assert main(["observe", str(camp), "-o", str(tmp_path / "o.parquet"), "--progress"]) == 0
    err = capsys.readouterr().err
    assert bar.search(err), err
    assert "rigtools: error: run 'LS7-80C' failed" in err
    # on by default on a terminal
    monkeypatch.setattr(sys.stderr, "isatty", lambda: True, raising=False)
    assert main(["observe", str(camp), "-o", str(tmp_path / "o.parquet")]) == 0
    assert bar.search(capsys.readouterr().err)
    # and off with --no-progress: the error line is there, the bar is not
    assert main(["observe", str(camp), "-o", str(tmp_path / "o.parquet"), "--no-progress"]) == 0
    err = capsys.readouterr().err
    assert not bar.search(err) and "rigtools: error: run 'LS7-80C' failed" in err

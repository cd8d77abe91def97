"""The demo job end to end: formats agree, round trips exact, analysis finds the truth."""

import json

from rigtools.cli import main


def test_demo_runs_and_recovers_the_synthetic_truth(tmp_path, capsys):
    out = tmp_path / "demo"
    assert main(["demo", "-o", str(out), "--duration", "2"]) == 0
    text = capsys.readouterr().out
    assert "all formats agree sample for sample" in text
    summary = json.loads((out / "summary.json").read_text())
    assert set(summary["formats"]) == {"mcap", "blf", "candump"}
    for f in summary["formats"].values():
        assert f["round_trip_exact"] and f["max_abs_error"] == 0.0
        assert f["report"]["rejected"] == {} and f["report"]["gaps"] == []
    truth = summary["truth"]
    a = summary["analysis"]["accel_1"]  # channel 1 has gain 1
    # Mesh harmonics: off-bin amplitudes from the Hann main lobe, within 5 % (noise 0.2 m/s^2).
    for h in ("A1", "A2", "A3"):
        assert abs(a[h] - truth[h]) < 0.05 * truth[h] + 0.05
    # Resonance: 12.5 Hz Welch bins and ~50 averages over 2 s: f_n within 2 %, zeta within 25 %.
    assert abs(a["f_n_Hz"] - truth["f_n_Hz"]) < 0.02 * truth["f_n_Hz"]
    assert abs(a["zeta"] - truth["zeta"]) < 0.25 * truth["zeta"]

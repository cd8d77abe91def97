"""Run-up data: arms rows to the curves the SDOF models are fitted to (issue 20, items 1 and 7).

Tables are built here row by row (``to_frame``) with a known path of the mesh frequency in
time, up then down, and an Arms curve with a resonance; every rule of
:mod:`rigtools.calibration.runup_data` is checked against that truth.
"""

from __future__ import annotations

import math
import pickle
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from rigtools.calibration.errors import CalibrationError
from rigtools.calibration.runup_config import RunUpSettings
from rigtools.calibration.runup_data import (
    MAX_GAP_FRACTION,
    WINDOW_NODES,
    WINDOW_WEIGHTS,
    RunUpCurve,
    RunUpDataError,
    has_interior_maximum,
    prepare_runup,
    prepare_runups,
    runup_runs,
)
from rigtools.campaign import load_campaign, to_frame, validate_observations

F_N = 1000.0  # the resonance of the synthetic Arms curve (Hz)


def arms_of(f: np.ndarray, gain: float = 1.0) -> np.ndarray:
    """A resonance in acceleration: f^2 times an SDOF magnification (m/s^2)."""
    r = f / F_N
    return gain * 1e-6 * (2 * np.pi * f) ** 2 / np.sqrt((1 - r * r) ** 2 + (0.1 * r) ** 2)


def ramp_rows(run_id: str = "R", *, n: int = 60, f0: float = 600.0, f1: float = 1500.0,
              channels: tuple[str, ...] = ("x", "y"), torque: float = 300.0,
              with_direction: bool = True, t0: float = 0.0) -> list[dict]:
    """Up from f0 to f1 then down, ``n`` windows each way, windows 0.1 s apart."""
    up = np.geomspace(f0, f1, n)
    f = np.concatenate([up, up[::-1][1:]])
    t = t0 + 0.1 * np.arange(f.size)
    d = ["up"] * n + ["down"] * (n - 1)
    d[n - 1] = "hold"
    rows = []
    for k, ch in enumerate(channels):
        a = arms_of(f, gain=1.0 / (k + 1))
        for i in range(f.size):
            h = a[i] * np.array([0.8, 0.5, 0.33]) / np.sqrt(0.8**2 + 0.5**2 + 0.33**2)
            rows.append({
                "campaign": "c", "run_id": run_id, "channel": ch, "quantity": "arms",
                "segment": "ramp", "step_index": i, "step_start_s": t[i] - 0.05,
                "step_stop_s": t[i] + 0.05, "mesh_frequency_Hz": f[i],
                "step_speed_rpm": 60 * f[i] / 50, "torque_Nm": torque,
                "direction": d[i] if with_direction else None,
                "a1_m_s2": h[0], "a2_m_s2": h[1], "a3_m_s2": h[2], "arms_m_s2": a[i],
                "n_windows": 1, "n_gaps": 0, "status": "ok", "quality_flags": "",
                "message": "", "source_file": "r.mcap", "rigtools_version": "0"})
    return rows


def steady_rows(run_id: str = "S") -> list[dict]:
    return [{"campaign": "c", "run_id": run_id, "channel": "x", "quantity": "arms",
             "segment": "step", "step_index": 0, "step_start_s": 0.0, "step_stop_s": 5.0,
             "mesh_frequency_Hz": 400.0, "step_speed_rpm": 1500.0, "torque_Nm": 100.0,
             "direction": "up", "a1_m_s2": 1.0, "a2_m_s2": 0.5, "a3_m_s2": 0.2,
             "arms_m_s2": float(np.sqrt(1.29)), "n_windows": 10, "n_gaps": 0, "status": "ok",
             "quality_flags": "", "message": "", "source_file": "s.mcap",
             "rigtools_version": "0"}]


GEARS = {"R": "kahraman-blankenship", "S": "fzg-c", "Q": "kahraman-blankenship"}


def test_a_clean_ramp_gives_its_curve_in_time_order():
    rows = ramp_rows()
    table = to_frame(rows[::-1])  # rows in any order
    assert validate_observations(table) == []
    c = prepare_runup(table, "R", "kahraman-blankenship")
    assert isinstance(c, RunUpCurve)
    assert c.channels == ("y", "x") and c.torque_Nm == 300.0  # in table order
    assert c.gear_set == "kahraman-blankenship"
    assert c.n_points == 119 and c.observed.shape == (2, 119) and c.harmonics.shape == (2, 119, 3)
    assert np.all(np.diff(c.time_s) > 0)
    f_truth = np.array([r["mesh_frequency_Hz"] for r in rows[:119]])
    np.testing.assert_allclose(c.mesh_frequency_Hz, f_truth)
    np.testing.assert_allclose(c.observed[1], arms_of(f_truth))
    np.testing.assert_allclose(c.observed[0], arms_of(f_truth) / 2)
    np.testing.assert_allclose(np.sqrt(np.sum(c.harmonics**2, axis=2)), c.observed)
    assert list(c.direction[:59]) == ["up"] * 59 and c.direction[59] == "hold"
    assert set(c.direction[60:]) == {"down"}
    assert c.notes == ()
    assert c.observed_mask.all()


def test_directions_missing_from_the_table_are_computed():
    c = prepare_runup(to_frame(ramp_rows(with_direction=False)), "R", "kb")
    d = np.array(c.direction)
    assert set(d[:55]) == {"up"} and set(d[-55:]) == {"down"}
    assert set(d) <= {"up", "down", "hold"}


def test_thinning_keeps_time_order_and_at_most_max_points_per_direction():
    rows = ramp_rows(n=300)
    table = to_frame(rows)
    c = prepare_runup(table, "R", "kb", RunUpSettings(max_speed_points=50))
    d = np.array(c.direction)
    for way in ("up", "down"):
        assert 40 <= np.count_nonzero(d == way) <= 50
    assert np.all(np.diff(c.time_s) > 0)
    up = c.mesh_frequency_Hz[d == "up"]
    assert np.all(np.diff(up) > 0) and np.all(np.diff(c.mesh_frequency_Hz[d == "down"]) < 0)
    # every point is one of the windows, with its own values (no medians over a bin)
    windows = {round(r["step_start_s"] + 0.05, 6): r for r in rows if r["channel"] == "x"}
    for f, t, a, h in zip(c.mesh_frequency_Hz, c.time_s, c.observed[0], c.harmonics[0],
                          strict=True):
        r = windows[round(t, 6)]
        assert f == r["mesh_frequency_Hz"]
        assert a == r["arms_m_s2"] and h[0] == r["a1_m_s2"]
    np.testing.assert_allclose(c.observed[0], arms_of(c.mesh_frequency_Hz), rtol=1e-12)
    assert any("thinned" in n for n in c.notes)


def test_window_weights_integrate_cubics_against_the_hann_power_weight():
    # sin^4(pi u) on [0, 1] is the power weight of a Hann window; checked by dense quadrature
    u = np.linspace(0.0, 1.0, 400_001)
    w = np.sin(np.pi * u) ** 4
    nodes = 0.5 + np.asarray(WINDOW_NODES)
    assert sum(WINDOW_WEIGHTS) == pytest.approx(1.0, abs=1e-15)
    for k in range(4):
        exact = np.trapezoid((u - 0.5) ** k * w, u) / np.trapezoid(w, u)
        rule = float(np.dot(WINDOW_WEIGHTS, (nodes - 0.5) ** k))
        assert rule == pytest.approx(exact, abs=1e-9)
    # by hand: the variance about the middle is 1/12 - 5/(8 pi^2)
    assert float(np.dot(WINDOW_WEIGHTS, (nodes - 0.5) ** 2)) == pytest.approx(
        1 / 12 - 5 / (8 * np.pi ** 2), rel=1e-12)


def _time_at_angle(f0: float, slope: float, area: float) -> float:
    """The ``tau >= 0`` with ``f0 tau + slope tau^2 / 2 = area`` (angle under a linear f_m)."""
    if slope == 0.0:
        return area / f0
    return (-f0 + math.sqrt(f0 * f0 + 2.0 * slope * area)) / slope


def test_ramp_windows_carry_the_mesh_frequency_at_their_nodes():
    c = prepare_runup(to_frame(ramp_rows(n=60)), "R", "kb")
    nodes = c.nodes_Hz
    assert nodes.shape == (c.n_points, 3)
    # By hand. Windows 0.1 s long, 0.1 s apart, f_m piecewise linear through the window
    # middles: window i runs from the midpoint value m- = (f[i-1] + f[i]) / 2 to f[i] over its
    # first half and on to m+ = (f[i] + f[i+1]) / 2 over its second. Its nodes are where it has
    # turned 1/4, 1/2 and 3/4 of its angle (the integral of f_m; the analysis' Hann window is
    # in angle), each found by solving the quadratic of the angle under a linear f_m.
    up = np.geomspace(600.0, 1500.0, 60)
    i, h = 10, 0.05
    lo, hi = 0.5 * (up[i - 1] + up[i]), 0.5 * (up[i] + up[i + 1])
    a1, a2 = h * 0.5 * (lo + up[i]), h * 0.5 * (up[i] + hi)
    total = a1 + a2
    expected = []
    for frac in (0.25, 0.5, 0.75):
        target = frac * total
        if target <= a1:
            tau = _time_at_angle(lo, (up[i] - lo) / h, target)
            expected.append(lo + (up[i] - lo) / h * tau)
        else:
            tau = _time_at_angle(up[i], (hi - up[i]) / h, target - a1)
            expected.append(up[i] + (hi - up[i]) / h * tau)
    np.testing.assert_allclose(nodes[i], expected, rtol=1e-8)  # 129-point angle quadrature
    # the angle weighs the faster second half more: the middle node lies above f[i], and the
    # nodes a quarter of the way to the neighbours at equal *times* are not the rule
    assert nodes[i, 1] > up[i] * (1 + 1e-5)
    assert abs(nodes[i, 0] - (up[i] + 0.25 * (up[i - 1] - up[i]))) > 1e-3 * (up[i] - up[i - 1])
    # on the way down the first node is the higher frequency (time order)
    down = np.flatnonzero(np.array(c.direction) == "down")
    assert np.all(nodes[down, 0] > nodes[down, 2])
    # the first window: f_m extended linearly before the first middle (not held at f[0])
    lo0 = up[0] - 0.5 * (up[1] - up[0])
    assert nodes[0, 0] < up[0] and nodes[0, 0] > lo0


def test_speed_steps_keep_their_own_mesh_frequency_at_every_node():
    rows = []
    for i, f in enumerate(np.geomspace(500.0, 1500.0, 30)):
        row = steady_rows()[0] | {"step_index": i, "step_start_s": 6.0 * i,
                                  "step_stop_s": 6.0 * i + 5.0, "mesh_frequency_Hz": f,
                                  "arms_m_s2": float(arms_of(np.array([f]))[0])}
        rows.append(row)
    c = prepare_runup(to_frame(rows), "S", "kb")
    assert c.n_points == 30
    np.testing.assert_array_equal(c.nodes_Hz, np.repeat(c.mesh_frequency_Hz[:, None], 3, 1))


def test_a_gap_is_bridged_by_model_only_points():
    rows = [r for r in ramp_rows() if not (r["direction"] == "up" and
                                           900.0 < r["mesh_frequency_Hz"] < 1000.0)]
    c = prepare_runup(to_frame(rows), "R", "kb")
    assert any("gap" in n and "bridged" in n for n in c.notes)
    bridged = ~c.observed_mask
    assert bridged.any()
    assert np.all(np.isnan(c.observed[:, bridged])) and np.all(np.isnan(c.harmonics[:, bridged]))
    assert set(c.direction[bridged]) == {"up"}
    assert np.all((c.mesh_frequency_Hz[bridged] > 880) & (c.mesh_frequency_Hz[bridged] < 1010))
    # the model never steps further than the median spacing (times the bridge factor)
    steps = np.abs(np.diff(np.log(c.mesh_frequency_Hz)))
    full = np.abs(np.diff(np.log(np.geomspace(600.0, 1500.0, 60))))
    assert steps.max() <= 1.0001 * full.max()
    assert np.all(np.diff(c.time_s) > 0)


def test_a_gap_over_a_quarter_of_the_span_refuses_the_run():
    lo, hi = 700.0, 1000.0
    assert np.log(hi / lo) / np.log(1500.0 / 600.0) > MAX_GAP_FRACTION
    rows = [r for r in ramp_rows() if not (r["direction"] == "up" and
                                           lo < r["mesh_frequency_Hz"] < hi)]
    with pytest.raises(RunUpDataError, match=r"run 'R': a gap .* cannot be bridged"):
        prepare_runup(to_frame(rows), "R", "kb")


def test_no_usable_speed_is_refused_with_the_rows_reason():
    table = to_frame([
        {"campaign": "c", "run_id": "Q", "channel": ch, "quantity": "arms", "status": "failed",
         "quality_flags": "speed_missing",
         "message": "speed signal 'PinionSpeed_rpm' not in the recording",
         "source_file": "q.mcap", "rigtools_version": "0"} for ch in ("x", "y")])
    with pytest.raises(RunUpDataError, match=r"run 'Q': no usable speed signal.*PinionSpeed"):
        prepare_runup(table, "Q", "kb")
    data = prepare_runups(table, GEARS)
    assert data.curves == () and "no usable speed signal" in data.refused["Q"]


def test_too_few_points_and_too_narrow_a_span_are_refused():
    few = to_frame(ramp_rows(n=8))
    with pytest.raises(RunUpDataError, match=r"run 'R': 15 usable speed point\(s\), fewer than "
                                             r"min_speed_points = 20"):
        prepare_runup(few, "R", "kb")
    narrow = to_frame(ramp_rows(f0=1000.0, f1=1200.0))
    with pytest.raises(RunUpDataError, match=r"run 'R': the mesh frequency spans 1000-1200 Hz "
                                             r"\(max/min 1\.2\), less than min_span = 1\.3"):
        prepare_runup(narrow, "R", "kb")
    no_torque = to_frame(ramp_rows(torque=np.nan))
    with pytest.raises(RunUpDataError, match="run 'R': no torque_Nm"):
        prepare_runup(no_torque, "R", "kb")


def test_rows_above_the_passband_are_left_out_with_a_note():
    rows = ramp_rows()
    for r in rows:
        if r["mesh_frequency_Hz"] > 1400.0:
            r.update(a3_m_s2=None, arms_m_s2=None, status="flagged",
                     quality_flags="above_passband", message="a mesh harmonic above ...")
    c = prepare_runup(to_frame(rows), "R", "kb")
    assert c.mesh_frequency_Hz.max() < 1400.0
    assert any("above the resampler's passband" in n for n in c.notes)
    n_left = sum(r["quality_flags"] == "above_passband" for r in rows)
    assert any(n.startswith(f"{n_left} arms row(s) left out") for n in c.notes)


def test_low_snr_rows_are_kept_and_counted():
    rows = ramp_rows()
    for r in rows[:10]:
        r.update(status="flagged", quality_flags="low_snr", flag_low_snr=True)
    c = prepare_runup(to_frame(rows), "R", "kb")
    assert c.observed_mask.sum() == 119
    assert any(n.startswith("10 arms row(s) kept with low_snr") for n in c.notes)


def test_prepare_runups_picks_runups_and_refuses_each_bad_one_by_name():
    table = to_frame([*ramp_rows("R"), *steady_rows("S"), *ramp_rows("Q", n=5, t0=100.0)])
    data = prepare_runups(table, GEARS)
    assert [c.run_id for c in data.curves] == ["R"]
    assert data.curves[0].gear_set == "kahraman-blankenship"
    # the steady run is no run-up: neither a curve nor a refusal
    assert set(data.refused) == {"Q"} and data.refused["Q"].startswith("run 'Q': 9 usable")
    # the runs whose usable rows span min_span, usable for a fit or not
    assert runup_runs(table) == ["R", "Q"]
    assert runup_runs(table, min_span=3.0) == []
    # asked for by name, the steady run is refused with its reason
    named = prepare_runups(table, GEARS, runs=["S"])
    assert named.curves == () and "fewer than min_speed_points" in named.refused["S"]
    # a run without a gear set is refused, not an error
    assert "no gear set" in prepare_runups(table, {}).refused["R"]


def test_prepare_runups_takes_the_run_gear_sets_from_the_campaign(tmp_path: Path):
    (tmp_path / "c.toml").write_text("""\
[campaign]
name = "c"
gear_set = "fzg-c"
[[run]]
id = "R"
file = "r.mcap"
gear_set = "kahraman-blankenship"
[[run]]
id = "S"
file = "s.mcap"
""")
    camp = load_campaign(tmp_path / "c.toml")
    table = to_frame([*ramp_rows("R"), *ramp_rows("S", t0=50.0), *ramp_rows("X", t0=99.0)])
    data = prepare_runups(table, camp)
    assert {c.run_id: c.gear_set for c in data.curves} == {"R": "kahraman-blankenship",
                                                           "S": "fzg-c"}
    assert "not a run of the campaign" in data.refused["X"]


def test_has_interior_maximum_tells_a_resonance_from_a_ramp_below_it():
    c = prepare_runup(to_frame(ramp_rows()), "R", "kb")
    assert has_interior_maximum(c)
    below = prepare_runup(to_frame(ramp_rows(f0=300.0, f1=700.0)), "R", "kb")
    assert not has_interior_maximum(below)
    above = prepare_runup(to_frame(ramp_rows(f0=1500.0, f1=3000.0)), "R", "kb")
    assert not has_interior_maximum(above)


def test_the_error_names_the_run_and_survives_pickling():
    e = RunUpDataError("too few points", run="R")
    assert isinstance(e, CalibrationError) and str(e) == "run 'R': too few points"
    e2 = pickle.loads(pickle.dumps(e))
    assert type(e2) is RunUpDataError and str(e2) == str(e) and e2.run == "R"


def test_a_table_without_the_columns_is_an_error():
    with pytest.raises(CalibrationError, match="no column 'quantity'"):
        prepare_runups(pd.DataFrame({"run_id": ["R"]}), GEARS)

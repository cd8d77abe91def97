"""The observation model of the SDOF run-up calibration, on synthetic housing signals.

Issue 20 item 1 (PLAN section 1): the housing acceleration of mesh harmonic h on channel c is
``a_{c,h} = G_c (2 pi h f_m)^2 D_h``, with ``D_h`` the peak DTE amplitude of harmonic h (m)
and ``G_c`` a dimensionless gain; the ``arms`` rows must read it back. The signals are made
here by another route than the analysis takes: a sum of cosines at the mesh harmonics, phase
continuous (the angle is the running integral of the true speed), with known ``G_c`` and a
smooth DTE resonance ``D_h(f_m)``, plus broadband noise; the analysis gets only a logged speed
(100 Hz, with 0.1 rpm of noise) and finds steps or windows, resamples in angle and reads the orders
(``observe_campaign``, the project's path). The runs are on the Kahraman-Blankenship pair
(z1 = 50) through ``[[run]] gear_set`` in an FZG-C campaign (z1 = 16): with the campaign's teeth
the harmonics would be read at the wrong orders.
"""

from __future__ import annotations

import itertools
import math
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from rigtools.calibration.runup_config import RunUpSettings
from rigtools.calibration.runup_data import has_interior_maximum, prepare_runups
from rigtools.campaign import load_campaign, observe_campaign, validate_observations
from rigtools.campaign.observe_orders import ramp_directions, step_directions
from rigtools.demo.mcap_writer import write_accel_mcap

FS = 12_800.0
Z1 = 50  # Kahraman-Blankenship pinion
GAINS = {"accel_1": 1.0e-2, "accel_2": 4.0e-3}
D0 = (1.0e-6, 0.4e-6, 0.4e-6)  # DTE amplitudes of harmonics 1-3 off resonance (m, peak)
PHASES = (0.3, 1.1, -0.7)
F_R, ZETA_R = 800.0, 0.1  # a broad DTE resonance of harmonic 1 (Hz, 1)
NOISE = 0.01  # broadband housing noise (m/s^2, sd)
START = 1_763_800_000.0
HALF_S = 3.2  # the ramp's turn (s)


def dte_amplitude(f_m: np.ndarray, h: int) -> np.ndarray:
    """D_h at mesh frequency f_m (m): harmonic h excites the resonance at h f_m."""
    r = h * np.asarray(f_m, float) / F_R
    return D0[h - 1] / np.sqrt((1 - r * r) ** 2 + (2 * ZETA_R * r) ** 2)


def housing(f_m: np.ndarray, h: int, gain: float) -> np.ndarray:
    """a_h = G (2 pi h f_m)^2 D_h (m/s^2)."""
    return gain * (2 * np.pi * h * f_m) ** 2 * dte_amplitude(f_m, h)


def write_run(path: Path, rpm: np.ndarray, seed: int) -> Path:
    rng = np.random.default_rng(seed)
    theta = np.cumsum(rpm / 60.0) / FS  # pinion revolutions, phase continuous
    f_m = Z1 * rpm / 60.0
    chans = {}
    for name, g in GAINS.items():
        x = sum(housing(f_m, h, g) * np.cos(2 * np.pi * h * Z1 * theta + PHASES[h - 1])
                for h in (1, 2, 3))
        x = x + rng.normal(0.0, NOISE, x.size)
        chans[name] = (x, FS, "m/s^2", 0, START)
    t_log = np.arange(0.0, rpm.size / FS, 0.01)
    logged = np.interp(t_log, np.arange(rpm.size) / FS, rpm) + rng.normal(0.0, 0.1, t_log.size)
    return write_accel_mcap(path, chans, {"PinionSpeed_rpm": (START + t_log, logged, "rpm")},
                            None)


def ramp_rpm(n0: float = 700.0, rate: float = 0.15, half_s: float = HALF_S) -> np.ndarray:
    """Up then down, exponential in time (a constant relative rate per window)."""
    t = np.arange(int(2 * half_s * FS)) / FS
    return n0 * np.exp(rate * np.minimum(t, 2 * half_s - t))


def step_rpm(levels=(700.0, 900.0, 1100.0, 950.0, 800.0), dwell_s: float = 1.2,
             ramp_s: float = 0.15) -> np.ndarray:
    """Plateaus joined by short linear ramps (the phase stays continuous)."""
    parts = [np.full(int(dwell_s * FS), levels[0])]
    for a, b in itertools.pairwise(levels):
        parts.append(np.linspace(a, b, int(ramp_s * FS), endpoint=False))
        parts.append(np.full(int(dwell_s * FS), b))
    return np.concatenate(parts)


CAMPAIGN = """\
[campaign]
name = "run-up observation model"
gear_set = "fzg-c"

[sensors]
accel = ["accel_1", "accel_2"]
speed = "PinionSpeed_rpm"

[analysis]
max_peaks = 1                   # the modes are not what this test is about: keep it fast
prominence_dB = 60.0

[[run]]
id = "ramp"
file = "ramp.mcap"
torque_Nm = 300.0
gear_set = "kahraman-blankenship"

[[run]]
id = "steps"
file = "steps.mcap"
torque_Nm = 200.0
gear_set = "kahraman-blankenship"
"""


@pytest.fixture(scope="module")
def observed(tmp_path_factory) -> pd.DataFrame:
    d = tmp_path_factory.mktemp("runup_obs")
    write_run(d / "ramp.mcap", ramp_rpm(), seed=1)
    write_run(d / "steps.mcap", step_rpm(), seed=2)
    (d / "c.toml").write_text(CAMPAIGN)
    obs = observe_campaign(load_campaign(d / "c.toml"))
    assert all(r.analysed for r in obs.runs)
    return obs.table


def arms(df: pd.DataFrame, run: str) -> pd.DataFrame:
    return df[(df.run_id == run) & (df.quantity == "arms")].reset_index(drop=True)


def test_the_table_with_directions_is_valid(observed):
    assert validate_observations(observed) == []
    assert set(arms(observed, "ramp").segment) == {"ramp"}
    assert set(arms(observed, "steps").segment) == {"step"}


@pytest.mark.parametrize("run", ["ramp", "steps"])
def test_harmonics_read_back_the_observation_model(observed, run):
    rows = arms(observed, run)
    assert (rows.status != "failed").all()
    assert len(rows) >= (40 if run == "ramp" else 10)
    # mesh frequency on the run's pair: z1 = 50, not the campaign's 16
    np.testing.assert_allclose(rows.mesh_frequency_Hz, Z1 * rows.step_speed_rpm / 60, rtol=1e-9)
    mid = 0.5 * (rows.step_start_s + rows.step_stop_s)
    if run == "ramp":
        # windows of 8 revolutions away from the ends and the turn of the ramp
        keep = (mid > 0.7) & (mid < 2 * HALF_S - 0.7) & ((mid - HALF_S).abs() > 0.3)
    else:
        keep = np.ones(len(rows), bool)
    sub = rows[keep]
    assert len(sub) >= 10
    for ch, g in GAINS.items():
        s = sub[sub.channel == ch]
        f_m = s.mesh_frequency_Hz.to_numpy()
        expected = np.stack([housing(f_m, h, g) for h in (1, 2, 3)], axis=1)
        got = s[["a1_m_s2", "a2_m_s2", "a3_m_s2"]].to_numpy(float)
        np.testing.assert_allclose(got, expected, rtol=0.02,
                                   err_msg=f"{run} {ch}: a_h = G (2 pi h f_m)^2 D_h (PLAN 1)")
        # Arms is the root sum of squares of the three peak amplitudes (seed 003 Sec. 4)
        np.testing.assert_allclose(s.arms_m_s2, np.sqrt(np.sum(got**2, axis=1)), rtol=1e-9)
        np.testing.assert_allclose(s.arms_m_s2, np.sqrt(np.sum(expected**2, axis=1)),
                                   rtol=0.02)


def test_ramp_directions_follow_the_speed(observed):
    rows = arms(observed, "ramp")
    mid = 0.5 * (rows.step_start_s + rows.step_stop_s)
    up = mid < HALF_S - 0.6
    down = mid > HALF_S + 0.6
    assert (rows.direction[up] == "up").all()
    assert (rows.direction[down] == "down").all()
    assert set(rows.direction) <= {"up", "down", "hold"}
    assert up.sum() >= 15 and down.sum() >= 15


def test_step_directions_follow_the_steps(observed):
    rows = arms(observed, "steps")
    per_step = rows.groupby("step_index").agg(direction=("direction", "first"),
                                              rpm=("step_speed_rpm", "median"))
    assert list(per_step.direction) == ["up", "up", "up", "down", "down"]
    assert (rows.groupby("step_index").direction.nunique() == 1).all()


def test_the_runup_curve_of_the_observed_ramp(observed):
    data = prepare_runups(observed, {"ramp": "kahraman-blankenship",
                                     "steps": "kahraman-blankenship"},
                          RunUpSettings(min_speed_points=15))
    # the stepped run has 5 points, fewer than min_speed_points: refused, named
    assert set(data.refused) == {"steps"}
    assert "run 'steps'" in data.refused["steps"]
    assert "min_speed_points" in data.refused["steps"]
    (curve,) = data.curves
    assert curve.run_id == "ramp" and curve.torque_Nm == 300.0
    assert curve.channels == ("accel_1", "accel_2")
    assert np.all(np.diff(curve.time_s) > 0)
    d = list(curve.direction)
    first_down = d.index("down")
    assert set(d[:first_down]) <= {"up", "hold"} and set(d[first_down:]) == {"down"}
    # the two channels see one curve up to their gains
    ratio = curve.observed[1] / curve.observed[0]
    np.testing.assert_allclose(ratio[np.isfinite(ratio)], GAINS["accel_2"] / GAINS["accel_1"],
                               rtol=0.03)
    # the DTE resonance at 800 Hz lies inside 583-940 Hz: Arms / f_m^2 peaks inside
    assert has_interior_maximum(curve)
    top = Z1 * 700.0 * math.exp(0.15 * HALF_S) / 60
    assert math.isclose(float(np.nanmax(curve.mesh_frequency_Hz)), top, rel_tol=0.03)


def test_ramp_directions_are_robust_on_a_noisy_speed():
    # up for 5 s, a 2 s dwell, down for 5 s; windows 0.05 s apart, 0.5 % noise on each
    t = np.arange(240) * 0.05
    f = 600.0 * np.exp(0.1 * np.clip(np.minimum(t, 12.0 - t), None, 5.0))
    noisy = f * (1 + np.random.default_rng(3).normal(0.0, 0.005, t.size))
    d = ramp_directions(t, noisy, 0.01)
    assert (d[t < 4.8] == "up").all()
    assert (d[(t > 5.3) & (t < 6.7)] == "hold").all()
    assert (d[t > 7.2] == "down").all()
    # the order of the input does not matter
    perm = np.random.default_rng(4).permutation(t.size)
    assert list(ramp_directions(t[perm], noisy[perm], 0.01)) == list(d[perm])
    with pytest.raises(ValueError, match="`rel_tolerance` must be > 0"):
        ramp_directions(t, f, 0.0)


def test_step_directions_take_the_sign_of_the_change():
    assert list(step_directions([900.0, 700.0, 500.0], 0.01)) == ["down", "down", "down"]
    assert list(step_directions([500.0], 0.01)) == ["up"]
    assert list(step_directions([500.0, 502.0, 800.0, np.nan, 700.0], 0.01)) == [
        "up", "hold", "up", None, "down"]

"""A ramp window's value: what the analysis reads against what the run-up calibration models.

The calibration compares each ramp window's Arms with the model's power mean over the window
(:mod:`rigtools.calibration.runup_data`, "Windows": nodes at equal fractions of the window's
*angle*, the Hann weights of the order spectrum), and the analysis reads each harmonic over
a band wide enough for the modulation within the window
(:data:`rigtools.campaign.observe_orders.RAMP_BAND_BINS`). Checked here on housing signals
made by another route than the analysis takes: a sum of cosines at the mesh harmonics, phase
continuous along a linear speed ramp (the angle the running sum of the true speed), harmonic
1 through a resonance whose complex FRF sets its amplitude and phase at each instant
(quasi-static: no transient), harmonics 2 and 3 flat. The exact window value is integrated
here densely in angle, not with the package's quadrature.
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest

from rigtools.analysis.orders import run_up_curve
from rigtools.analysis.speed import speed_from_slow_signal
from rigtools.calibration.runup_config import RunUpSettings
from rigtools.calibration.runup_data import WINDOW_NODES, WINDOW_WEIGHTS, prepare_runups
from rigtools.campaign import load_campaign, observe_campaign
from rigtools.campaign.observe_orders import ramp_band_bins
from rigtools.demo.mcap_writer import write_accel_mcap

FS = 12_800.0
Z1 = 50                          # Kahraman-Blankenship pinion
GAIN = 1e-2
D0 = (1.0e-6, 0.3e-6, 0.2e-6)    # DTE amplitudes of harmonics 1-3 off resonance (m, peak)
F_R = 900.0                      # resonance of harmonic 1 (Hz)
N0, N1, HALF_S = 400.0, 1400.0, 6.0   # linear ramp up then down (rpm, rpm, s)
REVS = 8                         # [analysis] revs_per_block default
START = 1_763_800_000.0


def housing(f_m: np.ndarray, h: int, zeta: float) -> np.ndarray:
    """Complex housing acceleration of harmonic h, ``G (2 pi h f_m)^2 D_h`` (m/s^2)."""
    f = np.asarray(f_m, float)
    r = h * f / F_R
    d = D0[0] / ((1 - r * r) + 2j * zeta * r) if h == 1 else np.full(f.shape, D0[h - 1] + 0j)
    return GAIN * (2 * np.pi * h * f) ** 2 * d


def rpm_at(t: np.ndarray) -> np.ndarray:
    return N0 + (N1 - N0) * np.minimum(t, 2 * HALF_S - t) / HALF_S


def signal(zeta: float, noise: float, seed: int) -> tuple[np.ndarray, np.ndarray]:
    t = np.arange(int(2 * HALF_S * FS)) / FS
    rpm = rpm_at(t)
    theta = np.cumsum(rpm / 60.0) / FS
    f_m = Z1 * rpm / 60.0
    x = sum(np.real(housing(f_m, h, zeta) * np.exp(2j * np.pi * h * Z1 * theta))
            for h in (1, 2, 3))
    return t, x + np.random.default_rng(seed).normal(0.0, noise, t.size)


def exact_window_arms(t0: float, t1: float, zeta: float) -> float:
    """Root of the Hann-power (sin^4 in angle) weighted mean of sum_h |a_h|^2 over [t0, t1]."""
    tt = np.linspace(t0, t1, 8001)
    f = Z1 * rpm_at(tt) / 60.0
    theta = np.concatenate([[0.0], np.cumsum(0.5 * (f[1:] + f[:-1]) * np.diff(tt))])
    w = np.sin(np.pi * theta / theta[-1]) ** 4 * f     # per unit time: weight x dtheta/dt
    a2 = sum(np.abs(housing(f, h, zeta)) ** 2 for h in (1, 2, 3))
    return math.sqrt(np.trapezoid(w * a2, tt) / np.trapezoid(w, tt))


CAMPAIGN = """\
[campaign]
name = "ramp windows"
gear_set = "fzg-c"

[sensors]
accel = ["accel_1"]
speed = "PinionSpeed_rpm"

[analysis]
max_peaks = 1
prominence_dB = 60.0

[[run]]
id = "ramp"
gear_set = "kahraman-blankenship"   # z1 = 50
torque_Nm = 300.0
file = "ramp.mcap"
"""


@pytest.fixture(scope="module")
def ramp_table(tmp_path_factory) -> pd.DataFrame:
    """The project's path: MCAP, logged speed (100 Hz, 0.1 rpm noise), observe_campaign."""
    d = tmp_path_factory.mktemp("ramp_windows")
    t, x = signal(0.02, 0.002, seed=0)
    rng = np.random.default_rng(1)
    t_log = np.arange(0.0, t[-1], 0.01)
    logged = rpm_at(t_log) + rng.normal(0.0, 0.1, t_log.size)
    write_accel_mcap(d / "ramp.mcap", {"accel_1": (x, FS, "m/s^2", 0, START)},
                     {"PinionSpeed_rpm": (START + t_log, logged, "rpm")}, None)
    (d / "c.toml").write_text(CAMPAIGN)
    obs = observe_campaign(load_campaign(d / "c.toml"))
    assert all(r.analysed for r in obs.runs)
    return obs.table


def test_the_models_window_value_reads_back_the_analysed_windows(ramp_table):
    # harmonic 1's resonance (zeta 0.02, half-power width 36 Hz) lies inside windows spanning
    # 60 Hz of f_m near it; the slow windows span up to 25 % of f_m, where Arms grows as f_m^2
    (curve,) = prepare_runups(ramp_table, {"ramp": "kahraman-blankenship"},
                              RunUpSettings(max_speed_points=1000)).curves
    ok = np.isfinite(curve.observed[0])
    nodes = curve.nodes_Hz[ok]
    power = sum(np.abs(housing(nodes, h, 0.02)) ** 2 for h in (1, 2, 3))
    model = np.sqrt(power @ np.asarray(WINDOW_WEIGHTS))
    err = np.log(curve.observed[0][ok] / model)
    assert ok.sum() >= 40
    # measured on this fixture: median 0.011 %, largest 0.70 % (the peak window: three nodes
    # over a peak narrower than the window)
    assert np.median(np.abs(err)) < 5e-4
    assert np.max(np.abs(err)) < 0.01
    # Contrast, so the test can fail: nodes at equal fractions of the window's *duration*
    # (the rule before) leave the windows' value a median 0.56 % (up to 1.75 %) off.
    rows = ramp_table[(ramp_table.quantity == "arms") & (ramp_table.status != "failed")]
    rows = rows.sort_values("step_start_s")
    t0, t1 = rows.step_start_s.to_numpy(), rows.step_stop_s.to_numpy()
    mid = 0.5 * (t0 + t1)
    at = mid[:, None] + np.asarray(WINDOW_NODES)[None, :] * (t1 - t0)[:, None]
    by_time = np.interp(at, mid, rows.mesh_frequency_Hz.to_numpy())
    power_t = sum(np.abs(housing(by_time, h, 0.02)) ** 2 for h in (1, 2, 3))
    err_t = np.log(rows.arms_m_s2.to_numpy() / np.sqrt(power_t @ np.asarray(WINDOW_WEIGHTS)))
    assert np.median(np.abs(err_t)) > 3e-3


@pytest.mark.parametrize(("zeta", "tol_ramp", "short_by_3_bins"), [(0.01, 0.005, 0.03),
                                                                    (0.02, 0.001, 0.008)])
def test_the_ramp_readout_band_holds_the_modulation(zeta, tol_ramp, short_by_3_bins):
    # the exact speed, no noise: only the readout band differs between the two analyses
    _, x = signal(zeta, 0.0, seed=0)
    speed = speed_from_slow_signal(np.array([0.0, HALF_S, 2 * HALF_S]), np.array([N0, N1, N0]))
    exact = None
    errs = {}
    for band in (1, ramp_band_bins(REVS)):
        rc = run_up_curve(x, FS, speed, Z1, revs_per_window=REVS, band_bins=band)
        half = 0.5 * REVS * 60.0 / rc.speed_rpm
        if exact is None:
            exact = np.array([exact_window_arms(m - h, m + h, zeta)
                              for m, h in zip(rc.time_s, half, strict=True)])
        errs[band] = np.log(rc.arms / exact)
    wide = errs[ramp_band_bins(REVS)]
    # measured: the peak window 5.7 % / 1.4 % low over three bins (zeta 0.01 / 0.02), 0.14 % /
    # 0.00 % over seven; every other window within 0.02 % either way
    assert np.max(np.abs(wide)) < tol_ramp
    assert np.min(errs[1]) < -short_by_3_bins
    assert np.median(np.abs(wide)) < 2e-4


def test_the_ramp_band_keeps_the_first_shaft_sideband_outside():
    assert ramp_band_bins(8) == 3
    assert ramp_band_bins(3) == 2      # the sideband of shaft order 1 sits 3 bins off
    assert ramp_band_bins(1) == 1

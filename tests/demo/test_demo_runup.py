"""The demo's run-up run (issue 20 item 6): the time-integrated signal and its truth.

The run-up recording is made by integrating the SDOF model in time along the speed ramp
(:mod:`rigtools.demo.runup_signal`); the run-up calibration sweeps periodic steady states
(:func:`models.dynamics.sweep`). The checks:

* **kernel vs periodic sweep** (independent methods): on a short ramp through the resonance,
  the DTE amplitudes of mesh harmonics 1-3 read per window of 40 whole mesh cycles (Hann in
  the mesh phase, which the integration knows exactly) match the sweep along the same path in
  time order, away from the jumps, and the recorded acceleration is ``(2 pi h f_m)^2`` times
  the DTE harmonic (the contract's observation model, by another route);
* **limits**: no stiffness fluctuation (``eps = 0``), a small harmonic error and no contact
  loss give the linear FRF ``E_h / (1 - r^2 + 2 i zeta r)``; undamped free vibration through
  the dead zone keeps its energy;
* **the recording through the project's order analysis**: the MCAP file, read back with its
  100 Hz speed, gives per-window order amplitudes ``a_h = G (2 pi h f_m)^2 D_h`` of the sweep
  off the jumps;
* **the truth**: ``f_n`` from the contract's definition recomputed from ``models``, the ramp
  crosses both jumps with margin, quasi-static crossing, no plateau, no back-side impact;
* **the demo campaign** lists the run on its gear set with the ``[calibration]`` tables.
"""

from __future__ import annotations

import json
import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from models.dynamics import SDOFModel, sweep
from models.geometry import load_gear_set, mesh_frequency_Hz
from models.geometry.inertia import pair_equivalent_mass
from models.stiffness import Harmonics, mesh_cycle, pair_compliance
from rigtools.analysis.orders import run_up_curve_from_recording
from rigtools.analysis.speed import SpeedProfile, detect_speed_steps, speed_profile
from rigtools.calibration.campaign_inputs import campaign_config
from rigtools.campaign import load_campaign
from rigtools.demo.campaign import demo_run_count, generate_demo_campaign
from rigtools.demo.runup import (
    RUNUP_CALIBRATION,
    RUNUP_GEAR_SET,
    runup_model,
    runup_signals,
    runup_spec,
    runup_truth,
    speed_ramp,
    write_runup_recording,
)
from rigtools.demo.runup_signal import RunUpResponse, integrate_ramp, mesh_phase, runup_response
from rigtools.ingest import read

H = np.arange(1, 4)


def _window_harmonics(r: RunUpResponse, y: np.ndarray, cycles: int = 40
                      ) -> tuple[np.ndarray, np.ndarray]:
    """Mean f_m and |Y_h| (peak) per Hann window of ``cycles`` whole mesh cycles, no overlap."""
    phi = r.mesh_phase
    f, amps = [], []
    for p0 in np.arange(phi[0], phi[-1] - cycles, cycles):
        i0, i1 = np.searchsorted(phi, [p0, p0 + cycles])
        ph, yy = phi[i0:i1 + 1], y[i0:i1 + 1]
        w = 1.0 - np.cos(2 * np.pi * (ph - p0) / cycles)
        amps.append([abs(2 * np.trapezoid(w * yy * np.exp(-2j * np.pi * h * ph), ph)
                         / np.trapezoid(w, ph)) for h in H])
        f.append(float(np.mean(r.mesh_frequency_Hz[i0:i1 + 1])))
    return np.array(f), np.array(amps)


def _arms_form(f: np.ndarray, dte: np.ndarray) -> np.ndarray:
    """Housing Arms per unit gain: ``(2 pi f)^2 sqrt(sum h^4 D_h^2)``."""
    return (2 * np.pi * f) ** 2 * np.sqrt((H ** 4 * dte ** 2).sum(axis=1))


def _off_jumps(f: np.ndarray, arms: np.ndarray, rel: float = 0.03,
               step: float = 0.15) -> np.ndarray:
    """Points farther than ``rel`` (relative f) from every jump (|d log Arms| > ``step``)."""
    d = np.abs(np.diff(np.log(arms)))
    jumps = np.concatenate([f[:-1][d > step], f[1:][d > step]])
    keep = np.ones(f.size, dtype=bool)
    for fj in jumps:
        keep &= np.abs(f / fj - 1) > rel
    return keep


@pytest.fixture(scope="module")
def short() -> dict:
    """A short ramp through the resonance (2500 -> 4000 -> 2500 rpm, 2 x 1.5 s) and its sweep."""
    spec = replace(runup_spec("ci"), speed_low_rpm=2500.0, speed_high_rpm=4000.0,
                   ramp_duration_s=1.5)
    rm = runup_model(spec)
    t_k, n_k = speed_ramp(spec)
    r = runup_response(rm.model, rm.omega_n_rad_s, t_k, mesh_frequency_Hz(n_k, rm.z1),
                       sample_rate_Hz=102_400.0)
    f, dte = _window_harmonics(r, r.dte_m)
    _, acc = _window_harmonics(r, r.dte_acceleration_m_s2)
    ref = sweep(rm.model, 2 * np.pi * f / rm.omega_n_rad_s)
    return {"spec": spec, "rm": rm, "r": r, "f": f, "dte": dte, "acc": acc,
            "ref": ref.amplitudes * ref.length_scale_m, "loss": ref.contact_loss}


def test_kernel_matches_the_periodic_sweep_along_the_same_path(short) -> None:
    f, dte, ref = short["f"], short["dte"], short["ref"]
    arms, arms_ref = _arms_form(f, dte), _arms_form(f, ref)
    assert short["loss"].any(), "the short ramp must reach contact loss (the nonlinear range)"
    keep = _off_jumps(f, arms_ref)
    assert keep.sum() > 0.6 * f.size
    err = np.abs(arms / arms_ref - 1)[keep]
    err1 = np.abs(dte[:, 0] / ref[:, 0] - 1)[keep]
    assert err.max() < 0.03, f"Arms off the jumps: worst {100 * err.max():.2f} % at " \
                             f"{f[keep][np.argmax(err)]:.0f} Hz"
    assert np.median(err) < 0.003 and np.median(err1) < 0.003
    # softening: a jump up on the way up, a jump down on the way down, lower
    d = np.diff(np.log(arms_ref))
    n = f.size // 2
    assert d[:n].max() > 0.15 and d[n:].min() < -0.15
    assert f[n + np.argmin(d[n:])] < f[np.argmax(d[:n])]


def test_recorded_acceleration_is_the_dte_acceleration(short) -> None:
    f, dte, acc = short["f"], short["dte"], short["acc"]
    keep = _off_jumps(f, _arms_form(f, short["ref"]))
    expected = (2 * np.pi * H[None, :] * f[:, None]) ** 2 * dte
    # each harmonic against the Arms it enters (h3 is 0.2-0.6 % of h1 in DTE: its own
    # relative error is leakage-bound), and the first harmonic on its own
    err = np.abs(acc - expected) / np.sqrt((expected ** 2).sum(axis=1))[:, None]
    assert err[keep].max() < 2e-3, err[keep].max()
    assert np.abs(acc[:, 0] / expected[:, 0] - 1)[keep].max() < 5e-3


def test_no_fluctuation_no_contact_loss_is_the_linear_frf() -> None:
    zeta, f_n = 0.03, 3000.0
    wn = 2 * np.pi * f_n
    e = np.array([0.02, 0.01, 0.005])            # error harmonics (units of L)
    model = SDOFModel(zeta=zeta, force=1.0, backlash=1.0,
                      stiffness=Harmonics(1.0, np.zeros(0), np.zeros(0)),   # eps = 0
                      error=Harmonics(0.0, e, np.array([0.3, -1.0, 2.0])),
                      length_scale_m=1e-5, kind="custom")
    # 2 -> 4 kHz in 1.5 s: harmonics 2 and 3 stay clear of their resonances (1.5, 1 kHz)
    r = runup_response(model, wn, [0.0, 1.5], [2000.0, 4000.0], sample_rate_Hz=102_400.0)
    u = r.dte_m / 1e-5 - 1.0
    assert not r.contact_loss.any() and u.min() > 0.3   # never near the gap: linear
    f, dte = _window_harmonics(r, r.dte_m)
    f, dte = f[1:], dte[1:]      # the first window holds the start transient
    ratio = H[None, :] * 2 * np.pi * f[:, None] / wn
    frf = 1e-5 * e[None, :] / np.abs(1 - ratio ** 2 + 2j * zeta * ratio)
    rel = np.abs(dte / frf - 1)
    band = np.abs(f / f_n - 1) < 2 * zeta    # the half-power band of the first harmonic
    assert band.sum() >= 5
    assert rel[~band].max() < 5e-3, rel[~band].max()
    # in the band the ramp (1333 Hz/s, sweep-rate parameter df/dt / (zeta f_n)^2 = 0.16) lags
    # the stationary peak: 1.7 % at most, half that at half the rate
    assert rel[band].max() < 0.025, rel[band].max()


def test_undamped_free_vibration_through_the_dead_zone_keeps_its_energy() -> None:
    wn, b, force = 2 * np.pi * 2000.0, 1.0, 0.5
    kd = np.ones((64, 1))
    zero = np.zeros((64, 1))
    n, fs = 2000, 200_000.0           # 100 samples per natural period, 8 RK4 steps each
    t_k, f_k = np.array([0.0, 1.0]), np.array([1000.0, 1000.0])

    def energy(x: float, v: float) -> float:
        """Non-dimensional: x'^2 / 2 + V(x) - F x with x' = v / omega_n."""
        return 0.5 * (v / wn) ** 2 + 0.5 * max(abs(x) - b, 0.0) ** 2 - force * x

    x, v = b + force + 2.5, 0.0       # released 2.5 above the static state: through the gap
    e0 = energy(x, v)
    seen_loss = seen_impact = False
    for chunk in range(10):
        xs, a, phi = np.empty(n), np.empty(n), np.empty(n)
        loss, impact = np.zeros(n, dtype=bool), np.zeros(n, dtype=bool)
        x, v = integrate_ramp(x, v, 0.0, force, b, wn, kd, zero, kd, zero, t_k, f_k,
                              mesh_phase(t_k, f_k), chunk * n / fs, 1 / fs, 8, xs, a, phi,
                              loss, impact)
        seen_loss |= bool(loss.any())
        seen_impact |= bool(impact.any())
        # RK4 is not symplectic and the dead zone's kinks cost it order h^2 per crossing:
        # a slow drift, 3e-6 per 20 periods here (a wrong force would be off by O(1))
        assert energy(x, v) == pytest.approx(e0, rel=1e-4), chunk
        assert np.allclose(phi, 1000.0 * (chunk * n + np.arange(n)) / fs)
    assert seen_loss and seen_impact, "the free vibration must cross the whole gap"


def test_bad_ramps_are_refused() -> None:
    model = SDOFModel(zeta=0.02, force=1.0, backlash=1.0)
    with pytest.raises(ValueError, match="`knot_time_s` must be finite and increasing"):
        runup_response(model, 1e4, [0.0, 0.0], [100.0, 200.0], sample_rate_Hz=1e4)
    with pytest.raises(ValueError, match="`knot_mesh_frequency_Hz` must be finite and > 0"):
        runup_response(model, 1e4, [0.0, 1.0], [100.0, 0.0], sample_rate_Hz=1e4)
    with pytest.raises(ValueError, match="`sample_rate_Hz` must be > 0"):
        runup_response(model, 1e4, [0.0, 1.0], [100.0, 200.0], sample_rate_Hz=0.0)
    with pytest.raises(ValueError, match="not quasi-static"):
        runup_truth(replace(runup_spec("ci"), ramp_duration_s=0.5))


# -- the truth -------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def truth_ci():
    spec = runup_spec("ci")
    rm = runup_model(spec)
    return spec, rm, runup_truth(spec, rm)


def test_natural_frequency_is_the_contracts_definition(truth_ci) -> None:
    spec, _rm, truth = truth_ci
    pair = load_gear_set(RUNUP_GEAR_SET).pair
    cyc = mesh_cycle(pair, lambda s: pair_compliance(pair, s).total_m_per_N, spec.torque_Nm)
    k_f0 = float(np.mean(cyc.fvms_N_m))
    m_e = pair_equivalent_mass(pair)
    f_n = math.sqrt(spec.stiffness_scale * k_f0 / m_e) / (2 * math.pi)
    assert truth.mesh_natural_frequency_Hz == pytest.approx(f_n, rel=1e-3)
    assert truth.equivalent_mass_kg == pytest.approx(m_e)
    # Kahraman-Blankenship, z1 = 50: the VVMS resonance at 3700-3900 rpm (PLAN section 4)
    rpm = 60 * truth.model_natural_frequency_Hz / truth.pinion_teeth
    assert 3600 < rpm < 3900, rpm


def test_the_ramp_crosses_both_jumps_with_margin_and_slowly(truth_ci) -> None:
    spec, rm, truth = truth_ci
    lo, hi = (float(mesh_frequency_Hz(v, rm.z1)) for v in (spec.speed_low_rpm,
                                                           spec.speed_high_rpm))
    assert truth.jump_frequency_down_Hz < truth.jump_frequency_up_Hz  # softening hysteresis
    assert lo < 0.5 * truth.jump_frequency_down_Hz
    assert hi > 1.25 * max(truth.jump_frequency_up_Hz, truth.model_natural_frequency_Hz)
    assert truth.crossing_ratio > 100     # crossing the half-power band / 1 / (zeta omega_n)
    assert truth.contact_loss and not truth.backside_impact
    block = truth.summary()
    assert block["backlash_identifiable"] is False
    assert set(block["parameters"]) == {"zeta", "mesh_stiffness_scale", "fluctuation_scale",
                                        "backlash", "gain@accel_x", "gain@accel_y",
                                        "gain@accel_z"}
    assert block["parameters"]["backlash"] == {"value": pytest.approx(136.0), "unit": "um"}
    assert block["derived"]["mesh_natural_frequency_Hz"]["value"] == pytest.approx(
        truth.mesh_natural_frequency_Hz)


@pytest.mark.parametrize("size", ["ci", "full"])
def test_no_plateau_at_either_size(size: str) -> None:
    spec = runup_spec(size)   # type: ignore[arg-type]
    t = np.arange(0.0, spec.duration_s, 1 / spec.speed_rate_Hz)
    rpm = np.interp(t, *speed_ramp(spec)) + np.random.default_rng(0).normal(0, 0.3, t.size)
    prof = SpeedProfile(time_s=t, speed_rpm=rpm, segment=np.zeros(t.size, dtype=int),
                        cover_start_s=t[:1], cover_stop_s=t[-1:], source="test")
    assert detect_speed_steps(prof) == ()


# -- the recording, through the project's order analysis -------------------------------------


@pytest.fixture(scope="module")
def recording(tmp_path_factory: pytest.TempPathFactory, truth_ci):
    spec, rm, truth = truth_ci
    sig = runup_signals(spec, rm, start_time_s=1_763_800_000.0, lsb_m_s2=1e-5, rng=1)
    path = write_runup_recording(tmp_path_factory.mktemp("runup") / "ru.mcap", spec, sig)
    return spec, rm, truth, sig, read(path)


def test_recording_has_the_rates_and_the_ramp(recording) -> None:
    spec, _rm, _truth, sig, rec = recording
    for c in spec.channels:
        assert rec.channels[c].sample_rate_Hz == spec.sample_rate_Hz
        assert len(rec.channels[c]) == sig.response.time_s.size
    speed = rec.slow["PinionSpeed_rpm"]
    assert np.median(np.diff(speed.time_s)) == pytest.approx(1 / spec.speed_rate_Hz, rel=1e-4)
    assert speed.values.max() == pytest.approx(spec.speed_high_rpm, abs=2.0)
    assert speed.values.min() == pytest.approx(spec.speed_low_rpm, abs=2.0)


def test_order_analysis_of_the_recording_follows_the_observation_model(recording) -> None:
    spec, rm, truth, _sig, rec = recording
    curve = run_up_curve_from_recording(rec, "accel_x", speed_profile(rec, "PinionSpeed_rpm"),
                                        rm.z1, revs_per_window=4)
    f, a = curve.mesh_frequency_Hz, curve.amplitude
    assert np.isfinite(a).all()          # 51.2 kHz: the third harmonic inside the passband
    ref = sweep(rm.model, 2 * np.pi * f / rm.omega_n_rad_s)   # the windows in time order
    d_ref = ref.amplitudes * ref.length_scale_m
    g = spec.gains[0]
    model = g * _arms_form(f, d_ref)
    rel = np.abs(np.sqrt((a ** 2).sum(axis=1)) / model - 1)
    rel1 = np.abs(a[:, 0] / (g * (2 * np.pi * f) ** 2 * d_ref[:, 0]) - 1)
    assert np.median(rel) < 0.01, np.median(rel)
    # Off the jumps, and above the superharmonic resonances (f_n / 2, f_n / 3) where the
    # linear ramp's windows at low speed span 10-30 % of f_m:
    keep = f > 0.55 * truth.model_natural_frequency_Hz
    for fj in (truth.jump_frequency_up_Hz, truth.jump_frequency_down_Hz):
        keep &= np.abs(f / fj - 1) > 0.04
    assert keep.sum() > 0.6 * f.size
    assert rel[keep].max() < 0.03, f"worst {100 * rel[keep].max():.1f} % at " \
                                   f"{f[keep][np.argmax(rel[keep])]:.0f} Hz"
    assert np.median(rel[keep]) < 0.005 and rel1[keep].max() < 0.03


# -- the demo campaign -------------------------------------------------------------------------


def test_demo_campaign_lists_the_runup_on_its_gear_set(tmp_path: Path) -> None:
    demo = generate_demo_campaign(tmp_path, seed=1, size="ci", duration_s=0.25)
    assert demo.runup is not None and demo.runup.file.is_file()
    assert demo_run_count("ci") == len(demo.runs) + 1
    camp = load_campaign(demo.campaign_path)
    spec = runup_spec("ci")
    assert camp.gear_for(spec.run_id).name == RUNUP_GEAR_SET
    assert camp.gear_set == "fzg-c"
    assert [r.id for r in camp.runs][-1] == spec.run_id
    cfg = campaign_config(camp)
    assert tuple(cfg.models) == ("fvms", "vvms", "lste")
    ru = cfg.runup
    for key, value in RUNUP_CALIBRATION["ci"].items():
        assert getattr(ru, key) == value, key
    truth = json.loads(demo.truth_path.read_text(encoding="utf-8"))
    block = truth["runup"]
    assert block["run_id"] == spec.run_id and block["model"] == "vvms"
    assert block["file"] == demo.runup.file.relative_to(tmp_path).as_posix()
    assert block["parameters"]["zeta"]["value"] == 0.025
    assert spec.run_id not in truth["runs"]   # the FZG-C truth keeps its runs

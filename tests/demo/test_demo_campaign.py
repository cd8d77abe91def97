"""The built-in demo campaign (issue 19 item 7): files, truth, and the modes in the recordings.

The CI size is generated once per module (a few seconds). Checks:

* the files load as a campaign (:func:`rigtools.campaign.load_campaign`) and every run ingests
  with the campaign's DBC and mapping: half MCAP, half CAN of the triaxial layout, the dropped
  frames found as gaps where they were made;
* the truth is consistent with :mod:`models.thermal` (``critical_gap``, the regime flip across
  the temperatures, no jammed run) and uses the calibration summary's names;
* the mesh mode and the housing mode are where the truth says, checked independently with
  :func:`scipy.signal.welch` against the PSD the truth predicts (accelerance with its
  mass-line floor, white noise), not with rigtools' own peak analysis;
* the same seed gives the same files.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
from scipy.signal import welch

from models.thermal import SEED_000_CHI, critical_gap
from rigtools.campaign import load_campaign, read_run
from rigtools.demo.campaign import (
    DEFAULT_DURATION_S,
    MCAP_LSB_M_S2,
    demo_conditions,
    generate_demo_campaign,
)
from rigtools.demo.triax_can import ACCEL_CHANNELS, ACCEL_LSB_M_S2

FS = 25_600.0
NPERSEG = 4096


@pytest.fixture(scope="module")
def demo(tmp_path_factory: pytest.TempPathFactory):
    return generate_demo_campaign(tmp_path_factory.mktemp("demo-ci"), seed=0, size="ci")


@pytest.fixture(scope="module")
def truth_json(demo) -> dict:
    return json.loads(demo.truth_path.read_text(encoding="utf-8"))


@pytest.fixture(scope="module")
def recordings(demo) -> dict:
    camp = load_campaign(demo.campaign_path)
    return {r.id: read_run(camp, r) for r in camp.runs}


# -- files and campaign ------------------------------------------------------------------------


def test_campaign_file_lists_every_run_with_its_conditions(demo) -> None:
    camp = load_campaign(demo.campaign_path)
    assert camp.gear_set == "fzg-c"
    assert camp.sensors.dbc is None and camp.sensors.mapping is None
    assert camp.sensors.accel == ACCEL_CHANNELS
    assert camp.thermal.reference_temperature_C == demo.truth.physics.reference_temperature_C
    assert [r.id for r in camp.runs] == [c.run_id for c in demo_conditions("ci")] + [
        demo.runup.run_id]
    for run in camp.runs:
        if run.id == demo.runup.run_id:     # the run-up: its truth is truth.json["runup"]
            continue
        t = demo.truth.run(run.id)
        assert run.file.is_file(), run.file
        assert run.file.resolve() == demo.run_files[run.id].resolve()
        assert (run.torque_Nm, run.bulk_temperature_C, run.speed_rpm) == (
            t.torque_Nm, t.bulk_temperature_C, t.speed_rpm)
        assert run.oil_temperature_C == pytest.approx(t.oil_temperature_C, abs=0.005)
        # two loggers in one campaign: the CAN runs name their own layout, MCAP runs none
        sensors = camp.sensors_for(run)
        fmt = {r.run_id: r.format for r in demo.runs}[run.id]
        if fmt == "mcap":
            assert sensors.dbc is None and sensors.mapping is None, run.id
        else:
            assert (sensors.dbc, sensors.mapping) == (demo.dbc_path, demo.mapping_path), run.id
            assert sensors.format == fmt, run.id


def test_half_the_runs_are_mcap_half_can_of_another_layout(demo) -> None:
    formats = [r.format for r in demo.runs]
    assert formats.count("mcap") == len(formats) // 2
    assert {"blf", "candump"} <= set(formats)
    dbc = demo.dbc_path.read_text(encoding="utf-8")
    assert "RigSampleRate" not in dbc and "BO_ 256 " not in dbc  # not the reference layout
    for r in demo.runs:
        assert r.file.suffix == {"mcap": ".mcap", "blf": ".blf", "candump": ".log"}[r.format]


def test_every_run_ingests_with_the_campaigns_dbc_and_mapping(demo, recordings) -> None:
    n = round(DEFAULT_DURATION_S["ci"] * FS)
    for r in demo.runs:
        rec = recordings[r.run_id]
        assert set(rec.channels) == set(ACCEL_CHANNELS), r.run_id
        assert {"PinionSpeed_rpm", "Torque_Nm", "BulkTemp_C", "OilTemp_C"} <= set(rec.slow)
        assert not rec.report.rejected, (r.run_id, rec.report.rejected)
        lost = sum(k for _s, k in r.dropped_frames)
        for name in ACCEL_CHANNELS:
            ch = rec.channels[name]
            assert ch.sample_rate_Hz == FS
            assert ch.first_index == 0 and len(ch) == n, (r.run_id, name, len(ch))
            assert int((~ch.valid).sum()) == lost, (r.run_id, name)
            gaps = sorted((g.start_index, g.n_missing) for g in rec.report.gaps
                          if g.channel == name)
            assert gaps == sorted(r.dropped_frames), (r.run_id, name, gaps)
            lsb = MCAP_LSB_M_S2 if r.format == "mcap" else ACCEL_LSB_M_S2
            v = ch.values[ch.valid]
            steps = v / lsb
            tol = 1e-6 if r.format != "mcap" else 2e-7 * float(np.max(np.abs(v))) / lsb + 1e-6
            assert np.max(np.abs(steps - np.round(steps))) <= tol, (r.run_id, name)
        t = demo.truth.run(r.run_id)
        assert np.mean(rec.slow["Torque_Nm"].values) == pytest.approx(t.torque_Nm, rel=2e-3)
        assert np.mean(rec.slow["BulkTemp_C"].values) == pytest.approx(t.bulk_temperature_C,
                                                                       abs=0.05)
        assert np.mean(rec.slow["PinionSpeed_rpm"].values) == pytest.approx(1500.0, abs=0.5)
    assert any(r.dropped_frames for r in demo.runs), "some CAN runs must have dropped frames"


# -- the truth ---------------------------------------------------------------------------------


def test_truth_crosses_the_regime_flip(demo) -> None:
    truth = demo.truth
    p = truth.physics
    temps = truth.temperatures_C
    assert len(temps) >= 3
    for r in truth.runs:
        d = p.closure_slope_m_per_K * (r.bulk_temperature_C - p.reference_temperature_C)
        c_star = float(critical_gap(d, SEED_000_CHI))
        assert r.critical_gap_m == pytest.approx(c_star, rel=1e-12)
        assert r.margin_m == pytest.approx(p.backlash_m - c_star, rel=1e-12)
        assert r.regime == ("rises" if p.backlash_m > c_star else "falls"), r.run_id
        assert abs(r.margin_m) >= 2e-6, "margins well outside the 1 um 'unchanged' band"
        assert not r.mesh.jammed and r.mesh.min_net_deflection_m > 0
    by_t = {t: {r.regime for r in truth.runs if r.bulk_temperature_C == t} for t in temps}
    assert by_t[temps[0]] == {"rises"} and by_t[temps[-1]] == {"falls"}
    assert temps[0] < p.flip_temperature_C < temps[-1]
    assert p.critical_gap_m(p.flip_temperature_C) == pytest.approx(p.backlash_m, rel=1e-12)
    # physically plausible: seed 000's c* of about 10 um at 90 degC (its hot state)
    assert p.critical_gap_m(90.0) * 1e6 == pytest.approx(10.27, abs=0.05)


def test_truth_json_uses_the_calibration_summary_names(demo, truth_json) -> None:
    p = demo.truth.physics
    assert truth_json["parameters"]["backlash"] == {"value": pytest.approx(p.backlash_m * 1e6),
                                                    "unit": "um"}
    derived = truth_json["derived"]
    for t in demo.truth.temperatures_C:
        assert derived[f"critical_gap@{t:g}C"]["value"] == pytest.approx(
            p.critical_gap_m(t) * 1e6)
    for r in demo.truth.runs:
        assert derived[f"margin@{r.run_id}"]["value"] == pytest.approx(r.margin_m * 1e6)
        row = truth_json["runs"][r.run_id]
        assert row["regime"] in ("rises", "falls", "unchanged")
        assert row["mesh_mode_Hz"] == pytest.approx(r.mesh.f_n_Hz)
    assert derived["flip_temperature_C"]["unit"] == "degC"
    assert truth_json["conventions"]["equivalent_mass_kg"] == pytest.approx(p.equivalent_mass_kg)
    assert truth_json["housing_mode"]["f_n_Hz"] == demo.truth.housing.f_n_Hz


def test_mesh_modes_lie_where_a_25k6_accelerometer_resolves_them(demo) -> None:
    f_mesh, f_p, f_w = 400.0, 25.0, 400.0 / 24
    lines = [k * f_mesh + j * fs for k in range(1, 6) for j in range(-3, 4) for fs in (f_p, f_w)]
    lines += [k * fs for k in range(1, 11) for fs in (f_p, f_w)]
    for r in demo.truth.runs:
        f = r.mesh.f_n_Hz
        assert 1300.0 < f < 0.4 * FS, (r.run_id, f)
        assert min(abs(f - x) for x in lines) > 50.0, (r.run_id, f)


def test_housing_mode_is_taller_at_some_runs_and_close_at_some(demo, truth_json) -> None:
    runs = truth_json["runs"]
    taller_everywhere = [k for k, v in runs.items() if len(v["housing_taller_on"]) == 3]
    assert taller_everywhere, "the housing mode must be the tallest peak at some runs"
    assert any(not v["housing_taller_on"] or "accel_x" not in v["housing_taller_on"]
               for v in runs.values()), "and not at all of them"
    close = [k for k, v in runs.items() if abs(v["mesh_housing_separation_Hz"]) < 400.0]
    assert close, "the housing mode must come within a few hundred Hz of the mesh mode"
    assert any(runs[k]["housing_taller_on"] for k in close)


# -- the modes in the recordings (independent of rigtools.analysis) ----------------------------


def _welch_valid(x: np.ndarray, valid: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Welch PSD over the valid stretches, weighted by their number of windows."""
    edges = np.flatnonzero(np.diff(np.r_[0, valid.astype(np.int8), 0]))
    total, weight = None, 0
    for a, b in zip(edges[::2], edges[1::2], strict=True):
        if b - a < NPERSEG:
            continue
        f, p = welch(x[a:b], FS, nperseg=NPERSEG)
        k = (b - a - NPERSEG) // (NPERSEG // 2) + 1
        total = p * k if total is None else total + p * k
        weight += k
    assert total is not None
    return f, total / weight


def _shape(f: np.ndarray, f_n: float, zeta: float) -> np.ndarray:
    """|A(f)|^2 of a single-DOF accelerance normalised to 1 at its peak (typed again here)."""
    r = f / f_n
    a2 = r**4 / ((1 - r**2) ** 2 + (2 * zeta * r) ** 2)
    return a2 * (4 * zeta**2 * (1 - zeta**2))


def test_modes_are_where_the_truth_says_in_each_runs_psd(demo, truth_json, recordings) -> None:
    housing = truth_json["housing_mode"]
    for r in demo.truth.runs:
        row = truth_json["runs"][r.run_id]
        rec = recordings[r.run_id]
        for c in ACCEL_CHANNELS:
            ch = rec.channels[c]
            f, p = _welch_valid(ch.values, ch.valid)
            expected = (row["mesh_peak_psd"][c] * _shape(f, r.mesh.f_n_Hz, r.mesh_zeta)
                        + row["housing_peak_psd"][c] * _shape(f, housing["f_n_Hz"],
                                                              housing["zeta"])
                        + 2 * row["noise_sigma_m_s2"][c] ** 2 / FS)
            band = (f > 1400.0) & (f < 11000.0)  # above the mesh harmonics and sidebands
            ratio_dB = 10 * np.log10(p[band] / expected[band])
            assert abs(np.median(ratio_dB)) < 0.5, (r.run_id, c, np.median(ratio_dB))
            for name, f_n, zeta in (("mesh", r.mesh.f_n_Hz, r.mesh_zeta),
                                    ("housing", housing["f_n_Hz"], housing["zeta"])):
                peak = f_n / math.sqrt(1 - 2 * zeta**2)
                near = np.abs(f - peak) <= max(zeta * f_n / 3, 2 * FS / NPERSEG)
                level = 10 * np.log10(np.mean(p[near]) / np.mean(expected[near]))
                assert abs(level) < 1.5, (r.run_id, c, name, level)
        # where each mode dominates its channel, the PSD peaks at the truth's frequency
        for name, f_n, zeta, other in (
                ("mesh", r.mesh.f_n_Hz, r.mesh_zeta, housing["f_n_Hz"]),
                ("housing", housing["f_n_Hz"], housing["zeta"], r.mesh.f_n_Hz)):
            key = f"{name}_peak_psd"
            other_key = "housing_peak_psd" if name == "mesh" else "mesh_peak_psd"
            c = max(ACCEL_CHANNELS, key=lambda k: row[key][k] / row[other_key][k])
            ch = rec.channels[c]
            f, p = _welch_valid(ch.values, ch.valid)
            half = zeta * f_n
            inside = np.abs(f - f_n) <= half
            f_peak = f[inside][np.argmax(p[inside])]
            assert abs(f_peak - f_n) <= 0.5 * half + FS / NPERSEG, (r.run_id, name, f_peak)
            away = f_n + 3 * half * (1 if other < f_n else -1)  # the flank away from the other
            skirt = p[np.argmin(np.abs(f - away))]
            assert 10 * np.log10(p.max(where=inside, initial=0) / skirt) > 6.0, (r.run_id, name)


# -- reproducible ------------------------------------------------------------------------------


def _contents(folder: Path) -> dict[str, bytes]:
    return {p.relative_to(folder).as_posix(): p.read_bytes()
            for p in sorted(folder.rglob("*")) if p.is_file()}


def test_same_seed_same_files_other_seed_other_recordings(tmp_path: Path) -> None:
    a = generate_demo_campaign(tmp_path / "a", seed=3, size="ci", duration_s=0.25)
    b = generate_demo_campaign(tmp_path / "b", seed=3, size="ci", duration_s=0.25)
    c = generate_demo_campaign(tmp_path / "c", seed=4, size="ci", duration_s=0.25)
    ca, cb, cc = (_contents(x.campaign_path.parent) for x in (a, b, c))
    assert ca == cb
    runs = [k for k in ca if k.startswith("runs/")]
    assert len(runs) == len(a.runs) + 1    # and the run-up
    assert all(ca[k] != cc[k] for k in runs)
    ta, tc = (json.loads(x.truth_path.read_text(encoding="utf-8")) for x in (a, c))
    assert ta["parameters"] == tc["parameters"] and ta["derived"] == tc["derived"]


def test_bad_arguments_are_refused(tmp_path: Path) -> None:
    with pytest.raises(ValueError, match="`size` must be one of"):
        generate_demo_campaign(tmp_path, size="huge")  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="`seed` must be an integer >= 0"):
        generate_demo_campaign(tmp_path, seed=-1)
    with pytest.raises(ValueError, match="`duration_s` must be > 0"):
        generate_demo_campaign(tmp_path, duration_s=0.0)

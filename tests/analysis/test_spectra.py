"""Spectra, RMS, gap-aware segmenting and quality checks (rigtools.analysis.spectra, .windows).

Tiers (STYLE.md 13): analytic limits (a sine's PSD peak integrates to A^2/2, its RMS is
A/sqrt(2), its amplitude reads A to the window's scalloping loss), identities with hypothesis
(Parseval), and hand-built cases for gaps, counts and errors. References: Harris (1978) for
window figures, Percival and Walden (1993) Eq. (292b) for the degrees of freedom.
"""

from __future__ import annotations

import pickle

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy import signal as sps

from rigtools.analysis import (
    amplitude_spectrum,
    band_rms,
    detect_clipping,
    log_chi2_stats,
    n_windows,
    rms_from_psd,
    valid_segments,
    welch_psd,
    window_properties,
)
from rigtools.errors import ConstantSignalError, InsufficientDataError, SignalError

FS = 25_600.0
DBC_FULL_SCALE = (-491.52, 491.505)  # int16 x 0.015 m/s^2, data_schemas/rig_reference.dbc
DBC_LSB = 0.015


def _sine(A: float, f: float, n: int, fs: float = FS, phase: float = 0.3) -> np.ndarray:
    return A * np.sin(2 * np.pi * f * np.arange(n) / fs + phase)


# --------------------------------------------------------------------------------------------
# Welch PSD: agreement with scipy, dtypes, shapes


def test_whole_signal_is_scipy_welch_exactly():
    x = np.random.default_rng(1).normal(size=(3, 50_000))
    s = welch_psd(x, 1000.0, nperseg=1024, unit="m/s^2")
    f, p = sps.welch(x, 1000.0, nperseg=1024)
    np.testing.assert_array_equal(s.freq_Hz, f)
    np.testing.assert_array_equal(s.psd_per_Hz, p)
    assert s.psd_unit == "(m/s^2)^2/Hz"
    assert s.n_windows.tolist() == [(50_000 - 512) // 512] * 3
    assert s.resolution_Hz == pytest.approx(1000.0 / 1024)


def test_float32_and_float64_agree():
    x = np.random.default_rng(2).normal(size=(2, 40_000))
    s64 = welch_psd(x, FS, nperseg=2048)
    s32 = welch_psd(x.astype(np.float32), FS, nperseg=2048)
    assert s32.psd_per_Hz.dtype == np.float64
    np.testing.assert_allclose(s32.psd_per_Hz, s64.psd_per_Hz, rtol=1e-4,
                               atol=1e-6 * s64.psd_per_Hz.max())
    r32 = band_rms(x.astype(np.float32), FS, (100.0, 5000.0), nperseg=2048)
    r64 = band_rms(x, FS, (100.0, 5000.0), nperseg=2048)
    np.testing.assert_allclose(r32.rms_time, r64.rms_time, rtol=1e-5)
    np.testing.assert_allclose(r32.rms_parseval, r64.rms_parseval, rtol=1e-5)


def test_axis_argument_follows_scipy():
    x = np.random.default_rng(3).normal(size=(20_000, 2))
    s = welch_psd(x, 1000.0, nperseg=512, axis=0)
    _, p = sps.welch(x, 1000.0, nperseg=512, axis=0)
    assert s.psd_per_Hz.shape == p.shape == (257, 2)
    np.testing.assert_allclose(s.psd_per_Hz, p, rtol=1e-12)


def test_resolution_request_sets_nperseg():
    x = np.random.default_rng(4).normal(size=100_000)
    s = welch_psd(x, FS, resolution_Hz=6.25)
    assert s.nperseg == 4096 and s.resolution_Hz == 6.25


def test_median_average_is_unbiased_for_gaussian_noise():
    x = np.random.default_rng(5).normal(0.0, 2.0, size=400_000)
    s = welch_psd(x, FS, nperseg=1024, average="median")
    level = 2.0**2 / (FS / 2)
    assert np.median(s.psd_per_Hz[5:-5]) / level == pytest.approx(1.0, abs=0.03)


# --------------------------------------------------------------------------------------------
# analytic limits: sines


@pytest.mark.parametrize("window", ["hann", "flattop"])
@pytest.mark.parametrize("offset_bins", [0.0, 0.25, 0.5])
def test_sine_psd_peak_integrates_to_A2_over_2(window, offset_bins):
    A, nperseg = 3.0, 4096
    f0 = (500 + offset_bins) * FS / nperseg
    s = welch_psd(_sine(A, f0, 400_000), FS, nperseg=nperseg, window=window)
    half = (window_properties(window, nperseg).mainlobe_half_width_bins + 4) * s.resolution_Hz
    power = float(rms_from_psd(s, (f0 - half, f0 + half))) ** 2
    assert power == pytest.approx(A**2 / 2, rel=2e-3), "sine: PSD peak integrates to A^2/2"


def test_sine_rms_is_A_over_sqrt2_both_ways():
    A = 2.5
    r = band_rms(_sine(A, 1234.5, 256_000), FS, nperseg=4096)
    assert r.rms_time == pytest.approx(A / np.sqrt(2), rel=1e-4)
    assert r.rms_parseval == pytest.approx(A / np.sqrt(2), rel=1e-3)
    band = band_rms(_sine(A, 1234.5, 256_000), FS, (1000.0, 1500.0), nperseg=4096)
    assert band.rms_time == pytest.approx(A / np.sqrt(2), rel=1e-3)
    assert band.rms_parseval == pytest.approx(A / np.sqrt(2), rel=1e-3)


@pytest.mark.parametrize(("window", "tolerance"), [("flattop", 0.0012), ("hann", 0.152)])
@pytest.mark.parametrize("offset_bins", [0.0, 0.1, 0.25, 0.4, 0.5])
def test_amplitude_spectrum_reads_A_within_scalloping_tolerance(window, tolerance,
                                                               offset_bins):
    """On-bin A; off-bin A within the scalloping loss (flattop 0.11 %, Hann 15.1 %)."""
    A, nperseg = 4.0, 4096
    f0 = (300 + offset_bins) * FS / nperseg
    a = amplitude_spectrum(_sine(A, f0, 200_000), FS, nperseg=nperseg, window=window)
    assert a.scalloping_tolerance <= tolerance
    reading = float(a.amplitude.max())
    assert abs(reading / A - 1) <= a.scalloping_tolerance + 1e-9
    if offset_bins == 0.0:
        assert reading == pytest.approx(A, rel=1e-9)


def test_window_figures_are_harris_values():
    hann = window_properties("hann", 4096)
    assert hann.enbw_bins == pytest.approx(1.5, rel=1e-6)
    assert hann.scalloping_loss == pytest.approx(1 - 0.8488, abs=2e-4)  # 1.42 dB
    assert hann.bandwidth_3dB_bins == pytest.approx(1.44, abs=0.01)
    assert hann.mainlobe_half_width_bins == 2.0
    np.testing.assert_allclose(hann.bin_correlation[:3], [1.0, 4 / 9, 1 / 36], rtol=1e-6)
    assert hann.kernel.sum() == pytest.approx(1.0)
    flat = window_properties("flattop", 4096)
    assert flat.scalloping_loss < 0.0012


# --------------------------------------------------------------------------------------------
# correlation of Welch estimates (what the SDOF fit's covariance uses)


def test_averaged_bin_correlation_of_overlapping_windows():
    """Hann, 50 % overlap: rho_1^2 = 0.459 over many windows, 0.444 for one (Isserlis).

    Checked on white noise: the correlation of neighbouring Welch PSD values, deviations from
    the mean over 200 channels, pooled over 110 bins (standard error about 0.007).
    """
    props = window_properties("hann", 256)
    one = props.averaged_bin_correlation(128, 1)
    np.testing.assert_allclose(one[:3], props.bin_correlation[:3], atol=1e-12)
    many = props.averaged_bin_correlation(128, 400)
    np.testing.assert_allclose(many[:4], [1.0, 0.4589, 0.0394, 0.0015], atol=2e-4)
    in_runs = props.averaged_bin_correlation(128, 400, n_segments=100)
    assert one[1] < in_runs[1] < many[1]  # fewer overlapping pairs
    x = np.random.default_rng(31).normal(size=(200, 400 * 128 + 128))
    p = welch_psd(x, FS, nperseg=256).psd_per_Hz[:, 8:-8]
    e = p - p.mean(axis=0)
    lag = [float(np.mean(e[:, : e.shape[1] - q] * e[:, q:]) / np.mean(e * e)) for q in (1, 2)]
    assert lag[0] == pytest.approx(many[1], abs=0.025)
    assert lag[1] == pytest.approx(many[2], abs=0.025)


def test_welch_covariance_limits():
    """White: 2/nu on the diagonal and the averaged correlation; a line: fully correlated."""
    props = window_properties("hann", 4096)
    bins = np.arange(400, 420)
    V = props.welch_covariance(np.ones_like, bins, 2048, 249)
    nu = 2 * 249**2 / (249 + 2 * 248 / 36)  # Percival and Walden Eq. (292b), rho(N/2)^2 = 1/36
    np.testing.assert_allclose(np.diag(V), 2 / nu, rtol=1e-3)
    rho = props.averaged_bin_correlation(2048, 249)
    np.testing.assert_allclose(V[5, 5:8] / V[5, 5], rho[:3], atol=1e-3)
    # one window, all power at one frequency: |X_j|^2 = |A|^2 |W(f0 - j)|^2, correlation 1
    line = props.welch_covariance(lambda g: np.where(np.abs(g - 410.25) < 1e-9, 1.0, 0.0),
                                  np.arange(409, 413), 2048, 1)
    np.testing.assert_allclose(line, 1.0, rtol=1e-9)


def test_welch_covariance_of_narrow_peaks_against_simulation():
    """Modes 1.8 bins wide: neighbouring bins at the peak correlate at ~0.6, not 0.46.

    Fourteen well separated modes at the same position relative to the bin grid, white force
    through their continuous receptance per FFT bin; correlation of the Welch PSD of the two
    bins around each peak over 60 records of 2 s (840 pairs, standard error about 0.03).
    """
    nperseg, n = 1024, 51_200
    df = FS / nperseg
    centres = (40 + 32 * np.arange(14) + 0.5) * df  # halfway between two bins
    hw = 0.9 * df  # half-power half-width: 1.8 bins across
    f = np.fft.rfftfreq(n, 1 / FS)
    h = sum(1.0 / (c**2 - f**2 + 2j * hw * f) for c in centres)
    rng = np.random.default_rng(32)
    k = np.round(centres / df - 0.5).astype(int)
    pairs = []
    for _ in range(60):
        x = np.fft.irfft(np.fft.rfft(rng.normal(size=n)) * h, n)
        p = welch_psd(x, FS, nperseg=nperseg).psd_per_Hz
        pairs.append(np.log(p[np.r_[k, k + 1]]).reshape(2, -1))
    a = np.array(pairs)  # (record, bin below/above, mode)
    a -= a.mean(axis=0)
    got = float(np.mean(a[:, 0] * a[:, 1]) / np.sqrt(np.mean(a[:, 0] ** 2)
                                                    * np.mean(a[:, 1] ** 2)))
    props = window_properties("hann", nperseg)
    c0 = centres[0] / df
    V = props.welch_covariance(lambda g: 1.0 / ((g - c0) ** 2 + (hw / df) ** 2),
                               np.array([k[0], k[0] + 1]), nperseg // 2, 99)
    want = V[0, 1] / np.sqrt(V[0, 0] * V[1, 1])
    white = props.averaged_bin_correlation(nperseg // 2, 99)[1]
    assert want > white + 0.08  # the case is what it says
    assert got == pytest.approx(want, abs=0.07), (got, want, white)


# --------------------------------------------------------------------------------------------
# RMS: time domain against Parseval


@pytest.mark.parametrize("band", [None, (100.0, 2000.0), (5000.0, 12_800.0), (0.0, 500.0)])
def test_band_rms_time_and_parseval_agree_to_1_percent_for_broadband(band):
    x = np.random.default_rng(6).normal(0.0, 3.0, size=int(10 * FS))
    r = band_rms(x, FS, band, nperseg=4096)
    assert float(r.ratio) == pytest.approx(1.0, abs=0.01)


def test_band_rms_uses_a_given_spectrum_and_several_channels():
    x = np.random.default_rng(7).normal(size=(3, 200_000)) * np.array([[1.0], [2.0], [0.5]])
    s = welch_psd(x, FS, nperseg=2048)
    r = band_rms(x, FS, (50.0, 8000.0), spectrum=s)
    assert r.rms_time.shape == (3,)
    np.testing.assert_allclose(r.ratio, 1.0, atol=0.01)
    np.testing.assert_allclose(r.rms_parseval, rms_from_psd(s, (50.0, 8000.0)))


@settings(max_examples=60, deadline=None)
@given(
    data=st.lists(st.floats(-1e3, 1e3, allow_nan=False), min_size=64, max_size=64),
    n_blocks=st.integers(1, 4),
    junk=st.lists(st.integers(1, 15), max_size=3),
)
def test_parseval_with_gaps_is_an_identity(data, n_blocks, junk):
    """Boxcar windows tiling each kept segment: sum S df equals the mean square exactly."""
    N = 16
    base = np.asarray(data)
    parts, valid = [], []
    for i in range(n_blocks):  # kept segments: multiples of N, separated by a one-sample gap
        seg = np.roll(base, 7 * i)[: N * (1 + i % 3)]
        parts += [seg, np.array([1e300])]
        valid += [np.ones(seg.size, bool), np.array([False])]
    for j in junk:  # segments too short for a window: dropped and counted
        parts += [np.full(j, 5.0), np.array([np.nan])]
        valid += [np.ones(j, bool), np.array([False])]
    x = np.concatenate(parts)
    v = np.concatenate(valid)
    kept = np.concatenate([p for p, m in zip(parts, valid, strict=True) if m.all()
                           and p.size % N == 0 and p.size >= N])
    s = welch_psd(x, 100.0, valid=v, nperseg=N, noverlap=0, window="boxcar", detrend=False) \
        if np.ptp(kept) > 0 else None
    if s is None:
        return
    assert int(s.account.n_segments_dropped) == len(junk)
    assert int(s.account.n_samples_dropped) == sum(junk)
    ms = float(np.mean(kept**2))
    assert float(rms_from_psd(s)) ** 2 == pytest.approx(ms, rel=1e-9, abs=1e-9)
    r = band_rms(x, 100.0, valid=v, spectrum=s)
    assert float(r.rms_time) ** 2 == pytest.approx(ms, rel=1e-9, abs=1e-9)


@settings(max_examples=60, deadline=None)
@given(
    data=st.lists(st.floats(-100, 100, allow_nan=False), min_size=40, max_size=40),
    lo=st.floats(0.0, 49.0),
    width=st.floats(0.5, 50.0),
)
def test_band_parseval_is_an_identity_for_one_window(data, lo, width):
    """One boxcar window over the whole signal: the FFT band-pass and the PSD band sum agree.

    (Bands end at Nyquist, 50 Hz here: a band starting there is empty and refused.)
    """
    x = np.asarray(data)
    if np.ptp(x) == 0:
        return
    s = welch_psd(x, 100.0, nperseg=x.size, window="boxcar", detrend=False)
    r = band_rms(x, 100.0, (lo, min(lo + width, 50.0)), spectrum=s)
    assert float(r.rms_time) == pytest.approx(float(r.rms_parseval), rel=1e-9, abs=1e-9)


# --------------------------------------------------------------------------------------------
# gaps: split, never bridged, counted


def test_windows_never_straddle_a_gap():
    rng = np.random.default_rng(8)
    x = rng.normal(size=(2, 60_000))
    v = np.ones(60_000, bool)
    v[20_000:20_037] = False  # a gap
    v[41_000:41_100] = False  # and a segment too short for a window, between two gaps
    v[41_500:41_600] = False
    garbage = x.copy()
    garbage[:, ~v] = 1e12  # whatever the gap holds never reaches the estimate
    s = welch_psd(garbage, FS, valid=v, nperseg=1024)
    pieces = [(0, 20_000), (20_037, 41_000), (41_600, 60_000)]
    k = [int(n_windows(b - a, 1024, 512)) for a, b in pieces]
    ref = sum(ki * sps.welch(x[:, a:b], FS, nperseg=1024)[1]
              for ki, (a, b) in zip(k, pieces, strict=True)) / sum(k)
    np.testing.assert_allclose(s.psd_per_Hz, ref, rtol=1e-12)
    acc = s.account
    assert acc.n_windows.tolist() == [sum(k)] * 2
    assert acc.n_segments.tolist() == [3, 3]
    assert acc.n_segments_dropped.tolist() == [1, 1]
    assert acc.n_samples_dropped.tolist() == [400, 400]
    assert acc.n_invalid.tolist() == [37 + 200] * 2


def test_nan_gaps_without_a_mask_and_per_channel_masks():
    rng = np.random.default_rng(9)
    x = rng.normal(size=(2, 30_000))
    y = x.copy()
    y[1, 10_000:10_050] = np.nan  # only channel 1 has a gap
    s = welch_psd(y, FS, nperseg=1024)
    np.testing.assert_array_equal(s.psd_per_Hz[0], sps.welch(x[0], FS, nperseg=1024)[1])
    assert s.account.n_segments.tolist() == [1, 2]
    assert s.account.n_invalid.tolist() == [0, 50]
    median = welch_psd(y, FS, nperseg=1024, average="median")
    assert median.account.n_windows.tolist() == s.account.n_windows.tolist()


def test_valid_segments_and_window_counts():
    v = np.array([1, 1, 1, 0, 1, 0, 0, 1, 1, 1, 1], bool)
    s = valid_segments(v, min_length=3)
    assert [(sl.start, sl.stop) for sl in s.slices()] == [(0, 3), (7, 11)]
    assert (s.n_found, s.n_dropped, s.n_samples_dropped, s.n_invalid) == (3, 1, 1, 3)
    assert valid_segments(np.ones(5, bool)).is_whole
    assert valid_segments(np.zeros(5, bool)).n_kept == 0
    for length in (1023, 1024, 1535, 1536, 10_000):  # the count scipy uses
        x = np.zeros(length)
        x[::7] = 1.0
        if length >= 1024:
            _, _, sxx = sps.spectrogram(x, nperseg=1024, noverlap=512)
            assert int(n_windows(length, 1024, 512)) == sxx.shape[-1]
        else:
            assert int(n_windows(length, 1024, 512)) == 0


def test_equivalent_degrees_of_freedom():
    x = np.random.default_rng(10).normal(size=8192 * 40)
    box = welch_psd(x, FS, nperseg=8192, noverlap=0, window="boxcar")
    assert float(box.dof) == pytest.approx(2 * 40)  # 2K without overlap
    hann = welch_psd(x, FS, nperseg=8192)
    K = int(hann.n_windows)
    assert float(hann.dof) == pytest.approx(2 * K / (1 + 2 * (1 - 1 / K) / 36), rel=1e-9)
    # the log scatter of white noise matches the chi-square statistics
    _, var = log_chi2_stats(float(hann.dof))
    lnp = np.log(hann.psd_per_Hz[20:-20])
    assert np.var(lnp) == pytest.approx(var, rel=0.15)


# --------------------------------------------------------------------------------------------
# errors and flags


def test_too_short_for_the_resolution():
    x = np.random.default_rng(11).normal(size=5000)
    with pytest.raises(InsufficientDataError, match=r"`nperseg` must be <= len\(x\)=5000, "
                                                     r"was 8192"):
        welch_psd(x, FS, nperseg=8192)
    with pytest.raises(InsufficientDataError, match=r"resolution 1 Hz needs 1 s"):
        welch_psd(np.random.default_rng(12).normal(size=30_000), 1000.0, resolution_Hz=1.0,
                  valid=np.arange(30_000) % 1500 < 900)
    with pytest.raises(InsufficientDataError, match=r"longest valid segment of x=900 samples"):
        welch_psd(np.random.default_rng(12).normal(size=30_000), 1000.0, nperseg=1000,
                  valid=np.arange(30_000) % 1500 < 900)


def test_constant_signal_is_an_error():
    x = np.zeros((2, 4096))
    x[0] = np.random.default_rng(13).normal(size=4096)
    with pytest.raises(ConstantSignalError, match=r"`x\[1\]` is constant \(all 4096 valid "
                                                  r"samples equal 0.0\)"):
        welch_psd(x, FS, nperseg=1024)


@pytest.mark.parametrize(("kwargs", "match"), [
    ({"fs": -1.0}, r"`fs` must be a finite positive sample rate"),
    ({"noverlap": 1024}, r"`noverlap` must be an integer in \[0, nperseg=1024\), was 1024"),
    ({"detrend": "quadratic"}, r"`detrend` must be 'constant', 'linear', False"),
    ({"average": "mode"}, r"`average` must be 'mean' or 'median', was 'mode'"),
    ({"valid": np.ones(7, bool)}, r"`valid` must be of shape \(5000,\)"),
    ({"valid": np.ones(5000)}, r"`valid` must be a boolean mask"),
    ({"window": "nosuchwindow"}, r"`window` must be a window scipy.signal.get_window knows"),
    ({"nperseg": 1024, "resolution_Hz": 5.0}, r"`resolution_Hz` must be None when"),
])
def test_argument_validation(kwargs, match):
    args = {"fs": FS, "nperseg": 1024} | kwargs
    fs = args.pop("fs")
    with pytest.raises(SignalError, match=match):
        welch_psd(np.random.default_rng(14).normal(size=5000), fs, **args)


def test_non_finite_where_valid_is_an_error():
    x = np.random.default_rng(15).normal(size=5000)
    x[10] = np.inf
    with pytest.raises(SignalError, match=r"`x` must be finite where `valid` is True"):
        welch_psd(x, FS, nperseg=1024, valid=np.ones(5000, bool))


def test_errors_pickle_with_their_fields():
    e = InsufficientDataError("nperseg", "<= len(x)=10", "20", "detail", channel="accel_1")
    e2 = pickle.loads(pickle.dumps(e))
    assert type(e2) is InsufficientDataError and str(e2) == str(e)
    assert (e2.argument, e2.expected, e2.found, e2.channel) == ("nperseg", "<= len(x)=10",
                                                                 "20", "accel_1")
    assert isinstance(e2, ValueError)


def test_clipping_at_the_dbc_full_scale_is_flagged():
    rng = np.random.default_rng(16)
    raw = _sine(600.0, 440.0, 50_000) + rng.normal(0, 5, 50_000)  # beyond +-491.5 m/s^2
    x = np.clip(np.round(raw / DBC_LSB), -32768, 32767) * DBC_LSB
    c = detect_clipping(x)
    assert c.clipped and c.n_runs > 10 and c.longest_run > 3
    assert (c.low, c.high) == pytest.approx(DBC_FULL_SCALE)
    quiet = np.round((_sine(40.0, 440.0, 50_000) + rng.normal(0, 5, 50_000)) / DBC_LSB) * DBC_LSB
    assert not detect_clipping(quiet).clipped
    assert detect_clipping(quiet, full_scale=(-30.0, 30.0)).clipped  # a stated full scale
    v = np.ones(x.size, bool)
    v[np.abs(x) > 491] = False  # masked-out samples are not counted
    assert not detect_clipping(x, v).clipped


def test_clipping_needs_one_channel():
    with pytest.raises(SignalError, match=r"`x` must be one channel"):
        detect_clipping(np.zeros((2, 10)))


@pytest.mark.parametrize("time_axis", [0, 1, -1])
def test_band_rms_and_rms_from_psd_agree_whatever_the_time_axis(time_axis):
    from rigtools.analysis.spectra import band_rms, rms_from_psd, welch_psd

    fs = 10_000.0
    rng = np.random.default_rng(7)
    x = rng.normal(size=(2, 3, 40_000))  # time last
    ref = band_rms(x, fs, (50.0, 500.0), nperseg=1024)
    xa = np.moveaxis(x, -1, time_axis)
    got = band_rms(xa, fs, (50.0, 500.0), nperseg=1024, axis=time_axis)
    np.testing.assert_allclose(got.rms_parseval, ref.rms_parseval, rtol=1e-12)
    np.testing.assert_allclose(got.rms_time, ref.rms_time, rtol=1e-12)
    spec = welch_psd(xa, fs, nperseg=1024, axis=time_axis)
    assert spec.psd_per_Hz.shape[time_axis] == 513
    np.testing.assert_allclose(rms_from_psd(spec, (50.0, 500.0)), ref.rms_parseval,
                               rtol=1e-12)
    # a spectrum computed on axis 0 passed back in
    again = band_rms(xa, fs, (50.0, 500.0), spectrum=spec, axis=time_axis)
    np.testing.assert_allclose(again.rms_parseval, ref.rms_parseval, rtol=1e-12)


def test_axis_0_of_a_two_channel_array():
    from rigtools.analysis.spectra import band_rms, rms_from_psd, welch_psd

    fs = 10_000.0
    t = np.arange(100_000) / fs
    X = np.stack([np.sin(2 * np.pi * 100 * t), 2 * np.sin(2 * np.pi * 200 * t)], axis=1)
    want = [np.sqrt(0.5), np.sqrt(2.0)]
    np.testing.assert_allclose(band_rms(X, fs, (50, 500), nperseg=4096, axis=0).rms_parseval,
                               want, rtol=1e-6)
    np.testing.assert_allclose(
        rms_from_psd(welch_psd(X, fs, nperseg=4096, axis=0), (50, 500)), want, rtol=1e-6)
    np.testing.assert_allclose(rms_from_psd(welch_psd(X.T, fs, nperseg=4096), (50, 500)),
                               want, rtol=1e-6)

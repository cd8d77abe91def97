"""Signal synthesis of the demo: analytic limits of the accelerance, PSD levels, sidebands, noise.

Sources: Ewins (2000) sec. 2.2 for the accelerance and its mass line; Bendat and Piersol (2010)
sec. 6.1 for ``G_yy = |H|^2 G_xx`` (checked with scipy.signal.welch).
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.signal import welch

from rigtools.demo.modal_response import (
    accelerance,
    accelerance_peak,
    add_sensor_noise,
    mesh_tones,
    mode_acceleration,
    quantise,
)


def test_accelerance_limits_and_peak() -> None:
    zeta = 0.03
    f = np.array([0.0, 1.0, 1000.0, 1e7])
    a = np.abs(accelerance(f, 1000.0, zeta))
    assert a[0] == 0.0
    assert a[1] == pytest.approx(1e-6, rel=1e-3), "r^2 below resonance"
    assert a[2] == pytest.approx(1 / (2 * zeta)), "1 / (2 zeta) at f_n"
    assert a[3] == pytest.approx(1.0, rel=1e-6), "the mass line"
    grid = np.linspace(900.0, 1100.0, 200_001)
    assert np.abs(accelerance(grid, 1000.0, zeta)).max() == pytest.approx(
        accelerance_peak(zeta), rel=1e-9)
    with pytest.raises(ValueError, match="`zeta` must lie in"):
        accelerance(f, 1000.0, 0.8)


def test_mode_record_has_the_requested_peak_and_the_mass_line_floor() -> None:
    fs, f_n, zeta, peak = 25_600.0, 3000.0, 0.03, 0.02
    x = mode_acceleration(25_600 * 20, fs, f_n, zeta, peak, rng=1)
    f, p = welch(x, fs, nperseg=4096)
    at_peak = np.abs(f - f_n / np.sqrt(1 - 2 * zeta**2)) < 15.0
    assert np.mean(p[at_peak]) == pytest.approx(peak, rel=0.1)
    high = (f > 9000.0) & (f < 12000.0)  # r = 3..4: |A|^2 within 13 % of the mass line
    r = f[high] / f_n
    floor = peak * (r**4 / ((1 - r**2) ** 2 + (2 * zeta * r) ** 2)) / accelerance_peak(zeta) ** 2
    assert np.mean(p[high]) == pytest.approx(np.mean(floor), rel=0.05)
    low = (f > 100.0) & (f < 300.0)
    assert np.mean(p[low]) < 1e-3 * np.mean(p[high]), "no floor below resonance: r^4"
    with pytest.raises(ValueError, match="below the Nyquist"):
        mode_acceleration(100, fs, 13_000.0, zeta, peak)


def test_mesh_tones_carry_shaft_rate_sidebands() -> None:
    fs, n = 25_600.0, 25_600 * 6  # whole periods of 400, 25 and 400/24 Hz
    x = mesh_tones(n, fs, 400.0, (4.0, 2.0, 1.0), shaft_frequencies_Hz=(25.0, 400 / 24),
                   modulation_depths=(0.2, 0.1), rng=0)
    spec = np.abs(np.fft.rfft(x)) * 2 / n
    df = fs / n

    def amp(freq: float) -> float:
        return float(spec[round(freq / df)])

    for k, a in enumerate((4.0, 2.0, 1.0), 1):
        assert amp(400 * k) == pytest.approx(a, rel=1e-9)
        assert amp(400 * k + 25) == pytest.approx(a * 0.2 / 2, rel=1e-9)
        assert amp(400 * k - 400 / 24) == pytest.approx(a * 0.1 / 2, rel=1e-9)
    with pytest.raises(ValueError, match="one value per shaft frequency"):
        mesh_tones(10, fs, 400.0, (1.0,), shaft_frequencies_Hz=(25.0,))


def test_noise_at_the_stated_snr_and_quantisation() -> None:
    x = np.sin(np.linspace(0, 200 * np.pi, 200_000)) * 3.0
    y, sigma = add_sensor_noise(x, 20.0, rng=2)
    assert sigma == pytest.approx(np.std(x) / 10)
    assert np.std(y - x) == pytest.approx(sigma, rel=0.01)
    q = quantise(y, 0.01)
    assert np.max(np.abs(q - y)) <= 0.005 + 1e-12
    assert np.allclose(q / 0.01, np.round(q / 0.01), atol=1e-9)

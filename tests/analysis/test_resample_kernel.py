"""The compiled angular-resampling kernel against the array version it replaced.

The reference below is the array implementation that ``rigtools.analysis.resample`` used
before the kernel was compiled (outputs x taps per chunk, ``scipy.special.i0``): an
independent, slower evaluation of the same windowed sinc.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.special import i0

from rigtools.analysis.resample_kernel import bessel_i0, kaiser_sinc_apply, kaiser_table

ZEROS, BETA, CUTOFF = 32.0, 10.0, 0.94


def reference(xr: np.ndarray, u: np.ndarray, rho: np.ndarray) -> np.ndarray:
    out = np.empty(u.size)
    last = xr.size - 1
    for i in range(u.size):
        k = int(np.ceil(ZEROS / rho[i]))
        idx = np.floor(u[i]).astype(np.int64) + np.arange(-k + 1, k + 1)
        tau = u[i] - idx
        xw = rho[i] * tau / ZEROS
        w = np.where(np.abs(xw) < 1.0, i0(BETA * np.sqrt(np.clip(1.0 - xw * xw, 0.0, None))),
                     0.0)
        h = np.sinc(CUTOFF * rho[i] * tau) * w
        out[i] = h @ xr[np.clip(idx, 0, last)] / h.sum()
    return out


@pytest.mark.parametrize("x", [0.0, 1e-3, 0.5, 3.0, 7.5, 10.0])
def test_bessel_i0_equals_scipy(x: float) -> None:
    assert bessel_i0(x) == pytest.approx(float(i0(x)), rel=2e-15)


def test_the_window_table_is_within_1e8_of_the_series() -> None:
    table = kaiser_table(BETA)
    s = np.random.default_rng(1).uniform(0.0, 1.0, 2000)
    steps = table.size - 1
    m = np.minimum((s * steps).astype(int), steps - 1)
    interp = table[m] + (s * steps - m) * (table[m + 1] - table[m])
    exact = np.array([bessel_i0(BETA * np.sqrt(1.0 - v)) for v in s])
    assert np.max(np.abs(interp / exact - 1.0)) < 1e-8


def test_kernel_equals_the_array_version() -> None:
    rng = np.random.default_rng(4)
    xr = rng.standard_normal(4000)
    u = np.sort(rng.uniform(200.0, 3800.0, 500))
    u[:3] = [400.0, 401.0, 402.5]           # on a sample, on the next, half way
    rho = rng.uniform(0.2, 1.0, u.size)
    rho[::7] = 1.0
    got = kaiser_sinc_apply(xr, u, rho, ZEROS, CUTOFF, kaiser_table(BETA))
    # the window is read from a table (module notes: relative error ~1e-8 of the window)
    np.testing.assert_allclose(got, reference(xr, u, rho), rtol=0, atol=1e-7)


def test_a_band_limited_signal_is_interpolated() -> None:
    """A tone well inside the passband is reproduced between samples (rho = 1)."""
    n = np.arange(2000)
    f = 0.05                                        # cycles per sample
    xr = np.sin(2 * np.pi * f * n)
    u = np.linspace(100.3, 1899.7, 777)
    got = kaiser_sinc_apply(xr, u, np.ones_like(u), ZEROS, CUTOFF, kaiser_table(BETA))
    np.testing.assert_allclose(got, np.sin(2 * np.pi * f * u), atol=2e-5)

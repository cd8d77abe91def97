"""Figures of a calibration: Figures on the Agg canvas, PNGs written, no pyplot state."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest
from calibration_cases import TRUTH
from matplotlib.figure import Figure

from rigtools.calibration.curves import predictive_curves
from rigtools.plots.calibration import (
    calibration_figures,
    plot_frequency_vs_torque,
    plot_stiffness_vs_torque,
)


@pytest.fixture(scope="module")
def result(secant_fit: tuple[object, Path]) -> object:
    return secant_fit[0]


def test_curves_pass_through_the_measured_peaks(result: object) -> None:
    c = predictive_curves(result.headline, torque_Nm=[20.0, 50.0, 100.0, 183.4, 302.0])
    assert c.f_n_Hz.shape == (3, 2, 5)
    assert np.all(c.f_n_Hz[0] <= c.f_n_Hz[1]) and np.all(c.f_n_Hz[1] <= c.f_n_Hz[2])
    assert np.all(c.f_n_new_Hz[0] <= c.f_n_Hz[1]) and np.all(c.f_n_Hz[1] <= c.f_n_new_Hz[1])
    for temp_i, temp in enumerate(c.temperature_C):
        for t_i, t in enumerate([20.0, 50.0, 100.0, 183.4, 302.0]):
            run = np.isclose(c.run_temperature_C, temp) & np.isclose(c.run_torque_Nm, t)
            f = c.run_f_n_Hz[run]
            if f.size and np.isfinite(f[0]):
                lo, hi = c.f_n_new_Hz[:, temp_i, t_i]
                assert lo * 0.9 < f[0] < hi * 1.1, (temp, t)
    assert c.backlash_um[0] < c.backlash_um[1] < c.backlash_um[2]


def test_figures_are_drawn_and_written(result: object, tmp_path: Path) -> None:
    paths = calibration_figures(result, tmp_path, truths=TRUTH)
    assert set(paths) == {"corner", "traces", "f_n_vs_torque", "stiffness_vs_torque"}
    for p in paths.values():
        assert p.stat().st_size > 10_000 and p.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    c = predictive_curves(result.headline)
    for fig in (plot_frequency_vs_torque(c), plot_stiffness_vs_torque(c)):
        assert isinstance(fig, Figure) and fig.canvas is not None
    if "matplotlib.pyplot" in sys.modules:
        import matplotlib.pyplot as plt

        assert plt.get_fignums() == []

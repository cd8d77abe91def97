"""Smoke tests of the two-stage figures (rigtools.plots.two_stage): structure and data read back.

The maps and diagrams come from coarse runs of models.dynamics.two_stage_maps; the checks read
the drawn data back (colour-mesh values, Poincare points) against the result objects.
"""

import dataclasses

import numpy as np
import pytest
from matplotlib.collections import QuadMesh
from matplotlib.figure import Figure

from models.dynamics.two_stage_maps import bifurcation_over_frequency, peak_dte_map
from rigtools.plots import save_png
from rigtools.plots.two_stage import plot_peak_dte_map, plot_two_stage_bifurcation

FAST = dict(transient_periods=20, record_periods=4, steps_per_period=32)


@pytest.fixture(scope="module")
def dte_map():
    return peak_dte_map([3000.0, 5000.0, 7000.0, 9000.0], [40.0, 80.0, 120.0], **FAST)


def test_peak_dte_map_figure(dte_map, tmp_path):
    fig = plot_peak_dte_map(dte_map)
    assert isinstance(fig, Figure)
    panels = [ax for ax in fig.axes if ax.get_title().startswith("stage")]
    assert len(panels) == 2
    for st, ax in enumerate(panels):
        meshes = [c for c in ax.collections if isinstance(c, QuadMesh)]
        np.testing.assert_allclose(
            np.asarray(meshes[0].get_array()).reshape(3, 4), dte_map.peak_dte_m[:, :, st] * 1e6
        )
        assert "kHz" in ax.get_xlabel()
    assert "deg C" in panels[0].get_ylabel()
    amp = plot_peak_dte_map(dte_map, quantity="amplitude")
    ax = next(a for a in amp.axes if a.get_title().startswith("stage"))
    mesh = next(c for c in ax.collections if isinstance(c, QuadMesh))
    np.testing.assert_allclose(
        np.asarray(mesh.get_array()).reshape(3, 4), dte_map.amplitude_m[:, :, 0] * 1e6
    )
    assert dte_map.contact_loss.any()  # the hatching layer is drawn
    out = save_png(fig, tmp_path / "map.png", dpi=50)
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_map_figure_with_down_sweep_sorts_frequency():
    m = peak_dte_map([7000.0, 3000.0], [60.0], direction="down", **FAST)
    fig = plot_peak_dte_map(m, title="t")
    ax = next(a for a in fig.axes if a.get_title().startswith("stage"))
    mesh = next(c for c in ax.collections if isinstance(c, QuadMesh))
    np.testing.assert_allclose(np.asarray(mesh.get_array()).ravel(), m.peak_dte_m[0, ::-1, 0] * 1e6)


def test_map_figure_sorts_temperatures_and_shows_the_modes():
    """Unsorted temperatures used to garble pcolormesh (edges from unsorted centres)."""
    t = np.array([120.0, 40.0, 80.0])
    f = np.array([3000.0, 5000.0])
    m = peak_dte_map(f, t, **FAST)
    fig = plot_peak_dte_map(m, quantity="deflection")
    ax = next(a for a in fig.axes if a.get_title().startswith("stage"))
    mesh = next(c for c in ax.collections if isinstance(c, QuadMesh))
    order = np.argsort(t)
    np.testing.assert_allclose(
        np.asarray(mesh.get_array()).reshape(3, 2), m.peak_deflection_m[order, :, 0] * 1e6
    )
    np.testing.assert_allclose(mesh.get_coordinates()[:, 0, 1], [20.0, 60.0, 100.0, 140.0])
    # dashed mode lines: mode frequency (kHz) against the sorted temperatures
    dashed = [ln for ln in ax.get_lines() if ln.get_linestyle() == "--"]
    assert len(dashed) == 2
    np.testing.assert_allclose(dashed[0].get_ydata(), t[order])
    np.testing.assert_allclose(
        dashed[1].get_xdata(), m.mode_frequency_Hz[order, :, 1].mean(axis=1) / 1e3
    )
    title = fig.get_suptitle()
    assert "modes" in title and "40 deg C" in title and "f_n" not in title
    lo = m.mode_frequency_Hz[order[0]].mean(axis=0) / 1e3
    assert f"{lo[0]:.2f}/{lo[1]:.2f} kHz" in title


def test_map_figure_marks_diverged_points(dte_map):
    div = np.zeros(dte_map.diverged.shape, dtype=bool)
    div[1, 2] = True
    peak = dte_map.peak_dte_m.copy()
    peak[1, 2] = np.nan
    m = dataclasses.replace(dte_map, diverged=div, peak_dte_m=peak)
    fig = plot_peak_dte_map(m)
    ax = next(a for a in fig.axes if a.get_title().startswith("stage"))
    crosses = [ln for ln in ax.get_lines() if ln.get_marker() == "x"]
    assert len(crosses) == 1
    assert crosses[0].get_xdata()[0] == pytest.approx(7.0)  # 7 kHz
    assert crosses[0].get_ydata()[0] == pytest.approx(80.0)


def test_bifurcation_figure(tmp_path):
    b = bifurcation_over_frequency([3000.0, 5000.0, 7000.0], 80.0, **FAST)
    fig = plot_two_stage_bifurcation(b)
    panels = [ax for ax in fig.axes if ax.get_ylabel().startswith("DTE")]
    assert len(panels) == 2
    for st, ax in enumerate(panels):
        ys = np.concatenate([ln.get_ydata() for ln in ax.get_lines()])
        np.testing.assert_allclose(np.sort(ys), np.sort(b.samples_m[:, :, st].ravel() * 1e6))
    assert "kHz" in panels[1].get_xlabel()
    save_png(fig, tmp_path / "bif.png", dpi=50)


def test_rejects_wrong_objects():
    with pytest.raises(ValueError):
        plot_peak_dte_map(object())  # type: ignore[arg-type]
    with pytest.raises(ValueError):
        plot_two_stage_bifurcation(object())  # type: ignore[arg-type]
    m = peak_dte_map([3000.0], [60.0], **FAST)
    with pytest.raises(ValueError):
        plot_peak_dte_map(m, quantity="rms")  # type: ignore[arg-type]

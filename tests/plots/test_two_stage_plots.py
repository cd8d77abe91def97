"""Smoke tests of the two-stage figures (rigtools.plots.two_stage): structure and data read back.

The maps and diagrams come from coarse runs of models.dynamics.two_stage_maps; the checks read
the drawn data back (colour-mesh values, Poincare points) against the result objects.
"""

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

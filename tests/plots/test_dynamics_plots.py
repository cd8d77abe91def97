"""Figures of SDOF dynamics (rigtools.plots.dynamics): smoke tests with data read back.

A coarse up/down sweep of a Mathieu-type oscillator with backlash (period-1 branches, a
softening jump with contact loss, and a period-2 window at the principal parametric resonance
Lambda ~ 2) is drawn; the figures are checked as objects: axis labels, the lines and their
data against the SweepResult arrays, the marker series at the flagged points, the jump band,
and a PNG written through the Agg canvas.
"""

import numpy as np
import pytest
from matplotlib.figure import Figure

from models.dynamics import SDOFModel, sweep_up_down
from models.dynamics.dimensional import dimensional_scaling
from models.dynamics.sweep import SweepResult, hysteresis_band, hysteresis_bands
from models.geometry import load_gear_set
from models.stiffness.mesh_cycle import Harmonics
from rigtools.plots.dynamics import plot_sweep, plot_sweep_bifurcation
from rigtools.plots.stiffness import save_png

LAM = np.linspace(0.6, 2.2, 33)


@pytest.fixture(scope="module")
def sweeps():
    m = SDOFModel(
        zeta=0.03,
        force=0.1,
        backlash=1.0,
        stiffness=Harmonics(1.0, np.array([0.3]), np.array([0.0])),
        error=Harmonics(0.0, np.array([0.05]), np.array([0.0])),
        mean_stiffness_N_m=3e8,
        length_scale_m=68e-6,
    )
    up, down = sweep_up_down(m, LAM, steps_per_period=48, tol=1e-6, max_periods=600)
    return m, up, down


def lines(fig):
    return {ln.get_label(): ln for ln in fig.axes[0].get_lines()}


def test_sweep_figure_lines_markers_and_band(sweeps):
    _, up, down = sweeps
    assert down.contact_loss.any()  # the case exercises the contact-loss markers
    fig = plot_sweep(up, down, title="test")
    assert isinstance(fig, Figure) and len(fig.axes) == 1
    ax = fig.axes[0]
    assert "Λ" in ax.get_xlabel() and "A_rms" in ax.get_ylabel()
    ln = lines(fig)
    np.testing.assert_allclose(ln["up"].get_xdata(), LAM)
    np.testing.assert_allclose(ln["up"].get_ydata(), up.arms)
    np.testing.assert_allclose(ln["down"].get_ydata(), down.arms)
    loss = down.contact_loss & ~down.backside_impact
    np.testing.assert_allclose(ln["down: contact loss"].get_xdata(), LAM[loss])
    bands = hysteresis_bands(up, down)
    assert bands and all(lo <= hi for lo, hi in bands)
    band = hysteresis_band(up, down)
    assert band == (bands[0][0], bands[-1][1])
    spans = [p for p in ax.patches if p.get_facecolor()[:3] == (232 / 255,) * 3]
    assert len(spans) == len(bands)
    for sp, (lo, hi) in zip(spans, bands, strict=True):
        x0, x1 = sp.get_bbox().x0, sp.get_bbox().x1  # data x of an axvspan
        assert x0 == pytest.approx(lo) and x1 == pytest.approx(hi)
    labels = [p.get_label() for p in spans]
    assert labels.count("up/down differ (jump band)") == 1  # one legend entry


def test_sweep_figure_in_rig_units(sweeps, tmp_path):
    m, up, down = sweeps
    s = dimensional_scaling(m, load_gear_set("kahraman-blankenship").pair)
    fig = plot_sweep(up, down, scaling=s)
    ax = fig.axes[0]
    assert "Hz" in ax.get_xlabel() and "µm" in ax.get_ylabel()
    ln = lines(fig)
    np.testing.assert_allclose(ln["up"].get_xdata(), s.mesh_frequency_Hz(LAM))
    np.testing.assert_allclose(ln["up"].get_ydata(), up.arms * 68.0)
    out = save_png(fig, tmp_path / "sweep.png", dpi=60)
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_bifurcation_figure(sweeps, tmp_path):
    _, up, down = sweeps
    assert (up.period == 2).any() and (up.period == 1).any()  # both kinds of orbit present
    fig = plot_sweep_bifurcation([up, down], labels=["up", "down"])
    ln = lines(fig)
    assert set(ln) == {"up", "down"}
    x, y = ln["up"].get_xdata(), ln["up"].get_ydata()
    assert x.size == np.isfinite(up.poincare[..., 0]).sum()
    # distinct Poincare values per Lambda: 1 on a period-1 point, 2 on a period-2 point
    for i in (int(np.argmax(up.period == 1)), int(np.argmax(up.period == 2))):
        vals = np.sort(y[x == LAM[i]])
        clusters = 1 + int(np.sum(np.diff(vals) > 1e-3))  # settle tol is 1e-6
        assert clusters == up.period[i]
    save_png(fig, tmp_path / "bif.png", dpi=60)
    with pytest.raises(ValueError, match="labels"):
        plot_sweep_bifurcation([up, down], labels=["one"])
    with pytest.raises(ValueError, match="SweepResult"):
        plot_sweep("not a result")  # type: ignore[arg-type]


def test_marker_series_only_where_flagged(sweeps):
    _, up, _down = sweeps
    ln = lines(plot_sweep(up))
    assert ("up: contact loss" in ln) == bool((up.contact_loss & ~up.backside_impact).any())
    assert ("up: back-side impact" in ln) == bool(up.backside_impact.any())
    assert "down" not in ln


def _result(freq, arms):
    """A SweepResult with the given Arms (first harmonic only), all else neutral."""
    n = len(freq)
    a = np.zeros((n, 3))
    a[:, 0] = arms
    return SweepResult(
        frequency=np.asarray(freq, dtype=float),
        amplitudes=a,
        arms=np.asarray(arms, dtype=float),
        mean_dte=np.zeros(n),
        contact_loss=np.zeros(n, dtype=bool),
        backside_impact=np.zeros(n, dtype=bool),
        converged=np.ones(n, dtype=bool),
        periods=np.zeros(n, dtype=int),
        length_scale_m=1.0,
        period=np.ones(n, dtype=int),
        poincare=np.zeros((n, 1, 2)),
        entry_state=np.zeros((n, 2)),
    )


def test_separate_regions_give_separate_bands():
    """Super-harmonic and primary jump regions apart: two bands, two shaded spans, not one."""
    f = np.round(np.arange(0.4, 1.41, 0.1), 2)  # 0.4 .. 1.4
    up = np.ones(f.size)
    down = up.copy()
    down[[1, 2]] = 2.0  # 0.5, 0.6
    down[[5, 6, 7]] = 3.0  # 0.9, 1.0, 1.1
    down[10] = 1.05  # within rel_tol: not a band
    bands = hysteresis_bands(_result(f, up), _result(f[::-1], down[::-1]))
    assert bands == [(0.5, 0.6), (0.9, 1.1)]
    assert hysteresis_band(_result(f, up), _result(f, down)) == (0.5, 1.1)
    ax = plot_sweep(_result(f, up), _result(f, down)).axes[0]
    spans = sorted((p.get_bbox().x0, p.get_bbox().x1) for p in ax.patches)
    np.testing.assert_allclose(spans, bands)
    assert hysteresis_bands(_result(f, up), _result(f, up)) == []
    assert hysteresis_band(_result(f, up), _result(f, up)) is None
    with pytest.raises(ValueError, match="grid"):
        hysteresis_bands(_result(f, up), _result(f + 0.01, up))

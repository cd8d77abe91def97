"""Figure of a run-up calibration (rigtools.plots.runup) on synthetic arrays.

A run-up and run-down path (12 points each way and 2 hold points at the top) with a resonance
curve, two models' bands and jumps; the figure is checked as an object: one log-y panel per
channel with labelled axes, the measured markers split by direction, each model's band and
median split by branch with the data of the arrays, the jump lines and strip markers, and a
PNG written through the Agg canvas.
"""

import numpy as np
import pytest
from matplotlib.figure import Figure

from rigtools.plots import RunUpBand, RunUpFigureData, plot_runup, write_runup_figures
from rigtools.plots.runup import figure_file_name

F_UP = np.linspace(1000.0, 4000.0, 12)
F = np.concatenate([F_UP, [4000.0, 4000.0], F_UP[::-1]])
DIRECTION = np.array(["up"] * 12 + ["hold"] * 2 + ["down"] * 12)
CHANNELS = ("x", "y $z$")


def _curve(f: np.ndarray, gain: float) -> np.ndarray:
    r = f / 3000.0
    return gain * f**2 / np.sqrt((1 - r**2) ** 2 + (0.1 * r) ** 2) * 1e-4


@pytest.fixture
def data() -> RunUpFigureData:
    obs = np.stack([_curve(F, 1.0), _curve(F, 0.4)])
    obs[1, 3] = np.nan  # a bridging point: not observed
    q = np.stack([obs * 0.8, obs, obs * 1.25])
    q[:, 1, 3] = _curve(F, 0.4)[3] * np.array([0.8, 1.0, 1.25])
    bands = (RunUpBand("vvms", q, np.array([2900.0, 3000.0, 3100.0]),
                       np.array([2700.0, 2800.0, 2850.0])),
             RunUpBand("fvms", q * 1.1))
    return RunUpFigureData(run_id="ramp-340", channels=CHANNELS, mesh_frequency_Hz=F,
                           direction=DIRECTION, observed_m_s2=obs, bands=bands,
                           measured_jump_up_Hz=3050.0, measured_jump_down_Hz=None,
                           torque_Nm=340.0)


def _by_gid(ax, gid):
    return [a for a in [*ax.get_lines(), *ax.collections] if a.get_gid() == gid]


def test_one_log_panel_per_channel_with_units(data):
    fig = plot_runup(data)
    assert isinstance(fig, Figure) and len(fig.axes) == 2
    for ax in fig.axes:
        assert ax.get_yscale() == "log"
        assert "m/s²" in ax.get_ylabel()
    assert "(Hz)" in fig.axes[-1].get_xlabel()
    assert "340 N m" in fig.get_suptitle()
    assert r"\$z\$" in fig.axes[1].get_title()  # mathtext escaped: shown literally


def test_measured_points_split_by_direction(data):
    fig_axes = plot_runup(data).axes
    ax = fig_axes[0]
    (up,) = _by_gid(ax, "measured/up")
    (down,) = _by_gid(ax, "measured/down")
    (hold,) = _by_gid(ax, "measured/hold")
    assert up.get_marker() == "^" and down.get_marker() == "v"
    np.testing.assert_allclose(up.get_xdata(), F[DIRECTION == "up"])
    np.testing.assert_allclose(up.get_ydata(), data.observed_m_s2[0, DIRECTION == "up"])
    np.testing.assert_allclose(down.get_ydata(), data.observed_m_s2[0, DIRECTION == "down"])
    assert len(hold.get_xdata()) == 2
    # the NaN (not observed) point of channel 1 is left out, the others are drawn
    (up1,) = _by_gid(fig_axes[1], "measured/up")
    assert len(up1.get_xdata()) == 11


def test_bands_and_medians_per_model_and_branch(data):
    ax = plot_runup(data).axes[0]
    for model in ("vvms", "fvms"):
        for branch in ("up", "down"):
            assert len(_by_gid(ax, f"band/{model}/{branch}")) == 1
            (med,) = _by_gid(ax, f"median/{model}/{branch}")
            assert med.get_linestyle() == ("-" if branch == "up" else "--")
    # the up branch holds the run-up points and the hold points after them, sorted by f
    (med,) = _by_gid(ax, "median/vvms/up")
    want = data.bands[0].arms_quantiles_m_s2[1, 0, :14]
    order = np.argsort(F[:14], kind="stable")
    np.testing.assert_allclose(med.get_xdata(), F[:14][order])
    np.testing.assert_allclose(med.get_ydata(), want[order])
    (med_d,) = _by_gid(ax, "median/vvms/down")
    np.testing.assert_allclose(med_d.get_xdata(), np.sort(F[14:]))


def test_jumps_measured_and_modelled(data):
    ax = plot_runup(data).axes[0]
    (line,) = _by_gid(ax, "jump/measured/up")
    assert line.get_xdata()[0] == pytest.approx(3050.0)
    assert not _by_gid(ax, "jump/measured/down")  # None: no line
    (m,) = _by_gid(ax, "jump/vvms/up")
    assert m.get_xdata()[0] == pytest.approx(3000.0) and m.get_marker() == "^"
    (bar,) = _by_gid(ax, "jump/vvms/up/interval")
    np.testing.assert_allclose(bar.get_xdata(), [2900.0, 3100.0])
    (m,) = _by_gid(ax, "jump/vvms/down")
    assert m.get_marker() == "v"
    assert not _by_gid(ax, "jump/fvms/up")  # NaN: no jump in the draws


def test_shapes_are_checked(data):
    bad = RunUpFigureData(run_id="r", channels=("x",), mesh_frequency_Hz=F,
                          direction=DIRECTION, observed_m_s2=data.observed_m_s2)
    with pytest.raises(ValueError, match=r"`observed_m_s2` must have the shape"):
        plot_runup(bad)
    bad = RunUpFigureData(run_id="r", channels=CHANNELS, mesh_frequency_Hz=F,
                          direction=DIRECTION[:-1], observed_m_s2=data.observed_m_s2)
    with pytest.raises(ValueError, match=r"`direction` must have the shape"):
        plot_runup(bad)
    bad = RunUpFigureData(run_id="r", channels=CHANNELS, mesh_frequency_Hz=F,
                          direction=DIRECTION, observed_m_s2=data.observed_m_s2,
                          bands=(RunUpBand("vvms", np.zeros((3, 1, F.size))),))
    with pytest.raises(ValueError, match=r"`arms_quantiles_m_s2` of model 'vvms'"):
        plot_runup(bad)


def test_png_written(tmp_path, data):
    paths = write_runup_figures([data], tmp_path)
    assert paths["ramp-340"] == tmp_path / "runup_ramp-340.png"
    assert paths["ramp-340"].read_bytes().startswith(b"\x89PNG")
    paths = write_runup_figures([data], tmp_path, file_name=lambda rid: f"runup_{rid}_x.png")
    assert paths["ramp-340"].name == "runup_ramp-340_x.png"
    assert figure_file_name("a/b c") == "runup_a_b_c.png"

"""Figure of the converged tribo-dynamic state (rigtools.plots.tribo): structure and data.

The figure is checked as an object: four panels with units in the labels, and the data of the
dynamic lines read back against the :class:`TriboSolution` arrays they were drawn from; it is
also written to PNG through the Agg canvas.
"""

import numpy as np
import pytest
from matplotlib.figure import Figure

from models.dynamics.tribo_case import load_tribo_case, solve_tribo_case
from rigtools.plots.stiffness import save_png
from rigtools.plots.tribo import plot_tribo_solution

CASE = load_tribo_case("seed-002-tribo")


@pytest.fixture(scope="module")
def solution():
    return solve_tribo_case(CASE)


def test_figure_panels_and_data(solution, tmp_path):
    fig = plot_tribo_solution(solution, CASE.pair)
    assert isinstance(fig, Figure)
    axes = fig.axes
    assert len(axes) == 4
    labels = [ax.get_ylabel() for ax in axes]
    assert "(µm)" in labels[0] and "Lambda" in labels[1] and "friction" in labels[2]
    assert labels[3] == "mesh force (N)"
    s, h = solution.contact.along_path("film_thickness_m")
    line = axes[0].lines[0]
    order = np.argsort(s, kind="stable")
    np.testing.assert_allclose(line.get_xdata(), s[order] * 1e3)
    np.testing.assert_allclose(line.get_ydata(), h[order] * 1e6)
    force = axes[3].lines[0]
    np.testing.assert_allclose(force.get_ydata(), solution.mesh_force_N)
    # the friction line crosses zero at the pitch point line drawn on the same axes
    pitch = next(ln for ln in axes[2].lines if ln.get_gid() == "pitch")
    f_line = axes[2].lines[0]
    x, f = np.asarray(f_line.get_xdata()), np.asarray(f_line.get_ydata())
    xp = float(np.asarray(pitch.get_xdata())[0])
    assert np.all(f[x < xp - 0.2] < 0) and np.all(f[x > xp + 0.2] > 0)
    out = save_png(fig, tmp_path / "tribo.png", dpi=60)
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_rejects_other_objects():
    with pytest.raises(ValueError, match="TriboSolution"):
        plot_tribo_solution(object())  # type: ignore[arg-type]

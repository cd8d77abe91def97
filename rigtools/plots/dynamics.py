r"""Figures of SDOF gear dynamics: up/down Arms sweeps and Poincare bifurcation diagrams.

The presentation layer over :mod:`models.dynamics.sweep` (seed 003 Figs. 8-11): functions here
take :class:`~models.dynamics.SweepResult` objects (and optionally a
:class:`~models.dynamics.dimensional.DimensionalScaling` for rig units) and return
:class:`matplotlib.figure.Figure` objects drawn on the Agg canvas, without ``matplotlib.pyplot``
or ``rcParams``, so importing this module changes no global state.

* :func:`plot_sweep`: Arms of the DTE (first three mesh harmonics) against ``Lambda`` -- or the
  mesh frequency (Hz) and DTE (um) with a scaling -- for an upward sweep (solid) and a downward
  sweep (dashed), with markers at the points with contact loss (open circles) and back-side
  impact (crosses), and each hysteresis (jump) band shaded where the two branches differ
  (:func:`models.dynamics.sweep.hysteresis_bands`).
* :func:`plot_sweep_bifurcation`: the Poincare points (DTE at mesh phase 0, after settling) against
  ``Lambda``: one dot per period of a period-1 response, ``n`` distinct dots for period ``n``,
  a cloud for aperiodic responses.

Use :func:`rigtools.plots.stiffness.save_png` to write PNG files.
"""

from __future__ import annotations

from typing import Final

import numpy as np
from matplotlib.axes import Axes
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from models.dynamics.dimensional import DimensionalScaling
from models.dynamics.sweep import SweepResult, hysteresis_bands

__all__ = ["plot_sweep", "plot_sweep_bifurcation"]

_WIDTH_IN: Final = 7.0
_HEIGHT_IN: Final = 4.2
#: Okabe-Ito colours: up sweep blue, down sweep vermillion, band grey.
_UP: Final = "#0072B2"
_DOWN: Final = "#D55E00"
_BAND: Final = "#E8E8E8"
_FONT_SIZE: Final = 8


def _check_result(result: object, name: str) -> SweepResult:
    if not isinstance(result, SweepResult):
        raise ValueError(f"`{name}` must be a SweepResult, was {type(result).__name__}")
    if result.frequency.size == 0:
        raise ValueError(f"`{name}` has no points")
    return result


def _axes_units(
    result: SweepResult, scaling: DimensionalScaling | None
) -> tuple[np.ndarray, np.ndarray, str, str]:
    if scaling is None:
        return (
            result.frequency,
            result.arms,
            "frequency ratio Λ = 2π f_m / ω_n",
            "A_rms of the DTE (units of L)",
        )
    return (
        scaling.mesh_frequency_Hz(result.frequency),
        scaling.dte_um(result.arms),
        "mesh frequency f_m (Hz)",
        "A_rms of the DTE (µm)",
    )


def _draw(
    ax: Axes,
    r: SweepResult,
    scaling: DimensionalScaling | None,
    colour: str,
    style: str,
    label: str,
) -> None:
    """The Arms line and, where there are any, the contact-loss and back-side markers."""
    x, y, _, _ = _axes_units(r, scaling)
    ax.plot(x, y, style, color=colour, lw=1.2, label=label)
    loss = r.contact_loss & ~r.backside_impact
    if loss.any():
        ax.plot(
            x[loss],
            y[loss],
            "o",
            mfc="none",
            mec=colour,
            ms=4,
            ls="none",
            label=f"{label}: contact loss",
        )
    if r.backside_impact.any():
        ax.plot(
            x[r.backside_impact],
            y[r.backside_impact],
            "x",
            color=colour,
            ms=5,
            ls="none",
            label=f"{label}: back-side impact",
        )


def plot_sweep(
    up: SweepResult,
    down: SweepResult | None = None,
    *,
    scaling: DimensionalScaling | None = None,
    title: str | None = None,
) -> Figure:
    """Arms against frequency for an up sweep and optionally a down sweep (seed 003 Fig. 8).

    Parameters
    ----------
    up : SweepResult
        Upward sweep (any order; drawn sorted).
    down : SweepResult, optional
        Downward sweep on the same grid; then every region where the branches differ
        (:func:`models.dynamics.sweep.hysteresis_bands`) is shaded separately.
    scaling : DimensionalScaling, optional
        Draw in mesh frequency (Hz) and um instead of ``Lambda`` and units of ``L``.
    title : str, optional

    Returns
    -------
    matplotlib.figure.Figure
        One axes; lines labelled ``"up"``, ``"down"``, and marker series ``"up: contact
        loss"``, ``"up: back-side impact"`` (likewise for down) where there are such points.
    """
    u = _check_result(up, "up").sorted()
    fig = Figure(figsize=(_WIDTH_IN, _HEIGHT_IN), layout="constrained")
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    _, _, xl, yl = _axes_units(u, scaling)
    if down is not None:
        d = _check_result(down, "down").sorted()
        for k, (lo, hi) in enumerate(hysteresis_bands(u, d)):
            if scaling is not None:
                lo, hi = (float(v) for v in scaling.mesh_frequency_Hz([lo, hi]))
            ax.axvspan(
                lo,
                hi,
                color=_BAND,
                zorder=0,
                label="up/down differ (jump band)" if k == 0 else "_nolegend_",
            )
    _draw(ax, u, scaling, _UP, "-", "up")
    if down is not None:
        _draw(ax, d, scaling, _DOWN, "--", "down")
    ax.set_xlabel(xl, fontsize=_FONT_SIZE)
    ax.set_ylabel(yl, fontsize=_FONT_SIZE)
    ax.tick_params(labelsize=_FONT_SIZE)
    ax.grid(True, lw=0.3, alpha=0.5)
    ax.legend(fontsize=_FONT_SIZE - 1, ncols=2, loc="upper right")
    if title:
        ax.set_title(title, fontsize=_FONT_SIZE + 1)
    return fig


def plot_sweep_bifurcation(
    results: SweepResult | list[SweepResult],
    *,
    labels: list[str] | None = None,
    scaling: DimensionalScaling | None = None,
    title: str | None = None,
) -> Figure:
    """Poincare bifurcation diagram: DTE at mesh phase 0 after settling, against frequency.

    Parameters
    ----------
    results : SweepResult or list of SweepResult
        E.g. ``[up, down]``; every stored Poincare point (``result.poincare[..., 0]``) of each
        frequency is drawn as a dot.
    labels : list of str, optional
        One per result (default ``"sweep 1"``, ...).
    scaling : DimensionalScaling, optional
        Draw in Hz and um.
    title : str, optional

    Returns
    -------
    matplotlib.figure.Figure
        One axes, one marker series (``Line2D``) per result.
    """
    rs = [results] if isinstance(results, SweepResult) else list(results)
    rs = [_check_result(r, f"results[{i}]") for i, r in enumerate(rs)]
    if labels is None:
        labels = [f"sweep {i + 1}" for i in range(len(rs))]
    if len(labels) != len(rs):
        raise ValueError(f"`labels` must have {len(rs)} entries, had {len(labels)}")
    colours = (_UP, _DOWN, "#009E73", "#CC79A7", "#E69F00", "#56B4E9")
    fig = Figure(figsize=(_WIDTH_IN, _HEIGHT_IN), layout="constrained")
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    for i, (r, lab) in enumerate(zip(rs, labels, strict=True)):
        k = r.poincare.shape[1]
        lam = np.repeat(r.frequency, k)
        x = r.poincare[..., 0].ravel()
        ok = np.isfinite(x)
        fx = lam if scaling is None else scaling.mesh_frequency_Hz(lam)
        fy = x if scaling is None else scaling.dte_um(x)
        ax.plot(fx[ok], fy[ok], ".", ms=2, color=colours[i % len(colours)], ls="none", label=lab)
    ax.set_xlabel(
        "frequency ratio Λ" if scaling is None else "mesh frequency f_m (Hz)", fontsize=_FONT_SIZE
    )
    ax.set_ylabel(
        "Poincaré DTE x(τ_k) (units of L)" if scaling is None else "Poincaré DTE (µm)",
        fontsize=_FONT_SIZE,
    )
    ax.tick_params(labelsize=_FONT_SIZE)
    ax.grid(True, lw=0.3, alpha=0.5)
    ax.legend(fontsize=_FONT_SIZE - 1, markerscale=4)
    if title:
        ax.set_title(title, fontsize=_FONT_SIZE + 1)
    return fig

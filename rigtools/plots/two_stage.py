r"""Figures of the two-stage thermal model: peak-DTE maps and bifurcation diagrams (seed 001).

The presentation layer over :mod:`models.dynamics.two_stage_maps`: functions take
:class:`~models.dynamics.two_stage_maps.PeakDTEMap` and
:class:`~models.dynamics.two_stage_maps.Bifurcation` result objects and return
:class:`matplotlib.figure.Figure` objects drawn on the Agg canvas. Nothing touches
``matplotlib.pyplot`` or ``rcParams`` (as :mod:`rigtools.plots.stiffness`).

* :func:`plot_peak_dte_map`: seed 001's parameter-plane maps, one panel per stage, peak
  ``|DTE|`` (um) in colour over stage-1 mesh frequency (x) and bulk temperature (y)
  (``pcolormesh``), the cells with contact loss hatched and outlined by a contour, the
  back-side impacts marked with dots;
* :func:`plot_two_stage_bifurcation`: bifurcation-style diagram, the Poincare samples of the DTE of
  both stages (one per system period after the transient) against mesh frequency or bulk
  temperature, points coloured by the contact state (full contact, contact loss, back-side
  impact).

Save with :func:`rigtools.plots.save_png`.
"""

from __future__ import annotations

from typing import Final, Literal

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.colors import ListedColormap
from matplotlib.figure import Figure
from matplotlib.patches import Patch

from models.dynamics.two_stage_maps import Bifurcation, PeakDTEMap

__all__ = ["plot_peak_dte_map", "plot_two_stage_bifurcation"]

_WIDTH_IN: Final = 7.0
_STAGE_NAMES: Final = ("stage 1 (gears 1-2)", "stage 2 (gears 3-4)")
#: Okabe-Ito: full contact, contact loss, back-side impact.
_STATE_COLOURS: Final = ("#0072B2", "#E69F00", "#D55E00")
_STATE_LABELS: Final = ("full contact", "contact loss", "back-side impact")


def _edges(x: np.ndarray) -> np.ndarray:
    """Cell edges around centres ``x`` (midpoints; ends mirrored; one point: +-0.5)."""
    if x.size == 1:
        return np.array([x[0] - 0.5, x[0] + 0.5])
    mid = 0.5 * (x[1:] + x[:-1])
    return np.concatenate([[2 * x[0] - mid[0]], mid, [2 * x[-1] - mid[-1]]])


def plot_peak_dte_map(
    result: PeakDTEMap,
    *,
    quantity: Literal["peak", "amplitude"] = "peak",
    title: str | None = None,
) -> Figure:
    """Peak-DTE maps of both stages over mesh frequency x bulk temperature.

    Parameters
    ----------
    result : PeakDTEMap
    quantity : {"peak", "amplitude"}
        Colour by peak ``|DTE|`` (static deflection included; seed 001's "maximum amplitude
        of the DTE") or by half the peak-to-peak DTE (the vibration alone).
    title : str or None
        Figure title; None gives one naming the sweep direction and the natural frequency.

    Returns
    -------
    matplotlib.figure.Figure
        Two panels (stage 1 left, stage 2 right), each with its colour bar of peak ``|DTE|``
        (um); cells with contact loss hatched ``//`` and outlined (contour at 0.5 of the
        flag); back-side impacts as black dots.
    """
    if not isinstance(result, PeakDTEMap):
        raise ValueError(f"`result` must be a PeakDTEMap, was {type(result).__name__}")
    if quantity not in ("peak", "amplitude"):
        raise ValueError(f"`quantity` must be 'peak' or 'amplitude', was {quantity!r}")
    values = result.peak_dte_m if quantity == "peak" else result.amplitude_m
    label = "peak |DTE| (um)" if quantity == "peak" else "DTE amplitude (um)"
    f, t = result.frequency_Hz, result.temperature_C
    order = np.argsort(f)
    f = f[order]
    fe, te = _edges(f) / 1e3, _edges(t)
    fig = Figure(figsize=(_WIDTH_IN, 3.4), layout="constrained")
    FigureCanvasAgg(fig)
    axes = fig.subplots(1, 2, sharey=True)
    for st, ax in enumerate(axes):
        z = values[:, order, st] * 1e6
        mesh = ax.pcolormesh(fe, te, z, cmap="viridis", shading="flat")
        fig.colorbar(mesh, ax=ax, label=label)
        loss = result.contact_loss[:, order, st]
        if loss.any():
            ax.pcolor(
                fe,
                te,
                np.ma.masked_where(~loss, loss.astype(float)),
                cmap=ListedColormap(["none"]),
                hatch="//",
                edgecolor="white",
                linewidth=0.0,
                shading="flat",
            )
            if loss.shape[0] > 1 and loss.shape[1] > 1 and not loss.all():
                ax.contour(
                    f / 1e3, t, loss.astype(float), levels=[0.5], colors="white", linewidths=1.0
                )
        back = result.back_contact[:, order, st]
        if back.any():
            jj, ii = np.meshgrid(f / 1e3, t)
            ax.plot(jj[back], ii[back], ".", color="black", markersize=3)
        ax.set_title(_STAGE_NAMES[st])
        ax.set_xlabel("stage-1 mesh frequency (kHz)")
    axes[0].set_ylabel("bulk temperature (deg C)")
    handles = [
        Patch(facecolor="none", edgecolor="black", hatch="//", label="contact loss"),
        Patch(facecolor="black", label="back-side impact (dots)"),
    ]
    axes[1].legend(handles=handles, loc="upper right", fontsize="small", framealpha=0.8)
    fig.suptitle(
        title
        if title is not None
        else f"{'Peak DTE' if quantity == 'peak' else 'DTE amplitude'}, {result.direction}-sweep "
        f"(f_n = {result.natural_frequency_Hz / 1e3:.2f} kHz)"
    )
    return fig


def plot_two_stage_bifurcation(result: Bifurcation, *, title: str | None = None) -> Figure:
    """Bifurcation diagram: Poincare samples of the DTE of both stages over the parameter.

    Parameters
    ----------
    result : Bifurcation
    title : str or None
        Figure title; None names the fixed parameter.

    Returns
    -------
    matplotlib.figure.Figure
        Two stacked panels (stage 1 top), DTE (um) against the parameter (kHz for mesh
        frequency, deg C for temperature), one marker per Poincare sample, coloured by the
        contact state at that parameter value.
    """
    if not isinstance(result, Bifurcation):
        raise ValueError(f"`result` must be a Bifurcation, was {type(result).__name__}")
    freq = result.parameter_unit == "Hz"
    x = result.parameter / 1e3 if freq else result.parameter
    n_rec = result.samples_m.shape[1]
    fig = Figure(figsize=(_WIDTH_IN, 5.0), layout="constrained")
    FigureCanvasAgg(fig)
    axes = fig.subplots(2, 1, sharex=True)
    for st, ax in enumerate(axes):
        state = np.where(result.back_contact[:, st], 2, np.where(result.contact_loss[:, st], 1, 0))
        for k in range(3):
            sel = state == k
            if not sel.any():
                continue
            xs = np.repeat(x[sel], n_rec)
            ys = result.samples_m[sel, :, st].reshape(-1) * 1e6
            ax.plot(
                xs,
                ys,
                ".",
                markersize=2,
                color=_STATE_COLOURS[k],
                label=_STATE_LABELS[k],
                linestyle="none",
            )
        ax.set_ylabel(f"DTE {_STAGE_NAMES[st].split(' (')[0]} (um)")
        ax.legend(loc="upper right", fontsize="small", markerscale=4)
    axes[1].set_xlabel(f"{'stage-1 mesh frequency (kHz)' if freq else 'bulk temperature (deg C)'}")
    fixed = f"{result.fixed:.0f} deg C" if freq else f"{result.fixed / 1e3:.3g} kHz"
    fig.suptitle(title if title is not None else f"Poincare samples per system period at {fixed}")
    return fig

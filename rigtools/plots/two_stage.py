r"""Figures of the two-stage thermal model: peak-DTE maps and bifurcation diagrams (seed 001).

The presentation layer over :mod:`models.dynamics.two_stage_maps`: functions take
:class:`~models.dynamics.two_stage_maps.PeakDTEMap` and
:class:`~models.dynamics.two_stage_maps.Bifurcation` result objects and return
:class:`matplotlib.figure.Figure` objects drawn on the Agg canvas. Nothing touches
``matplotlib.pyplot`` or ``rcParams`` (as :mod:`rigtools.plots.stiffness`).

* :func:`plot_peak_dte_map`: seed 001's parameter-plane maps, one panel per stage, peak
  ``|DTE|`` (um) in colour over stage-1 mesh frequency (x) and bulk temperature (y)
  (``pcolormesh``, axes sorted), the cells with contact loss hatched and outlined by a
  contour, the back-side impacts marked with dots, diverged points with red crosses, and the
  system's two natural frequencies against temperature as dashed lines;
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


_QUANTITIES: Final = {
    "peak": ("peak_dte_m", "peak |DTE| (um)", "Peak DTE"),
    "amplitude": ("amplitude_m", "DTE amplitude (um)", "DTE amplitude"),
    "deflection": ("peak_deflection_m", "peak |DTE - e| (um)", "Peak mesh deflection"),
}


def plot_peak_dte_map(
    result: PeakDTEMap,
    *,
    quantity: Literal["peak", "amplitude", "deflection"] = "peak",
    title: str | None = None,
    show_modes: bool = True,
) -> Figure:
    """Peak-DTE maps of both stages over mesh frequency x bulk temperature.

    Parameters
    ----------
    result : PeakDTEMap
    quantity : {"peak", "amplitude", "deflection"}
        Colour by peak ``|DTE|`` (``peak_dte_m``: static deflection included; seed 001's
        "maximum amplitude of the DTE"), by half the peak-to-peak DTE (the vibration alone),
        or by the peak ``|u|``, ``u = DTE - e`` (``peak_deflection_m``, seed 001's state
        variable).
    title : str or None
        Figure title; None gives one naming the sweep direction and the system's two natural
        frequencies at the lowest and highest temperature.
    show_modes : bool
        Draw the two natural frequencies of the mean-stiffness system against temperature
        (``PeakDTEMap.mode_frequency_Hz``, averaged over the frequency columns) as dashed
        white lines: where a stage-1 mesh frequency meets a mode.

    Returns
    -------
    matplotlib.figure.Figure
        Two panels (stage 1 left, stage 2 right), each with its colour bar (um); frequencies
        and temperatures sorted (the map may come from a down-sweep or unsorted axes); cells
        with contact loss hatched ``//`` and outlined (contour at 0.5 of the flag);
        back-side impacts as black dots; diverged points (NaN) as red crosses.
    """
    if not isinstance(result, PeakDTEMap):
        raise ValueError(f"`result` must be a PeakDTEMap, was {type(result).__name__}")
    if quantity not in _QUANTITIES:
        raise ValueError(f"`quantity` must be one of {sorted(_QUANTITIES)}, was {quantity!r}")
    attr, label, name = _QUANTITIES[quantity]
    fo = np.argsort(result.frequency_Hz, kind="stable")
    to = np.argsort(result.temperature_C, kind="stable")
    f, t = result.frequency_Hz[fo], result.temperature_C[to]

    def sort(a: np.ndarray) -> np.ndarray:
        return a[to][:, fo]

    values = sort(getattr(result, attr))
    fe, te = _edges(f) / 1e3, _edges(t)
    fig = Figure(figsize=(_WIDTH_IN, 3.4), layout="constrained")
    FigureCanvasAgg(fig)
    axes = fig.subplots(1, 2, sharey=True)
    modes = result.mode_frequency_Hz
    has_modes = show_modes and modes.shape[:2] == result.peak_dte_m.shape[:2]
    diverged = sort(result.diverged) if result.diverged.shape == values.shape[:2] else None
    jj, ii = np.meshgrid(f / 1e3, t)
    for st, ax in enumerate(axes):
        z = values[:, :, st] * 1e6
        mesh = ax.pcolormesh(fe, te, z, cmap="viridis", shading="flat")
        fig.colorbar(mesh, ax=ax, label=label)
        loss = sort(result.contact_loss)[:, :, st]
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
        back = sort(result.back_contact)[:, :, st]
        if back.any():
            ax.plot(jj[back], ii[back], ".", color="black", markersize=3)
        if diverged is not None and diverged.any():
            ax.plot(jj[diverged], ii[diverged], "x", color="red", markersize=4)
        if has_modes and t.size > 1:
            mode_t = modes[to].mean(axis=1) / 1e3  # (n_t, 2), kHz
            for k in range(2):
                ax.plot(mode_t[:, k], t, "--", color="white", linewidth=0.8)
            ax.set_xlim(fe[0], fe[-1])
        ax.set_title(_STAGE_NAMES[st])
        ax.set_xlabel("stage-1 mesh frequency (kHz)")
    axes[0].set_ylabel("bulk temperature (deg C)")
    handles = [
        Patch(facecolor="none", edgecolor="black", hatch="//", label="contact loss"),
        Patch(facecolor="black", label="back-side impact (dots)"),
    ]
    axes[1].legend(handles=handles, loc="upper right", fontsize="small", framealpha=0.8)
    if title is None:
        title = f"{name}, {result.direction}-sweep"
        if modes.shape[:2] == result.peak_dte_m.shape[:2] and modes.size:
            lo, hi = modes[to[0]].mean(axis=0) / 1e3, modes[to[-1]].mean(axis=0) / 1e3
            title += f" (modes {lo[0]:.2f}/{lo[1]:.2f} kHz at {t[0]:.0f} deg C"
            title += f", {hi[0]:.2f}/{hi[1]:.2f} kHz at {t[-1]:.0f} deg C)" if t.size > 1 else ")"
    fig.suptitle(title)
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

"""The PSDs of a recording's channels with their peaks marked (``rigtools spectrum --plot``).

The presentation layer over :mod:`rigtools.analysis.recording`: :func:`plot_spectrum` takes a
:class:`~rigtools.analysis.recording.RecordingAnalysis` and returns a
:class:`matplotlib.figure.Figure` drawn on the Agg canvas, without ``matplotlib.pyplot`` and
its global state. Nothing here computes: the spectra, the peaks and their kinds come with the
analysis.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from rigtools.analysis.recording import RecordingAnalysis

__all__ = ["plot_spectrum"]

#: Kinds of peak drawn as lines of the gear mesh or the shafts (labelled with their order).
_ORDER_KINDS = ("mesh_harmonic", "shaft_harmonic")


def _order_label(kind: str, harmonic: int | None) -> str:
    if harmonic is None:
        return ""
    return f"{harmonic}x " + ("mesh" if kind == "mesh_harmonic" else "shaft")


def plot_spectrum(analysis: RecordingAnalysis, title: str = "", *,
                  f_range_Hz: Sequence[float] | None = None, db: bool = False) -> Figure:
    """A :class:`matplotlib.figure.Figure` of the PSDs with their peaks marked (Agg canvas).

    Parameters
    ----------
    analysis : RecordingAnalysis
        Per-channel spectra and peaks (:func:`rigtools.analysis.analyse_recording`); channels
        without a spectrum are left out.
    title : str
        Figure title (e.g. the file name).
    f_range_Hz : (float, float), optional
        Frequency range shown (Hz; the upper bound may be ``inf``); default the whole PSD
        without the 0 Hz bin.
    db : bool
        PSD in dB re 1 unit^2/Hz on a linear axis; default the PSD on a logarithmic axis.

    Returns
    -------
    matplotlib.figure.Figure
        One PSD line per channel (unit^2/Hz), labelled with its structural natural
        frequencies and damping ratios (up to three). A triangle marks a mode (a structural
        peak), a dot a mesh or shaft line, labelled with its order once for all channels
        (``2x mesh``), a cross any other line or tone. The legend sits below the axes, so it
        covers no peak.
    """
    fig = Figure(figsize=(7.5, 5.0), layout="constrained")
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    unit = ""
    # order label -> (frequency, level) of its highest marker over the channels
    orders: dict[str, tuple[float, float]] = {}
    lo, hi = (None, None) if f_range_Hz is None else (float(f_range_Hz[0]), float(f_range_Hz[1]))
    for ca in analysis.channels.values():
        spec = ca.spectrum
        if spec is None:
            continue
        unit = spec.psd_unit
        f, p = spec.freq_Hz[1:], spec.psd_per_Hz[1:]
        peaks = ca.peaks.peaks if ca.peaks is not None else ()
        if lo is not None and hi is not None:
            shown_bins = (f >= lo) & (f <= hi)
            f, p = f[shown_bins], p[shown_bins]
            peaks = tuple(pk for pk in peaks if lo <= pk.f_Hz <= hi)
        level = 10 * np.log10(np.maximum(p, np.finfo(float).tiny)) if db else p
        modes = [pk.mode for pk in peaks if pk.mode is not None and pk.kind == "structural"]
        label = ca.name
        if modes:
            shown = ", ".join(f"{m.f_n_Hz:.0f} Hz (ζ {m.zeta:.3f})" for m in modes[:3])
            label += f": f_n {shown}" + (" ..." if len(modes) > 3 else "")
        (line,) = (ax.plot if db else ax.semilogy)(f, level, lw=0.8, label=label)
        color = line.get_color()
        for pk in peaks:
            y = 10 * np.log10(max(pk.psd_per_Hz, np.finfo(float).tiny)) if db else pk.psd_per_Hz
            if pk.kind == "structural":
                ax.plot([pk.f_Hz], [y], "v", color=color, ms=7)
            elif pk.kind in _ORDER_KINDS:
                ax.plot([pk.f_Hz], [y], "o", color=color, ms=4, mfc="none")
                text = _order_label(pk.kind, pk.location.harmonic)
                if text and (text not in orders or y > orders[text][1]):
                    orders[text] = (pk.f_Hz, float(y))
            else:
                ax.plot([pk.f_Hz], [y], "x", color=color, ms=4)
    for text, (fx, fy) in orders.items():
        ax.annotate(text, (fx, fy), xytext=(0, 6), textcoords="offset points", ha="center",
                    va="bottom", fontsize=7, rotation=90)
    ax.set_xlabel("frequency (Hz)")
    if db:
        ax.set_ylabel(f"PSD (dB re 1 {unit})" if unit else "PSD (dB)")
    else:
        ax.set_ylabel(f"PSD ({unit})" if unit else "PSD")
    if lo is not None and hi is not None and np.isfinite(hi):
        ax.set_xlim(lo, hi)
    ax.margins(y=0.12)  # room above the highest peak for its order label
    ax.grid(True, which="both", lw=0.3, alpha=0.5)
    if ax.lines:
        n = sum(1 for ca in analysis.channels.values() if ca.spectrum is not None)
        fig.legend(fontsize=8, loc="outside lower center", ncols=1 if n < 3 else 2)
    marks = "▼ mode, ○ mesh or shaft line (order), × other line or tone"
    ax.set_title(f"{title}  ({marks})" if title else marks, fontsize=9)
    return fig

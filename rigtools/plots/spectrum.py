"""The PSDs of a recording's channels with their peaks marked (``rigtools spectrum --plot``).

The presentation layer over :mod:`rigtools.analysis.recording`: :func:`plot_spectrum` takes a
:class:`~rigtools.analysis.recording.RecordingAnalysis` and returns a
:class:`matplotlib.figure.Figure` drawn on the Agg canvas, without ``matplotlib.pyplot`` and
its global state. Nothing here computes: the spectra, the peaks and their kinds come with the
analysis.
"""

from __future__ import annotations

from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from rigtools.analysis.recording import RecordingAnalysis

__all__ = ["plot_spectrum"]


def plot_spectrum(analysis: RecordingAnalysis, title: str = "") -> Figure:
    """A :class:`matplotlib.figure.Figure` of the PSDs with their peaks marked (Agg canvas).

    Parameters
    ----------
    analysis : RecordingAnalysis
        Per-channel spectra and peaks (:func:`rigtools.analysis.analyse_recording`); channels
        without a spectrum are left out.
    title : str
        Figure title (e.g. the file name).

    Returns
    -------
    matplotlib.figure.Figure
        One log-PSD line per channel (unit^2/Hz, the 0 Hz bin left out), labelled with its
        structural natural frequencies and damping ratios (up to three); a triangle marks a
        resonance (a structural peak, or a broad peak on a mesh or shaft line), a cross a
        line or tone.
    """
    fig = Figure(figsize=(7.0, 4.2), layout="constrained")
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    unit = ""
    for ca in analysis.channels.values():
        spec = ca.spectrum
        if spec is None:
            continue
        unit = spec.psd_unit
        f, p = spec.freq_Hz[1:], spec.psd_per_Hz[1:]
        peaks = ca.peaks.peaks if ca.peaks is not None else ()
        modes = [pk.mode for pk in peaks if pk.mode is not None
                 and (pk.kind == "structural" or pk.possible_resonance)]
        label = ca.name
        if modes:
            shown = ", ".join(f"{m.f_n_Hz:.0f} Hz (ζ {m.zeta:.3f})" for m in modes[:3])
            label += f": f_n {shown}" + (" ..." if len(modes) > 3 else "")
        (line,) = ax.semilogy(f, p, lw=0.8, label=label)
        for pk in peaks:
            structural = pk.kind == "structural" or pk.possible_resonance
            ax.plot([pk.f_Hz], [pk.psd_per_Hz], "v" if structural else "x",
                    color=line.get_color(), ms=7 if structural else 4)
    ax.set_xlabel("frequency (Hz)")
    ax.set_ylabel(f"PSD ({unit})" if unit else "PSD")
    ax.grid(True, which="both", lw=0.3, alpha=0.5)
    if ax.lines:
        ax.legend(fontsize=8, loc="upper right")
    ax.set_title(title + "  (▼ resonance, × line or tone)" if title else
                 "▼ resonance, × line or tone", fontsize=9)
    return fig

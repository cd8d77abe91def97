"""The report's own figures: the verdict at a glance and each run's spectrum.

matplotlib :class:`~matplotlib.figure.Figure` objects (no pyplot state), drawn from the
report.json content (so the figure shows the numbers the document holds) and the spectra.
:func:`png_base64` turns one into the base64 PNG the page embeds. Labels from recordings and
campaigns are drawn as plain text (mathtext's ``$`` escaped) inside the raster: nothing of them
reaches the page's markup.
"""

from __future__ import annotations

import base64
import io
from collections.abc import Mapping
from typing import Any, Final

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from rigtools.report.inputs import RunSpectra

__all__ = ["REGIME_COLOURS", "label", "png_base64", "spectrum_figure", "verdict_figure"]

#: Colour of each regime (chips on the page use the same).
REGIME_COLOURS: Final[dict[str, str]] = {"rises": "#1a7f37", "falls": "#c62828",
                                         "unchanged": "#b7791f"}
_OTHER: Final = "#6b7280"
_CHANNEL_COLOURS: Final = ("#1f77b4", "#ff7f0e", "#2ca02c", "#9467bd", "#8c564b", "#e377c2",
                           "#7f7f7f", "#bcbd22", "#17becf", "#d62728")
_MAX_LABEL: Final = 40


def label(text: Any) -> str:
    """``text`` as a matplotlib label shown literally (``$`` escaped, at most 40 characters)."""
    s = str(text)
    if len(s) > _MAX_LABEL:
        s = s[: _MAX_LABEL - 1] + "\N{HORIZONTAL ELLIPSIS}"
    return s.replace("\\", "\\\\").replace("$", r"\$")


def png_base64(fig: Figure, *, dpi: float = 100) -> str:
    """The figure as a base64-encoded PNG (ASCII), through the Agg canvas."""
    FigureCanvasAgg(fig)
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=dpi, metadata={"Software": None})
    return base64.b64encode(buf.getvalue()).decode("ascii")


def _interval(ax: Any, y: float, q: Mapping[str, Any] | None, colour: str) -> None:
    if not q or q.get("q05") is None or q.get("q95") is None:
        return
    ax.plot([q["q05"], q["q95"]], [y, y], color=colour, lw=2.5, solid_capstyle="butt")
    mid = q.get("q50") if q.get("q50") is not None else q.get("mean")
    if mid is not None:
        ax.plot([mid], [y], "o", color=colour, ms=6)


def verdict_figure(verdict: Mapping[str, Any]) -> Figure | None:
    """Backlash and critical gap against temperature, and the margin of every run.

    Parameters
    ----------
    verdict : mapping
        The ``verdict`` section of report.json.

    Returns
    -------
    matplotlib.figure.Figure or None
        None when there is no calibration.
    """
    if not verdict.get("available"):
        return None
    runs = [r for r in verdict.get("runs", []) if r.get("margin_um")]
    fig = Figure(figsize=(11.0, max(2.6, 0.42 * len(runs) + 1.3)), layout="constrained")
    ax_t, ax_m = fig.subplots(1, 2, width_ratios=(1.0, 1.25))
    gaps = verdict.get("critical_gaps", [])
    c = verdict.get("backlash_um")
    if gaps:
        t = np.array([g["temperature_C"] for g in gaps], dtype=float)
        q = [g["critical_gap_um"] for g in gaps]
        lo = np.array([np.nan if x["q05"] is None else x["q05"] for x in q], dtype=float)
        hi = np.array([np.nan if x["q95"] is None else x["q95"] for x in q], dtype=float)
        mid = np.array([np.nan if x["q50"] is None else x["q50"] for x in q], dtype=float)
        ax_t.fill_between(t, lo, hi, color="#c62828", alpha=0.2, lw=0,
                          label="c*(θ), 90 % interval")
        ax_t.plot(t, mid, "o-", color="#c62828", label="c*(θ), median")
    if c and c.get("q05") is not None and c.get("q95") is not None:
        ax_t.axhspan(c["q05"], c["q95"], color="#1f77b4", alpha=0.18, lw=0,
                     label="backlash c, 90 % interval")
        if c.get("q50") is not None:
            ax_t.axhline(c["q50"], color="#1f77b4", lw=1.5, label="backlash c, median")
    flip = verdict.get("flip_temperature_C")
    if flip and flip.get("q50") is not None:
        ax_t.axvline(flip["q50"], color="#374151", ls="--", lw=1, label="flip temperature")
    ax_t.set_xlabel("bulk temperature (°C)")
    ax_t.set_ylabel("gap (µm)")
    ax_t.set_title("backlash and critical gap", fontsize=10)
    ax_t.legend(fontsize=7, loc="upper left")
    ax_t.grid(alpha=0.3)
    for i, r in enumerate(runs):
        colour = REGIME_COLOURS.get(r.get("regime") or "", _OTHER)
        _interval(ax_m, float(i), r["margin_um"], colour)
    ax_m.axvline(0.0, color="#111827", lw=1)
    ax_m.set_yticks(range(len(runs)), [label(r["run_id"]) for r in runs], fontsize=8)
    ax_m.set_ylim(len(runs) - 0.5, -0.5)
    ax_m.set_xlabel("margin c − c* (µm): median and 90 % interval")
    ax_m.set_title("margin per run (green: c > c*, stiffness rises; red: c < c*)", fontsize=10)
    ax_m.grid(alpha=0.3, axis="x")
    return fig


def spectrum_figure(run: Mapping[str, Any], spectra: RunSpectra) -> Figure:
    """One run's PSD per channel with the peaks found and the peak taken as the mesh mode.

    Parameters
    ----------
    run : mapping
        The run's entry of report.json ``runs`` (peaks, mesh mode, predicted frequency).
    spectra : RunSpectra

    Returns
    -------
    matplotlib.figure.Figure
    """
    # Fixed margins: a constrained layout measures every log-axis tick label (seconds per page).
    fig = Figure(figsize=(11.0, 3.6))
    fig.subplots_adjust(left=0.075, right=0.99, bottom=0.14, top=0.97)
    ax = fig.subplots()
    colours = {ch: _CHANNEL_COLOURS[i % len(_CHANNEL_COLOURS)]
               for i, ch in enumerate(spectra.channels)}
    units = {u for u in spectra.units.values() if u}
    for ch, (f, psd) in spectra.channels.items():
        ok = np.isfinite(f) & np.isfinite(psd) & (psd > 0)
        if ok.any():
            ax.semilogy(f[ok], psd[ok], lw=0.8, color=colours[ch], label=label(ch))
    pred = run.get("predicted_f_n_Hz") or {}
    if pred.get("q05") is not None and pred.get("q95") is not None:
        ax.axvspan(pred["q05"], pred["q95"], color="#9ca3af", alpha=0.25, lw=0,
                   label="predicted f_n, 90 %")
    for p in run.get("peaks", []):
        f_n, ch = p.get("f_n_Hz"), p.get("channel")
        if f_n is None or ch not in spectra.channels:
            continue
        f, psd = spectra.channels[ch]
        ok = np.isfinite(f) & np.isfinite(psd) & (psd > 0)
        if not ok.any():
            continue
        level = float(np.interp(f_n, f[ok], psd[ok]))
        if p.get("mesh_mode"):
            ax.plot([f_n], [level], marker="*", ms=16, color="#c62828", mec="black", mew=0.6,
                    ls="none", zorder=5, label="taken as mesh mode")
            ax.axvline(f_n, color="#c62828", lw=0.8, ls=":")
        else:
            ax.plot([f_n], [level], marker="v", ms=7, color=colours[ch], mec="black", mew=0.5,
                    ls="none", zorder=4)
    ax.plot([], [], marker="v", ms=7, color="white", mec="black", ls="none", label="peaks found")
    ax.set_xlabel("frequency (Hz)")
    ax.set_ylabel("PSD (" + label(units.pop()) + ")" if len(units) == 1 else "PSD")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7, loc="upper right", ncols=2)
    return fig

r"""Figures of a calibration: corner plot, traces, f_n and stiffness against torque.

Result objects in, :class:`matplotlib.figure.Figure` out, drawn on the Agg canvas; nothing
touches ``matplotlib.pyplot`` or ``rcParams``. The numbers come from
:mod:`rigtools.calibration` (:func:`~rigtools.calibration.curves.predictive_curves` for the
bands); nothing here computes physics.

* :func:`plot_corner`: pairwise posterior of the sampled parameters (``corner``), truths
  optional.
* :func:`plot_traces`: every walker's chain per parameter, the discarded burn-in shaded.
* :func:`plot_frequency_vs_torque`: one panel per campaign temperature: the posterior median
  of the predicted mesh-mode frequency, its 90 % band, the 90 % band of a new measurement,
  the peak chosen as the mesh mode in every run with its fit sd as error bars, and every
  other candidate peak as a grey dot (a housing mode shows as a row of dots at one
  frequency); torque ranges where more than half the draws are jammed are hatched.
* :func:`plot_stiffness_vs_torque`: left, the cycle-mean mesh stiffness against torque per
  temperature (median and 90 % band) with the elastic ``s k_m`` (what the stiffness equals
  at ``c = c*``); right, the backlash and the critical gap ``c*(theta)`` at the campaign
  temperatures (median and 90 % intervals): where the ``c*`` interval lies below the
  backlash the stiffness rises with load, above it falls (seed 000 Table 5).
* :func:`calibration_figures`: all four for a result, written as PNGs into a folder.
"""

from __future__ import annotations

from pathlib import Path
from typing import Final

import corner
import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from rigtools.calibration.curves import PredictiveCurves, predictive_curves
from rigtools.calibration.result import CalibrationResult, VariantFit
from rigtools.plots.stiffness import FIGURE_WIDTH_IN, save_png

__all__ = [
    "calibration_figures",
    "plot_corner",
    "plot_frequency_vs_torque",
    "plot_stiffness_vs_torque",
    "plot_traces",
]

#: Colour-blind-safe colours (Okabe and Ito 2008), one per temperature.
_COLOURS: Final = ("#0072B2", "#D55E00", "#009E73", "#CC79A7", "#E69F00", "#56B4E9")
_LABELS: Final = {"backlash": "backlash c (um)", "closure_coefficient": "closure coeff. (-)",
                  "stiffness_scale": "stiffness scale s (-)", "model_error": "model error (-)",
                  "chi": "chi (-)"}


def _figure(width: float, height: float) -> Figure:
    fig = Figure(figsize=(width, height))
    FigureCanvasAgg(fig)
    return fig


def _label(name: str) -> str:
    return _LABELS.get(name, name)


def plot_corner(fit: VariantFit, *, truths: dict[str, float] | None = None,
                max_draws: int = 20000) -> Figure:
    """Corner plot of the sampled global parameters of a fit.

    Parameters
    ----------
    fit : VariantFit
    truths : dict, optional
        Parameter name -> value to mark (synthetic campaigns).
    max_draws : int
        Draws plotted (evenly spaced).

    Returns
    -------
    matplotlib.figure.Figure
    """
    names = [n for n in fit.model.names if "@" not in n]
    idx = [fit.model.names.index(n) for n in names]
    flat = fit.samples.reshape(-1, fit.samples.shape[-1])[:, idx]
    flat = flat[np.linspace(0, flat.shape[0] - 1, min(max_draws, flat.shape[0])).astype(int)]
    fig = _figure(FIGURE_WIDTH_IN, FIGURE_WIDTH_IN)
    corner.corner(flat, fig=fig, labels=[_label(n) for n in names],
                  quantiles=[0.05, 0.5, 0.95], show_titles=True, title_fmt=".3g",
                  truths=None if truths is None else [truths.get(n) for n in names],
                  label_kwargs={"fontsize": 8}, title_kwargs={"fontsize": 7})
    fig.suptitle(f"posterior ({fit.variant})", fontsize=9)
    return fig


def plot_traces(fit: VariantFit) -> Figure:
    """Every walker's chain per sampled global parameter, burn-in shaded."""
    names = [n for n in fit.model.names if "@" not in n]
    fig = _figure(FIGURE_WIDTH_IN, 1.4 * len(names) + 0.6)
    axes = fig.subplots(len(names), 1, sharex=True, squeeze=False)[:, 0]
    chain = fit.run.chain
    steps = np.arange(chain.shape[0])
    for ax, n in zip(axes, names, strict=True):
        i = fit.model.names.index(n)
        ax.plot(steps, chain[:, :, i], lw=0.3, alpha=0.5, color="k")
        ax.axvspan(0, fit.run.burn_in, color="0.85", zorder=0)
        ax.set_ylabel(_label(n), fontsize=7)
        ax.tick_params(labelsize=7)
    axes[-1].set_xlabel("step", fontsize=8)
    axes[0].set_title(f"{fit.variant}: {chain.shape[1]} walkers, {chain.shape[0]} steps, "
                      f"burn-in {fit.run.burn_in} (shaded), thin {fit.run.thin}, "
                      f"max tau {np.max(fit.run.tau):.3g}"
                      + ("" if fit.converged else " - NOT CONVERGED"), fontsize=8)
    fig.tight_layout()
    return fig


def plot_frequency_vs_torque(curves: PredictiveCurves) -> Figure:
    """Predicted mesh-mode frequency against torque per temperature, measured peaks on top."""
    k = curves.temperature_C.size
    fig = _figure(FIGURE_WIDTH_IN, 2.6 * k + 0.6)
    axes = fig.subplots(k, 1, sharex=True, squeeze=False)[:, 0]
    t = curves.torque_Nm
    for i, (ax, temp) in enumerate(zip(axes, curves.temperature_C, strict=True)):
        col = _COLOURS[i % len(_COLOURS)]
        ax.fill_between(t, curves.f_n_new_Hz[0, i], curves.f_n_new_Hz[1, i], color=col,
                        alpha=0.15, lw=0, label="90 % new measurement")
        ax.fill_between(t, curves.f_n_Hz[0, i], curves.f_n_Hz[2, i], color=col, alpha=0.35,
                        lw=0, label="90 % model")
        ax.plot(t, curves.f_n_Hz[1, i], color=col, lw=1.2, label="posterior median")
        jam = curves.jammed_fraction[i] > 0.5
        if jam.any():
            ax.fill_between(t, 0, 1, where=jam, transform=ax.get_xaxis_transform(),
                            hatch="////", facecolor="none", edgecolor="0.5", lw=0,
                            label="jammed (most draws)")
        at = np.isclose(curves.candidate_temperature_C, temp)
        ax.plot(curves.candidate_torque_Nm[at], curves.candidate_f_n_Hz[at], ".",
                color="0.6", ms=3, label="other peaks")
        run = np.isclose(curves.run_temperature_C, temp) & np.isfinite(curves.run_f_n_Hz)
        ax.errorbar(curves.run_torque_Nm[run], curves.run_f_n_Hz[run],
                    yerr=curves.run_f_n_std_Hz[run], fmt="o", ms=4, color="k", capsize=2,
                    label="chosen mesh-mode peak (1 sd)")
        ax.set_ylabel("f_n (Hz)", fontsize=8)
        ax.set_title(f"{temp:g} degC", fontsize=8)
        ax.tick_params(labelsize=7)
        ax.set_xscale("log")
    axes[0].legend(fontsize=6, loc="lower right", ncol=2)
    axes[-1].set_xlabel("pinion torque (N m)", fontsize=8)
    fig.suptitle(f"mesh natural frequency against torque ({curves.variant})", fontsize=9)
    fig.tight_layout()
    return fig


def plot_stiffness_vs_torque(curves: PredictiveCurves) -> Figure:
    """Mesh stiffness against torque per temperature, and c against c*(theta)."""
    fig = _figure(FIGURE_WIDTH_IN, 3.4)
    ax, bx = fig.subplots(1, 2, gridspec_kw={"width_ratios": [2.0, 1.0]})
    t = curves.torque_Nm
    for k, temp in enumerate(curves.temperature_C):
        col = _COLOURS[k % len(_COLOURS)]
        ax.fill_between(t, curves.k_mean_N_per_m[0, k] / 1e6, curves.k_mean_N_per_m[2, k] / 1e6,
                        color=col, alpha=0.3, lw=0)
        ax.plot(t, curves.k_mean_N_per_m[1, k] / 1e6, color=col, lw=1.2, label=f"{temp:g} degC")
    ke = curves.k_elastic_N_per_m / 1e6
    ax.axhspan(ke[0], ke[2], color="k", alpha=0.1, lw=0)
    ax.axhline(ke[1], color="k", lw=0.8, ls="--", label="s k_m (c = c*)")
    ax.set_xscale("log")
    ax.set_xlabel("pinion torque (N m)", fontsize=8)
    ax.set_ylabel("mean mesh stiffness (N/um)", fontsize=8)
    ax.tick_params(labelsize=7)
    ax.legend(fontsize=6)
    x = np.arange(curves.temperature_C.size)
    c = curves.backlash_um
    bx.axhspan(c[0], c[2], color="k", alpha=0.15, lw=0)
    bx.axhline(c[1], color="k", lw=1.0, label="backlash c")
    cs = curves.critical_gap_um
    for i in range(x.size):
        bx.errorbar([i], [cs[1, i]], yerr=[[cs[1, i] - cs[0, i]], [cs[2, i] - cs[1, i]]],
                    fmt="s", color=_COLOURS[i % len(_COLOURS)], capsize=3)
    bx.set_xticks(x, [f"{v:g}" for v in curves.temperature_C])
    bx.set_xlabel("bulk temperature (degC)", fontsize=8)
    bx.set_ylabel("c and c* (um), 90 %", fontsize=8)
    bx.tick_params(labelsize=7)
    bx.legend(fontsize=6)
    bx.set_title("c* below c: rises; above: falls", fontsize=7)
    fig.suptitle(f"mesh stiffness against torque, critical gap marked ({curves.variant})",
                 fontsize=9)
    fig.tight_layout()
    return fig


def calibration_figures(result: CalibrationResult, outdir: str | Path, *,
                        truths: dict[str, float] | None = None) -> dict[str, Path]:
    """Draw the four figures of the headline fit and write them as PNGs.

    Parameters
    ----------
    result : CalibrationResult
    outdir : str or pathlib.Path
    truths : dict, optional
        Marked on the corner plot.

    Returns
    -------
    dict
        Figure name -> path (``corner.png``, ``traces.png``, ``f_n_vs_torque.png``,
        ``stiffness_vs_torque.png``).
    """
    out = Path(outdir)
    fit = result.headline
    curves = predictive_curves(fit, seed=result.config.seed)
    figs = {"corner": plot_corner(fit, truths=truths), "traces": plot_traces(fit),
            "f_n_vs_torque": plot_frequency_vs_torque(curves),
            "stiffness_vs_torque": plot_stiffness_vs_torque(curves)}
    return {name: save_png(f, out / f"{name}.png", dpi=120) for name, f in figs.items()}

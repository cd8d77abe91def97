r"""Figure of a run-up calibration: measured Arms against mesh frequency with each model's band.

One figure per run (``calibration/runup/runup_<run>.png``), drawn on the Agg canvas from plain
arrays (:class:`RunUpFigureData`); nothing here computes physics, the numbers are those of the
run-up calibration (:mod:`rigtools.calibration.runup_api`).

Layout: one panel per accelerometer channel, stacked and sharing the mesh-frequency axis, each
with a logarithmic Arms axis. Every channel gets a full panel rather than one main channel
with the others small: the channels have their own gains (a factor of several between housing
directions), so their curves cannot share one axis, and each carries the same information on
the resonance and the jumps, so none is secondary.

In each panel:

* measured Arms (``arms_m_s2`` of the observation rows): run-up windows as upward triangles,
  run-down windows as downward triangles, hold windows as dots;
* for each model, the 90 % posterior predictive band (5 % to 95 %) and its median, drawn
  separately along the up branch (solid median) and the down branch (dashed median), so the
  hysteresis between the branches shows;
* the measured jump frequencies as black vertical lines (solid: jump up, during the run-up;
  dashed: jump down, during the run-down) and each model's jump frequencies as its median
  (marker) and 90 % interval (bar) in a strip along the top of the panel (upward triangle for
  the run-up jump, downward for the run-down jump).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Final

import numpy as np
from matplotlib.axes import Axes
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.transforms import blended_transform_factory

from rigtools.plots.stiffness import FIGURE_WIDTH_IN, save_png

__all__ = [
    "MODEL_COLOURS",
    "RunUpBand",
    "RunUpFigureData",
    "figure_file_name",
    "plot_runup",
    "write_runup_figures",
]

#: Colour of each SDOF model (Okabe and Ito 2008), the same in every figure.
MODEL_COLOURS: Final[dict[str, str]] = {"fvms": "#D55E00", "vvms": "#0072B2",
                                        "lste": "#009E73", "itms": "#CC79A7"}
_OTHER_COLOURS: Final = ("#E69F00", "#56B4E9", "#999933", "#882255")
_PANEL_HEIGHT_IN: Final = 2.5
#: Title and legend above the panels (in).
_HEADER_IN: Final = 1.35
_MAX_LABEL: Final = 40
_DIRECTIONS: Final = ("up", "down")


def _text(s: Any) -> str:
    """A label shown literally (mathtext ``$`` escaped), at most 40 characters."""
    t = str(s)
    if len(t) > _MAX_LABEL:
        t = t[: _MAX_LABEL - 1] + "\N{HORIZONTAL ELLIPSIS}"
    return t.replace("\\", "\\\\").replace("$", r"\$")


@dataclass(frozen=True, eq=False)
class RunUpBand:
    """One model's posterior predictive along one run's mesh-frequency path.

    Attributes
    ----------
    model : str
        ``"fvms"``, ``"vvms"``, ``"lste"`` (any name is drawn).
    arms_quantiles_m_s2 : numpy.ndarray
        ``(3, C, N)``: the 5 %, 50 % and 95 % quantiles of the predicted Arms (m/s^2) of each
        channel at each point of the path (NaN where the model gives none).
    jump_up_Hz, jump_down_Hz : numpy.ndarray
        ``(3,)``: 5 %, 50 % and 95 % quantiles of the model's jump frequency (Hz) during the
        run-up and the run-down; NaN where the draws have no jump.
    """

    model: str
    arms_quantiles_m_s2: np.ndarray
    jump_up_Hz: np.ndarray = field(default_factory=lambda: np.full(3, np.nan))
    jump_down_Hz: np.ndarray = field(default_factory=lambda: np.full(3, np.nan))


@dataclass(frozen=True, eq=False)
class RunUpFigureData:
    """What the figure of one run shows.

    Attributes
    ----------
    run_id : str
    channels : tuple of str
        ``C`` channel names, in panel order.
    mesh_frequency_Hz : numpy.ndarray
        ``(N,)`` mesh frequency of each point of the path (Hz), in time order.
    direction : numpy.ndarray
        ``(N,)`` ``"up"``, ``"down"`` or ``"hold"`` per point.
    observed_m_s2 : numpy.ndarray
        ``(C, N)`` measured Arms (m/s^2); NaN where not observed (bridging points, failed rows).
    bands : tuple of RunUpBand
        One per model, in legend order.
    measured_jump_up_Hz, measured_jump_down_Hz : float or None
        Jump frequencies of the measured curve (Hz), None where there is none.
    torque_Nm : float or None
        Shown in the title.
    """

    run_id: str
    channels: tuple[str, ...]
    mesh_frequency_Hz: np.ndarray
    direction: np.ndarray
    observed_m_s2: np.ndarray
    bands: tuple[RunUpBand, ...] = ()
    measured_jump_up_Hz: float | None = None
    measured_jump_down_Hz: float | None = None
    torque_Nm: float | None = None


def _check(data: RunUpFigureData) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    f = np.asarray(data.mesh_frequency_Hz, dtype=float)
    if f.ndim != 1 or f.size == 0:
        raise ValueError(f"`mesh_frequency_Hz` must be a non-empty 1-D array, was shape "
                         f"{f.shape}")
    d = np.asarray(data.direction).astype(str)
    if d.shape != f.shape:
        raise ValueError(f"`direction` must have the shape of `mesh_frequency_Hz` {f.shape}, "
                         f"was {d.shape}")
    obs = np.asarray(data.observed_m_s2, dtype=float)
    want = (len(data.channels), f.size)
    if obs.shape != want:
        raise ValueError(f"`observed_m_s2` must have the shape (channels, points) = {want}, "
                         f"was {obs.shape}")
    for b in data.bands:
        q = np.asarray(b.arms_quantiles_m_s2)
        if q.shape != (3, *want):
            raise ValueError(f"`arms_quantiles_m_s2` of model {b.model!r} must have the shape "
                             f"(3, channels, points) = {(3, *want)}, was {q.shape}")
    return f, d, obs


def _branch_of(direction: np.ndarray) -> np.ndarray:
    """Up or down for every point: a hold point belongs to the branch before it."""
    out = np.empty(direction.shape, dtype=object)
    current = "up"
    for i, d in enumerate(direction):
        if d in _DIRECTIONS:
            current = str(d)
        out[i] = current
    return out


def _segments(branch: np.ndarray) -> list[tuple[str, np.ndarray]]:
    """Contiguous runs of one branch: (branch, indices)."""
    out: list[tuple[str, np.ndarray]] = []
    start = 0
    for i in range(1, branch.size + 1):
        if i == branch.size or branch[i] != branch[start]:
            out.append((str(branch[start]), np.arange(start, i)))
            start = i
    return out


def _colour(model: str, i: int) -> str:
    return MODEL_COLOURS.get(model, _OTHER_COLOURS[i % len(_OTHER_COLOURS)])


def _finite(x: float | None) -> bool:
    return x is not None and bool(np.isfinite(x))


def _draw_bands(ax: Axes, f: np.ndarray, segments: list[tuple[str, np.ndarray]],
                band: RunUpBand, c: int, colour: str) -> None:
    q = np.asarray(band.arms_quantiles_m_s2, dtype=float)[:, c, :]
    labelled = False
    for branch, idx in segments:
        order = idx[np.argsort(f[idx], kind="stable")]
        x = f[order]
        lo, mid, hi = q[0, order], q[1, order], q[2, order]
        ok = np.isfinite(lo) & np.isfinite(hi) & (lo > 0) & (hi > 0)
        if ok.any():
            ax.fill_between(x, np.where(ok, lo, np.nan), np.where(ok, hi, np.nan),
                            color=colour, alpha=0.18, lw=0,
                            label=None if labelled else f"{_text(band.model)}: 90 % band",
                            gid=f"band/{band.model}/{branch}")
        ls = "-" if branch == "up" else "--"
        ax.plot(x, np.where(np.isfinite(mid) & (mid > 0), mid, np.nan), ls=ls, lw=1.1,
                color=colour, gid=f"median/{band.model}/{branch}",
                label=None if labelled else f"{_text(band.model)}: median (up solid, "
                                            "down dashed)")
        labelled = True


def _draw_jumps(ax: Axes, data: RunUpFigureData, colours: Sequence[str]) -> None:
    for value, ls, name in ((data.measured_jump_up_Hz, "-", "up"),
                            (data.measured_jump_down_Hz, "--", "down")):
        if value is not None and _finite(value):
            ax.axvline(float(value), color="black", lw=0.9, ls=ls, gid=f"jump/measured/{name}",
                       label=f"measured jump {name}")
    strip = blended_transform_factory(ax.transData, ax.transAxes)
    n = max(len(data.bands), 1)
    for i, (band, colour) in enumerate(zip(data.bands, colours, strict=True)):
        for j, (q, marker, name) in enumerate(((band.jump_up_Hz, "^", "up"),
                                               (band.jump_down_Hz, "v", "down"))):
            qq = np.asarray(q, dtype=float).reshape(-1)
            if qq.size != 3 or not np.isfinite(qq[1]):
                continue
            y = 0.96 - 0.045 * (j * n + i)
            if np.isfinite(qq[0]) and np.isfinite(qq[2]):
                ax.plot([qq[0], qq[2]], [y, y], color=colour, lw=2.0, transform=strip,
                        solid_capstyle="butt", gid=f"jump/{band.model}/{name}/interval")
            ax.plot([qq[1]], [y], marker=marker, ms=6, color=colour, mec="black", mew=0.5,
                    ls="none", transform=strip, gid=f"jump/{band.model}/{name}")


def plot_runup(data: RunUpFigureData) -> Figure:
    """Measured Arms against mesh frequency with every model's predictive band (module notes).

    Parameters
    ----------
    data : RunUpFigureData

    Returns
    -------
    matplotlib.figure.Figure
        ``FIGURE_WIDTH_IN`` wide, on the Agg canvas; ``fig.axes`` holds one panel per channel,
        top to bottom. Artists carry a ``gid``: ``"measured/<direction>"`` (markers),
        ``"band/<model>/<branch>"`` and ``"median/<model>/<branch>"`` (``branch`` up or
        down), ``"jump/measured/<up|down>"`` (vertical lines) and ``"jump/<model>/<up|down>"``
        (median marker; ``.../interval`` its 90 % bar).

    Raises
    ------
    ValueError
        Arrays of inconsistent shapes (the argument and the shapes named).
    """
    f, direction, obs = _check(data)
    n_ch = max(len(data.channels), 1)
    fig = Figure(figsize=(FIGURE_WIDTH_IN, _PANEL_HEIGHT_IN * n_ch + _HEADER_IN + 0.45))
    FigureCanvasAgg(fig)
    axes = fig.subplots(n_ch, 1, sharex=True, squeeze=False)[:, 0]
    branch = _branch_of(direction)
    segments = _segments(branch)
    colours = [_colour(b.model, i) for i, b in enumerate(data.bands)]
    markers = {"up": ("^", "up (run-up)"), "down": ("v", "down (run-down)"),
               "hold": ("o", "hold")}
    for c, ax in enumerate(axes):
        for band, colour in zip(data.bands, colours, strict=True):
            if c < len(data.channels):
                _draw_bands(ax, f, segments, band, c, colour)
        if c < len(data.channels):
            y = obs[c]
            for d, (marker, lab) in markers.items():
                sel = (direction == d) & np.isfinite(y) & (y > 0)
                if sel.any():
                    ax.plot(f[sel], y[sel], marker=marker, ms=4, ls="none", color="#333333",
                            mfc="white" if d == "down" else "#333333", mew=0.7,
                            gid=f"measured/{d}", label=f"measured {lab}", zorder=4)
            ax.set_title(f"channel {_text(data.channels[c])}", fontsize=8)
        _draw_jumps(ax, data, colours)
        ax.set_yscale("log")
        lo, hi = ax.get_ylim()
        if data.bands and 0 < lo < hi:  # headroom for the strip of modelled jumps
            ax.set_ylim(lo, hi * (hi / lo) ** 0.3)
        ax.set_ylabel("Arms (m/s²)", fontsize=8)
        ax.tick_params(labelsize=7)
        ax.grid(alpha=0.3, which="both", lw=0.4)
    axes[-1].set_xlabel("mesh frequency f_m (Hz)", fontsize=8)
    if any(np.isfinite(np.asarray(q, dtype=float)).any() for b in data.bands
           for q in (b.jump_up_Hz, b.jump_down_Hz)):
        axes[0].plot([], [], marker="^", ms=6, color="white", mec="black", ls="-", lw=2.0,
                     label="modelled jump up ▲ / down ▼ (median, 90 % bar)")
    handles, labels = axes[0].get_legend_handles_labels()
    height = fig.get_figheight()
    if handles:  # above the panels, where it hides no data
        fig.legend(handles, labels, fontsize=6, loc="upper center", ncol=3, frameon=False,
                   bbox_to_anchor=(0.5, 1.0 - 0.5 / height))
    torque = (f", {data.torque_Nm:g} N m" if data.torque_Nm is not None
              and _finite(data.torque_Nm) else "")
    fig.suptitle(f"run {_text(data.run_id)}{torque}: measured Arms and each model's 90 % "
                 "posterior predictive band; jumps: measured (black lines), modelled (top "
                 "strip, median and 90 %)", fontsize=8, wrap=True)
    # Fixed margins: a tight layout measures every log-axis tick label (seconds per figure).
    fig.subplots_adjust(left=0.1, right=0.98, bottom=0.45 / height,
                        top=1.0 - _HEADER_IN / height, hspace=0.35)
    return fig


def figure_file_name(run_id: str) -> str:
    """``runup_<run>.png`` with every character outside ``[A-Za-z0-9._-]`` replaced by ``_``.

    Examples
    --------
    >>> figure_file_name("ramp 340 N·m")
    'runup_ramp_340_N_m.png'
    """
    safe = "".join(ch if (ch.isascii() and (ch.isalnum() or ch in "._-")) else "_"
                   for ch in run_id)
    return f"runup_{safe}.png"


def write_runup_figures(figures: Sequence[RunUpFigureData], outdir: str | Path, *,
                        file_name: Callable[[str], str] = figure_file_name,
                        dpi: float = 120) -> dict[str, Path]:
    """Draw the figure of every run and write it into ``outdir``.

    Parameters
    ----------
    figures : sequence of RunUpFigureData
    outdir : str or pathlib.Path
        An existing folder.
    file_name : callable
        Run id -> file name (default :func:`figure_file_name`; the pipeline names the files
        ``runup_<stem>.png`` after its run stems, which the report reads from
        ``pipeline.json``).
    dpi : float

    Returns
    -------
    dict
        Run id -> path of its PNG.
    """
    out = Path(outdir)
    return {d.run_id: save_png(plot_runup(d), out / file_name(d.run_id), dpi=dpi)
            for d in figures}

r"""Figures of the thermoelastic mesh stiffness and the mesh natural frequency against torque.

The presentation layer over :mod:`models.thermal` (seed 000, FZG-C): functions here take the
:class:`~models.thermal.NaturalFrequency` result of
:func:`~models.thermal.mesh_natural_frequency` (one row per backlash, one column per torque)
and return :class:`matplotlib.figure.Figure` objects drawn on the Agg canvas. Nothing touches
``matplotlib.pyplot`` or ``rcParams``, and importing this module changes no global state.

* :func:`plot_stiffness_vs_load` draws the cycle-mean thermoelastic mesh stiffness ``k_mean``
  against the pinion torque, one line per total backlash ``c``; the line at the critical
  compensation gap ``c = c*`` is drawn black and labelled (flat at the elastic ``k_EP`` mean).
  Where the gears are jammed by thermal growth (``c < c*`` at low torque: Eq. (1) of
  :mod:`models.thermal.thermoelastic` undefined) nothing is drawn: the torque range is shaded
  in the colour of its backlash, hatched, and bounded by a dotted line at the jam boundary,
  where Eq. (1) diverges.
* :func:`plot_natural_frequency_vs_load` draws ``f_n = sqrt(k_mean / m_e) / (2 pi)`` in the
  same way, with the torques of seed 000 Table 6 marked as ticks on the top axis and faint
  vertical lines.
* :func:`thermal_figures` draws both for a shipped gear set (FZG-C by default) from
  :func:`models.thermal.thermal_sweep`, with the thermal closure ``Delta_1 + Delta_2`` of seed
  000's hot state read from temperatures (:func:`models.thermal.seed_000_hot_state_closure`,
  the reference-state reading that reproduces the seed's ``c* ~ 10 um``, SEED-NOTES 8), and
  returns both figures.

The thermal closure is uniform along the path of contact and the same at every torque: the
critical gap ``c* = (1 - chi)(Delta_1 + Delta_2)`` is then one number, and at ``c = c*`` the
mean mesh stiffness equals the elastic one at every load (seed 000, Table 5). The figures
state the closure and the reading behind it in a note under the axes.

References
----------
.. [1] Seed 000, "Thermoelastic coupling stiffness analysis of spur gears with consideration
   of backlash" (FZG-C): stiffness formula, Tables 4-6, critical compensation gap.
"""

from __future__ import annotations

import math
import textwrap
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Final

import numpy as np
from matplotlib.axes import Axes
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.colors import is_color_like, to_rgba
from matplotlib.figure import Figure, SubFigure
from matplotlib.lines import Line2D
from matplotlib.patches import Patch
from numpy.typing import ArrayLike

from models.geometry import GearSet
from models.thermal import (
    CRITICAL_GAP_ATOL_M,
    SEED_000_CHI,
    TABLE_6_TORQUES_NM,
    NaturalFrequency,
    ThermalClosure,
    jammed_torque_spans,
    thermal_sweep,
)
from rigtools.plots.stiffness import FIGURE_WIDTH_IN

__all__ = [
    "plot_natural_frequency_vs_load",
    "plot_stiffness_vs_load",
    "thermal_figures",
]

_FIGURE_HEIGHT_IN: Final = 6.4
_FONT_SIZE: Final = 8.5
#: Colour-blind-safe colours (Okabe and Ito 2008) for the backlash values other than ``c*``,
#: smallest backlash first; the line at ``c = c*`` is black.
_CASE_COLOURS: Final = ("#D55E00", "#CC79A7", "#009E73", "#56B4E9", "#0072B2", "#E69F00")
#: Hatches of the jammed ranges, one per backlash that jams (overlaps cross-hatch).
_HATCHES: Final = ("////", "\\\\\\\\", "||||", "----")
#: Wrapping widths (characters) of the title and the note at ``FIGURE_WIDTH_IN``.
_TITLE_WIDTH: Final = 92
_NOTE_WIDTH: Final = 138
_CRITICAL_COLOUR: Final = "#000000"
_MARK_COLOUR: Final = "0.6"
_UM: Final = 1e6  # m -> um
_N_PER_UM: Final = 1e6  # N/m -> N/um
_N_PER_MM_UM: Final = 1e9  # N/m per m of face width -> N/(mm um)
_KHZ: Final = 1e-3  # Hz -> kHz
#: Top of the stiffness axis over the elastic stiffness (the ``c < c*`` lines diverge at the
#: jam boundary and leave the axes there); the frequency axis uses its square root.
_Y_TOP_FACTOR: Final = 2.2

_JAM_TEXT: Final = "gears jammed by\nthermal growth\n(formula not valid)"


# --- validation --------------------------------------------------------------------------------
def _check_inputs(torque_Nm: ArrayLike, result: NaturalFrequency, backlash_m: ArrayLike,
                  critical_gap_m: float) -> tuple[np.ndarray, np.ndarray, float]:
    if not isinstance(result, NaturalFrequency):
        raise ValueError(f"`result` must be a NaturalFrequency (from "
                         f"models.thermal.mesh_natural_frequency), was {type(result).__name__}")
    t = np.asarray(torque_Nm, dtype=float)
    if t.ndim != 1 or t.size < 2:
        raise ValueError(f"`torque_Nm` must be 1-D with at least 2 torques, had shape {t.shape}")
    if not (np.all(np.isfinite(t)) and np.all(t > 0) and np.all(np.diff(t) > 0)):
        raise ValueError("`torque_Nm` must be finite, > 0 and increasing (N m)")
    c = np.atleast_1d(np.asarray(backlash_m, dtype=float))
    if c.ndim != 1 or c.size < 1 or not np.all(np.isfinite(c) & (c >= 0)):
        raise ValueError(f"`backlash_m` must be 1-D, finite and >= 0 (m), was {c.tolist()!r}")
    shape = (c.size, t.size)
    if result.k_mean_N_per_m.shape != shape:
        raise ValueError(f"`result` must have shape (len(backlash_m), len(torque_Nm)) = {shape}, "
                         f"had {result.k_mean_N_per_m.shape}")
    c_star = float(critical_gap_m)
    if not math.isfinite(c_star):
        raise ValueError(f"`critical_gap_m` must be finite (m), was {critical_gap_m!r}")
    return t, c, c_star


def _check_colors(colors: Sequence[str] | None, n: int) -> list[str] | None:
    if colors is None:
        return None
    if isinstance(colors, str) or len(colors) != n:
        raise ValueError(f"`colors` must give one colour per backlash ({n}), was {colors!r}")
    for col in colors:
        if not is_color_like(col):
            raise ValueError(f"`colors` must hold matplotlib colours, had {col!r}")
    return list(colors)


def _check_positive(name: str, value: float | None) -> float | None:
    if value is None:
        return None
    if not (math.isfinite(value) and value > 0):
        raise ValueError(f"`{name}` must be finite and > 0, was {value!r}")
    return float(value)


# --- pieces of the figures ---------------------------------------------------------------------
def _num(x: float) -> str:
    return f"{x:g}"


def _um(x_m: float) -> str:
    """A length in um with 4 significant figures."""
    v = x_m * _UM
    return f"{v:.4g}"


def _is_critical(c: float, c_star: float) -> bool:
    return abs(c - c_star) <= CRITICAL_GAP_ATOL_M


def _backlash_names(backlash: np.ndarray, c_star: float) -> list[tuple[str, str]]:
    """``(short, long)`` names: ``("c = c*/2", "c = c*/2 = 5.137 µm")``, ``("c = 40 µm", ...)``."""
    names = []
    for c in backlash.tolist():
        ratio = c / c_star if c_star > 0 else math.nan
        if _is_critical(c, c_star):
            short = "c = c*"
        elif c == 0:
            names.append(("c = 0", "c = 0"))
            continue
        elif math.isfinite(ratio) and math.isclose(ratio, 0.5, rel_tol=1e-9):
            short = "c = c*/2"
        elif math.isfinite(ratio) and any(math.isclose(ratio, r, rel_tol=1e-9)
                                          for r in (2.0, 3.0, 4.0)):
            short = f"c = {ratio:.0f}c*"
        else:
            names.append((f"c = {_um(c)} µm", f"c = {_um(c)} µm"))
            continue
        names.append((short, f"{short} = {_um(c)} µm"))
    return names


def _colours(backlash: np.ndarray, c_star: float, colors: list[str] | None) -> list[str]:
    if colors is not None:
        return colors
    out, k = [], 0
    for c in backlash.tolist():
        if _is_critical(c, c_star):
            out.append(_CRITICAL_COLOUR)
        else:
            out.append(_CASE_COLOURS[k % len(_CASE_COLOURS)])
            k += 1
    return out


def _style_axes(ax: Axes) -> None:
    ax.tick_params(labelsize=_FONT_SIZE)
    ax.grid(True, color="0.88", lw=0.5)
    ax.set_axisbelow(True)
    for side in ("top", "right"):
        ax.spines[side].set_visible(False)


def _mark_torques(ax: Axes, torques: Sequence[float], x_max: float) -> None:
    """Faint vertical lines at ``torques`` and a top axis naming them (seed 000 Table 6)."""
    shown = [float(t) for t in torques if 0 <= float(t) <= x_max]
    if not shown:
        return
    for j, t in enumerate(shown):
        ax.axvline(t, color=_MARK_COLOUR, lw=0.6, ls=(0, (6, 4)), zorder=1, gid=f"marked/{j}")
    top = ax.secondary_xaxis("top")
    top.set_xticks(shown, labels=[_num(t) for t in shown])
    top.tick_params(labelsize=_FONT_SIZE - 0.5, direction="inout", length=6, color=_MARK_COLOUR,
                    labelcolor="0.3", pad=1)
    top.set_xlabel("torques of the seed 000 Table 6 runs (N·m)", fontsize=_FONT_SIZE - 0.5,
                   color="0.3", labelpad=3)
    top.set_gid("marked-axis")


@dataclass(frozen=True)
class _Quantity:
    """What one figure draws: a scale from the result's array and the axis wording."""

    values: np.ndarray  # (n_backlash, n_torque), SI
    scale: float
    ylabel: str
    gid: str
    elastic: float | None  # the elastic (c = c*) value, SI
    symbol: str  # the quantity's symbol, for "-> infinity" at the jam edge
    elastic_text: str  # label of the c* line, with "{value}" where the value goes
    value_format: str  # format of that value, e.g. "{:.4g}"
    y_top_factor: float


def _wrap(text: str, width: int) -> str:
    """``text`` wrapped to ``width`` characters, keeping its own line breaks."""
    return "\n".join(textwrap.fill(par, width) if par else "" for par in text.split("\n"))


def _plot_vs_torque(
    torque: np.ndarray,
    result: NaturalFrequency,
    backlash: np.ndarray,
    c_star: float,
    q: _Quantity,
    *,
    title: str,
    note: str | None,
    labels: Sequence[str] | None,
    colors: list[str] | None,
    marked_torques_Nm: Sequence[float],
    y_max: float | None,
) -> Figure:
    n_b = backlash.size
    names = _backlash_names(backlash, c_star)
    if labels is None:
        labels = [long for _, long in names]
        short_names = [short for short, _ in names]
    elif isinstance(labels, str) or len(labels) != n_b:
        raise ValueError(f"`labels` must give one label per backlash ({n_b}), was {labels!r}")
    else:
        short_names = [str(lab) for lab in labels]
    colours = _colours(backlash, c_star, colors)
    jammed = np.asarray(result.jammed, dtype=bool)
    net = np.asarray(result.min_net_deflection_m, dtype=float)
    x_max = float(torque[-1])
    spans_of = [jammed_torque_spans(torque, jammed[i], net[i]) for i in range(n_b)]
    any_jam = any(spans_of)

    n_entries = n_b + int(any_jam)
    ncols = min(n_entries, 3)
    title = _wrap(title, _TITLE_WIDTH)
    head_h = 0.42 + 0.2 * (title.count("\n") + 1) + 0.2 * math.ceil(n_entries / ncols)
    note = _wrap(note, _NOTE_WIDTH) if note else None
    foot_h = 0.0 if not note else 0.12 + 0.125 * (note.count("\n") + 1)
    fig = Figure(figsize=(FIGURE_WIDTH_IN, _FIGURE_HEIGHT_IN), layout="constrained")
    FigureCanvasAgg(fig)
    heights = [head_h, _FIGURE_HEIGHT_IN - head_h - foot_h] + ([foot_h] if note else [])
    grid = fig.add_gridspec(len(heights), 1, height_ratios=heights)
    head: SubFigure = fig.add_subfigure(grid[0])
    body: SubFigure = fig.add_subfigure(grid[1])
    ax = body.subplots()
    _style_axes(ax)

    # the data: only where Eq. (1) holds (not jammed), so nothing NaN, infinite or negative
    handles: list[Line2D | Patch] = []
    for i in range(n_b):
        y = q.values[i]
        valid = ~jammed[i] & np.isfinite(y) & (y > 0)
        crit = _is_critical(float(backlash[i]), c_star)
        (line,) = ax.plot(torque[valid], y[valid] * q.scale, color=colours[i],
                          lw=2.2 if crit else 1.6, label=str(labels[i]), gid=f"{q.gid}/{i}",
                          zorder=4 if crit else 3)
        handles.append(line)

    # the y range: from 0 to a multiple of the elastic value (the c < c* lines leave at the top)
    if y_max is None:
        if q.elastic is not None:
            y_max = q.y_top_factor * q.elastic * q.scale
        else:
            finite = q.values[np.isfinite(q.values) & ~jammed]
            y_max = 1.1 * float(finite.max()) * q.scale if finite.size else 1.0
    elif not (math.isfinite(y_max) and y_max > 0):
        raise ValueError(f"`y_max` must be finite and > 0, was {y_max!r}")
    ax.set_ylim(0.0, y_max)
    ax.set_xlim(0.0, x_max)

    # jammed torque ranges: hatched in the colour of their backlash (one hatch direction per
    # backlash, so overlaps cross-hatch), the jam boundary dotted and labelled
    n_jam = 0
    for i, spans in enumerate(spans_of):
        if not spans:
            continue
        col = colours[i]
        hatch = _HATCHES[n_jam % len(_HATCHES)]
        n_jam += 1
        for k, span_k in enumerate(spans):
            lo, hi = span_k.lo_Nm, span_k.hi_Nm
            span = ax.axvspan(lo, hi, facecolor=to_rgba(col, 0.06), edgecolor=to_rgba(col, 0.3),
                              hatch=hatch, lw=0, zorder=0)
            span.set_gid(f"jammed/{i}/{k}")
            if span_k.open_high:
                continue
            ax.axvline(hi, color=col, lw=1.1, ls=(0, (1, 1.5)), zorder=2,
                       gid=f"jam-edge/{i}/{k}")
            ax.annotate(f"{short_names[i]}: jammed below {hi:.0f} N·m, {q.symbol} → ∞ here",
                        (hi, 0.985), xycoords=ax.get_xaxis_transform(), xytext=(-3, 0),
                        textcoords="offset points", rotation=90, ha="right", va="top",
                        fontsize=_FONT_SIZE - 1.5, color=col, zorder=5, gid=f"jam-label/{i}/{k}",
                        bbox={"boxstyle": "square,pad=0.15", "facecolor": "white",
                              "edgecolor": "none", "alpha": 0.85})
    if any_jam:
        ax.text(0.01, 0.985, _JAM_TEXT, transform=ax.transAxes, ha="left", va="top",
                fontsize=_FONT_SIZE - 1, color="0.15", zorder=6, gid="jam-text",
                bbox={"boxstyle": "round,pad=0.25", "facecolor": "white", "edgecolor": "0.7",
                      "lw": 0.6, "alpha": 0.95})
        handles.append(Patch(facecolor=to_rgba("0.4", 0.06), edgecolor=to_rgba("0.35", 0.55),
                             hatch=_HATCHES[0], lw=0,
                             label="jammed (c < c*): not drawn,\nformula not valid"))

    # the critical gap: flat at the elastic value, labelled on the line
    for i in range(n_b):
        y = q.values[i]
        ok = np.isfinite(y) & ~jammed[i]
        if not (_is_critical(float(backlash[i]), c_star) and np.any(ok)):
            continue
        value = float(np.median(y[ok])) * q.scale
        text = q.elastic_text.replace("{value}", q.value_format.format(value))
        ax.annotate(text, (0.985 * x_max, value), xytext=(0, 4), textcoords="offset points",
                    ha="right", va="bottom", fontsize=_FONT_SIZE - 0.5, color=_CRITICAL_COLOUR,
                    zorder=6, gid="critical-label",
                    bbox={"boxstyle": "square,pad=0.1", "facecolor": "white",
                          "edgecolor": "none", "alpha": 0.8})

    if marked_torques_Nm:
        _mark_torques(ax, marked_torques_Nm, x_max)

    ax.set_xlabel("pinion torque T (N·m)", fontsize=_FONT_SIZE)
    ax.set_ylabel(q.ylabel, fontsize=_FONT_SIZE)

    head.suptitle(title, fontsize=_FONT_SIZE + 1.5)
    head.legend(handles=handles, loc="outside lower center", ncols=ncols,
                title="total backlash c on the line of action", fontsize=_FONT_SIZE,
                title_fontsize=_FONT_SIZE, frameon=False, handlelength=2.4, columnspacing=1.6)
    if note:
        foot = fig.add_subfigure(grid[2])
        foot.text(0.01, 0.98, note, ha="left", va="top", fontsize=_FONT_SIZE - 1.5,
                  color="0.25", gid="note", linespacing=1.3)
    return fig


# --- the public functions ----------------------------------------------------------------------
def plot_stiffness_vs_load(
    torque_Nm: ArrayLike,
    result: NaturalFrequency,
    backlash_m: ArrayLike,
    critical_gap_m: float,
    *,
    elastic_stiffness_N_per_m: float | None = None,
    title: str = "Mean thermoelastic mesh stiffness against torque",
    note: str | None = None,
    labels: Sequence[str] | None = None,
    face_width_m: float | None = None,
    colors: Sequence[str] | None = None,
    marked_torques_Nm: Sequence[float] = (),
    y_max: float | None = None,
) -> Figure:
    r"""Cycle-mean thermoelastic mesh stiffness against pinion torque, one line per backlash.

    Parameters
    ----------
    torque_Nm : array_like
        Pinion torques (N m), 1-D, > 0, increasing: the columns of ``result``.
    result : NaturalFrequency
        From :func:`models.thermal.mesh_natural_frequency` with the torques on the last axis and
        one row per backlash, shape ``(len(backlash_m), len(torque_Nm))``; its
        ``k_mean_N_per_m``, ``jammed`` and ``min_net_deflection_m`` are drawn.
    backlash_m : array_like
        Total backlash ``c`` of each row (m), >= 0.
    critical_gap_m : float
        ``c* = (1 - chi)(Delta_1 + Delta_2)`` (m) the result was computed with; the row with
        ``|c - c*| <= 1 pm`` is drawn black and labelled.
    elastic_stiffness_N_per_m : float, optional
        Mean elastic mesh stiffness ``k_EP`` (N/m), e.g.
        ``NaturalFrequencyModel.k_EP_mean_N_per_m``: sets the y range (to 2.2 times it).
    title : str
        Figure title; state the thermal closure here or in ``note``.
    note : str, optional
        Text under the axes (the thermal closure and the reading behind it).
    labels : sequence of str, optional
        One legend label per backlash; default ``"c = 0"``, ``"c = c*/2 = 5.137 µm"``,
        ``"c = 40 µm"`` ...
    face_width_m : float, optional
        Face width ``b`` (m). Given: stiffness per unit face width in N/(mm·µm); None: the
        whole-face stiffness in N/µm.
    colors : sequence of str, optional
        One colour per backlash; default Okabe-Ito colours, black for ``c*``.
    marked_torques_Nm : sequence of float
        Torques to mark with vertical lines and a top axis (e.g. :data:`TABLE_6_TORQUES_NM`).
    y_max : float, optional
        Top of the y axis in the plotted unit.

    Returns
    -------
    matplotlib.figure.Figure
        ``FIGURE_WIDTH_IN`` wide, on the Agg canvas. ``fig.axes[0]`` holds the data; the title
        and legend sit in the header subfigure ``fig.subfigs[0]``, the note in the last
        subfigure. Each data line has ``gid`` ``"k/<i>"`` (row ``i``) and holds only the
        torques where row ``i`` is not jammed: no NaN, infinite or negative value is drawn.
        Jammed torque ranges are patches with gid ``"jammed/<i>/<k>"``, their upper ends
        dotted lines ``"jam-edge/<i>/<k>"``.

    Raises
    ------
    ValueError
        On inputs of the wrong type, shape or range.

    Notes
    -----
    Seed 000's Eq. (1) at each position ``s`` on the path, averaged over a mesh cycle:

    .. math::

        \bar k = \frac{1}{p_b}\int_A^E \frac{f_n(s)\, k_{EP}(s)}
                 {f_n(s) - (1 - \chi) k_{EP}(s) (\Delta_1 + \Delta_2) + c\, k_{EP}(s)}\,ds .

    At ``c = c*`` it is the elastic ``k_EP`` mean at every load; below ``c*`` it falls with
    load towards it, above ``c*`` it rises towards it (Table 5). Where the denominator is
    ``<= 0`` somewhere on the path the gears are jammed (:mod:`models.thermal.thermoelastic`);
    next to that boundary Eq. (1) diverges, so those lines leave the axes at the top.
    """
    t, c, c_star = _check_inputs(torque_Nm, result, backlash_m, critical_gap_m)
    b = _check_positive("face_width_m", face_width_m)
    k_el = _check_positive("elastic_stiffness_N_per_m", elastic_stiffness_N_per_m)
    if b is None:
        scale, unit = 1.0 / _N_PER_UM, "N/µm"
        ylabel = "mean mesh stiffness k̄, whole face (N/µm)"
    else:
        scale, unit = 1.0 / (b * _N_PER_MM_UM), "N/(mm·µm)"
        ylabel = "mean mesh stiffness k̄ per face width (N/(mm·µm))"
    q = _Quantity(values=np.asarray(result.k_mean_N_per_m, dtype=float), scale=scale,
                  ylabel=ylabel, gid="k", elastic=k_el, symbol="k̄",
                  elastic_text="c = c*: k̄ = k̄$_{EP}$ = {value} " + unit + " at every torque",
                  value_format="{:.4g}",
                  y_top_factor=_Y_TOP_FACTOR)
    return _plot_vs_torque(t, result, c, c_star, q, title=title, note=note, labels=labels,
                           colors=_check_colors(colors, c.size),
                           marked_torques_Nm=marked_torques_Nm, y_max=y_max)


def plot_natural_frequency_vs_load(
    torque_Nm: ArrayLike,
    result: NaturalFrequency,
    backlash_m: ArrayLike,
    critical_gap_m: float,
    *,
    elastic_frequency_Hz: float | None = None,
    title: str = "Mesh natural frequency against torque",
    note: str | None = None,
    labels: Sequence[str] | None = None,
    colors: Sequence[str] | None = None,
    marked_torques_Nm: Sequence[float] = TABLE_6_TORQUES_NM,
    y_max: float | None = None,
) -> Figure:
    r"""Mesh natural frequency against pinion torque, one line per backlash (seed 000 Table 6).

    The same layout as :func:`plot_stiffness_vs_load`, drawing ``result.f_n_Hz`` in kHz
    (data lines ``"fn/<i>"``), with the torques ``marked_torques_Nm`` (default seed 000
    Table 6) as ticks on a top axis and faint vertical lines (gids ``"marked/<j>"``).

    Parameters
    ----------
    torque_Nm, result, backlash_m, critical_gap_m, title, note, labels, colors, y_max
        As :func:`plot_stiffness_vs_load`; ``y_max`` in kHz.
    elastic_frequency_Hz : float, optional
        ``f_n`` of the elastic mean stiffness (Hz), e.g.
        ``NaturalFrequencyModel.elastic_natural_frequency_Hz``: sets the y range (to
        ``sqrt(2.2)`` times it, the stiffness figure's range).
    marked_torques_Nm : sequence of float
        Torques to mark (N m).

    Returns
    -------
    matplotlib.figure.Figure

    Notes
    -----
    .. math:: f_n = \frac{1}{2\pi}\sqrt{\frac{\bar k}{m_e}}

    with the equivalent mass ``m_e`` of the two gear bodies on the line of action
    (:mod:`models.thermal.natural_frequency`).
    """
    t, c, c_star = _check_inputs(torque_Nm, result, backlash_m, critical_gap_m)
    f_el = _check_positive("elastic_frequency_Hz", elastic_frequency_Hz)
    q = _Quantity(values=np.asarray(result.f_n_Hz, dtype=float), scale=_KHZ,
                  ylabel="mesh natural frequency $f_n$ (kHz)", gid="fn", elastic=f_el,
                  symbol="$f_n$",
                  elastic_text="c = c*: $f_n$ = {value} kHz (elastic) at every torque",
                  value_format="{:.3g}",
                  y_top_factor=math.sqrt(_Y_TOP_FACTOR))
    return _plot_vs_torque(t, result, c, c_star, q, title=title, note=note, labels=labels,
                           colors=_check_colors(colors, c.size),
                           marked_torques_Nm=marked_torques_Nm, y_max=y_max)


def thermal_figures(
    gear_set: str | Path | GearSet = "fzg-c",
    backlash_m: Sequence[float] | None = None,
    *,
    torque_max_Nm: float = 500.0,
    n_torques: int = 500,
    thermal_closure: ThermalClosure | None = None,
    chi: float = SEED_000_CHI,
) -> dict[str, Figure]:
    """The mean mesh stiffness and the natural frequency against torque for a gear set.

    The sweep is :func:`models.thermal.thermal_sweep`. The thermal closure is seed 000's hot
    state (:func:`models.thermal.seed_000_hot_state_closure`: 302 N m,
    1500 min^-1, 90 deg C oil, the reading that reproduces ``c* ~ 10 um``) unless given; it is
    held fixed over the torque sweep, uniform along the path. Ishikawa's ``k_EP`` without the
    contact term and seed 000's load share (:func:`models.thermal.prepare_natural_frequency`).

    Parameters
    ----------
    gear_set : str, path or GearSet
        A shipped gear-set name, a gear-set file, or a loaded :class:`~models.geometry.GearSet`.
    backlash_m : sequence of float, optional
        Total backlash values (m); default 0, c*/2, c*, 2 c*, 40 um and 100 um.
    torque_max_Nm : float
        Largest pinion torque (N m).
    n_torques : int
        Steps of the torque grid; the Table 6 torques and points just above each jam boundary
        are added to it (the ``c < c*`` lines are then drawn up to where they leave the axes).
    thermal_closure : ThermalClosure, optional
        ``Delta_1 + Delta_2`` and its description for the note.
    chi : float
        Thermoelastic correction factor (-); seed 000's 0.0285.

    Returns
    -------
    dict of str to matplotlib.figure.Figure
        ``"stiffness"`` (:func:`plot_stiffness_vs_load`) and ``"natural_frequency"``
        (:func:`plot_natural_frequency_vs_load`).
    """
    sweep = thermal_sweep(gear_set, backlash_m, torque_max_Nm, n_torques, thermal_closure, chi)
    gear_set, closure, c_star = sweep.gear_set, sweep.closure, sweep.c_star
    backlash, model, torque, result = sweep.backlash, sweep.model, sweep.torque, sweep.result

    name = gear_set.name.upper() if gear_set.name.lower().startswith("fzg") else gear_set.name
    closure_text = (f"thermal closure Δ₁+Δ₂ = {closure.total_m * _UM:.2f} µm, χ = {_num(chi)}: "
                    f"c* = (1 − χ)(Δ₁+Δ₂) = {_um(c_star)} µm")
    note = (f"{closure.description}\n"
            "Mean over a mesh cycle of seed 000's thermoelastic pair stiffness, Eq. (1) "
            "(Ishikawa k_EP without contact term, seed 000 load share, exact f'_n = T / r_b1). "
            "Jammed: Eq. (1)'s denominator ≤ 0 somewhere on the path (thermal interference "
            "larger than the elastic deflection, both flanks in contact).")
    stiffness = plot_stiffness_vs_load(
        torque, result, backlash, c_star,
        elastic_stiffness_N_per_m=float(model.k_EP_mean_N_per_m),
        title=f"{name}: mean mesh stiffness against torque\n{closure_text}", note=note)
    frequency = plot_natural_frequency_vs_load(
        torque, result, backlash, c_star,
        elastic_frequency_Hz=float(model.elastic_natural_frequency_Hz),
        title=f"{name}: mesh natural frequency against torque\n{closure_text}",
        note=note + f" f_n = √(k̄ / m_e) / 2π, m_e = {model.equivalent_mass_kg:.4g} kg (gear "
                    "bodies as discs to the operating pitch circle).")
    return {"stiffness": stiffness, "natural_frequency": frequency}

r"""Figures of gear mesh stiffness over one mesh cycle: VVMS/FVMS, load sharing and LSTE.

The presentation layer over :mod:`models.stiffness.mesh_cycle`: functions here take
:class:`~models.stiffness.MeshCycle` result objects and return :class:`matplotlib.figure.Figure`
objects drawn on the Agg canvas. Nothing touches ``matplotlib.pyplot`` or ``rcParams``, so the
figures can be built in worker processes and in tests without a display, and importing this
module changes no global state.

* :func:`plot_mesh_cycle` draws three stacked panels over the mesh-cycle phase, in the manner
  of seed 003 Figs. 4 and 6: the variable-variable mesh stiffness (VVMS, solid) with the
  fixed-variable mesh stiffness (FVMS, dashed) and the theoretical single/double contact zones
  shaded; the load-sharing ratio of each tooth pair (one colour per case, one line style per
  pair); the loaded static transmission error (LSTE).
* :func:`mesh_cycle_figures` computes the two case studies of seed 003 for a shipped gear set
  (torque sweep without relief, Fig. 4; relief amounts at the design torque, Fig. 6(b)) with
  the potential-energy tooth-pair compliance, and returns both figures.
* :func:`save_png` writes a figure to a PNG file.

The phase ``tau`` is that of :func:`models.stiffness.mesh_cycle`: one cycle is one base pitch
of pinion roll, and at ``tau = 0`` the middle pair (#2, slot ``m = 0``) enters the theoretical
path at A. Pair #2 reaches the lowest point of single contact (LPSTC, ``B = E - p_b``) at
``tau = eps - 1`` and the highest (HPSTC, ``D = A + p_b``) at ``tau = 1``, so for
``1 < eps < 2`` the theoretical double-contact zone is ``[0, eps - 1]`` and the single-contact
zone ``[eps - 1, 1)``. Pairs are numbered as in seed 003 Fig. 4: #1 outgoing (``m = 1``),
#2 middle (``m = 0``), #3 incoming (``m = -1``); generally pair ``#(2 - m)``.

References
----------
.. [1] W. Yu, C. K. Mechefske, "Analytical modeling of spur gear corner contact effects",
   Mech. Mach. Theory 96 (2016) 146-164, Figs. 4 and 6 (seed 003).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path
from typing import Final

import numpy as np
from matplotlib.axes import Axes
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.colors import is_color_like
from matplotlib.figure import Figure
from matplotlib.lines import Line2D

from models.geometry import GearSet, load_gear_set
from models.stiffness import (
    MeshCycle,
    TabulatedCompliance,
    normalised_tip_relief,
    pair_compliance,
    prepare_mesh_cycle,
    tabulate_compliance,
)

__all__ = [
    "FIGURE_WIDTH_IN",
    "mesh_cycle_figures",
    "plot_mesh_cycle",
    "save_png",
]

#: Width of the figures (in): the text width of an A4/letter report.
FIGURE_WIDTH_IN: Final = 7.0
_FIGURE_HEIGHT_IN: Final = 7.6

#: Colour-blind-safe colours (Okabe and Ito 2008), one per case, in this order: blue to
#: vermillion runs cool to warm from the first case to the last (0 N m ... 340 N m).
_CASE_COLOURS: Final = ("#0072B2", "#009E73", "#E69F00", "#D55E00", "#CC79A7", "#56B4E9")
#: Colours of the relief amounts above zero in :func:`mesh_cycle_figures`, distinct from the
#: torque colours (Delta = 0 at the relief torque keeps that torque's colour).
_RELIEF_COLOURS: Final = ("#CC79A7", "#56B4E9", "#882255", "#117733", "#999933", "#332288")
_FVMS_COLOUR: Final = "#000000"
_ZONE_COLOUR: Final = "#E8E8E8"

#: Line style of each tooth pair in the load-sharing panel, by slot offset ``m``.
_PAIR_STYLES: Final = {1: "--", 0: "-", -1: ":"}
_OTHER_PAIR_STYLE: Final = "-."
_PAIR_ROLES: Final = {1: "outgoing", 0: "middle", -1: "incoming"}

_N_PER_MM_UM: Final = 1e9  # 1 N/(mm um) = 1e9 N/m^2
_N_PER_UM: Final = 1e6  # 1 N/um = 1e6 N/m
_UM: Final = 1e6  # m -> um

_FONT_SIZE: Final = 8.5
_ZONE_NAMES: Final = {1: "single", 2: "double", 3: "triple", 4: "quadruple"}
#: Shortest run of coinciding curves (in cycles) that gets a note.
_NOTE_MIN_RUN: Final = 0.15


# --- validation --------------------------------------------------------------------------------
def _check_cycles(cycles: Sequence[MeshCycle], labels: Sequence[str]) -> list[MeshCycle]:
    """The cycles as a list, checked to share one phase grid and one gear pair."""
    cycles = list(cycles)
    if isinstance(labels, str):
        raise ValueError(f"`labels` must be a sequence of strings, one per cycle, was the "
                         f"string {labels!r}")
    if not cycles:
        raise ValueError("`cycles` must hold at least one MeshCycle, was empty")
    if len(labels) != len(cycles):
        raise ValueError(f"`labels` must give one label per cycle ({len(cycles)}), "
                         f"gave {len(labels)}")
    for i, c in enumerate(cycles):
        if not isinstance(c, MeshCycle):
            raise ValueError(f"`cycles[{i}]` must be a MeshCycle, was {type(c).__name__}")
    ref = cycles[0]
    for i, c in enumerate(cycles[1:], start=1):
        if not np.array_equal(c.phase, ref.phase):
            raise ValueError(f"`cycles[{i}]` must share the phase grid of `cycles[0]` "
                             f"({ref.phase.size} phases), had {c.phase.size} different ones")
        if not (np.array_equal(c.slot_offset, ref.slot_offset)
                and math.isclose(c.theoretical_contact_ratio, ref.theoretical_contact_ratio)
                and math.isclose(c.base_pitch_m, ref.base_pitch_m)):
            raise ValueError(f"`cycles[{i}]` must come from the gear pair of `cycles[0]` "
                             f"(contact ratio {ref.theoretical_contact_ratio:.4f}), had "
                             f"contact ratio {c.theoretical_contact_ratio:.4f}")
    return cycles


def _check_face_width(face_width_m: float | None) -> float | None:
    if face_width_m is None:
        return None
    if not (math.isfinite(face_width_m) and face_width_m > 0):
        raise ValueError(f"`face_width_m` must be finite and > 0 m, was {face_width_m!r}")
    return float(face_width_m)


def _check_colors(colors: Sequence[str] | None, n: int) -> list[str]:
    if colors is None:
        return [_CASE_COLOURS[i % len(_CASE_COLOURS)] for i in range(n)]
    if isinstance(colors, str) or len(colors) != n:
        raise ValueError(f"`colors` must give one colour per cycle ({n}), was {colors!r}")
    for c in colors:
        if not is_color_like(c):
            raise ValueError(f"`colors` must hold matplotlib colours, had {c!r}")
    return list(colors)


# --- pieces of the figure ----------------------------------------------------------------------
def _pair_name(m: int) -> str:
    role = _PAIR_ROLES.get(m, "outgoing" if m > 0 else "incoming")
    return f"pair #{2 - m} ({role})"


def _pair_style(m: int) -> str:
    return _PAIR_STYLES.get(m, _OTHER_PAIR_STYLE)


def _contact_zones(cycle: MeshCycle) -> tuple[int, float]:
    """``(n, tau_b)``: ``n + 1`` pairs in the theoretical path for ``tau < tau_b``, ``n`` after.

    ``n = floor(eps)``; pair #2 reaches ``E - n p_b`` (the LPSTC ``B`` when ``n = 1``) at
    ``tau_b = eps - n`` and ``A + p_b`` (the HPSTC ``D`` when ``n = 1``) at ``tau = 1``.
    """
    eps = cycle.theoretical_contact_ratio
    n = math.floor(eps)
    return n, eps - n


def _shade_zones(ax: Axes, cycle: MeshCycle, *, label: bool) -> None:
    n, tau_b = _contact_zones(cycle)
    span = ax.axvspan(tau_b, 1.0, color=_ZONE_COLOUR, lw=0, zorder=0)
    span.set_gid("zone")
    if not label:
        return
    names = (_ZONE_NAMES.get(n + 1, f"{n + 1}-fold"), _ZONE_NAMES.get(n, f"{n}-fold"))
    for x, name in ((0.5 * tau_b, names[0]), (0.5 * (tau_b + 1.0), names[1])):
        ax.text(x, 0.97, f"{name} contact\n(theoretical)", transform=ax.get_xaxis_transform(),
                ha="center", va="top", fontsize=_FONT_SIZE - 1, color="0.35", zorder=1)


def _contact_point_axis(ax: Axes, cycle: MeshCycle) -> None:
    """Top axis of the first panel: where pair #2 touches at the zone boundaries."""
    n, tau_b = _contact_zones(cycle)
    top = ax.secondary_xaxis("top")
    names = ["A", "LPSTC", "HPSTC"] if n == 1 else ["A", f"E − {n} p$_b$", "A + p$_b$"]
    top.set_xticks([0.0, tau_b, 1.0], labels=names)
    top.tick_params(labelsize=_FONT_SIZE - 0.5, direction="in", pad=2)
    top.set_xlabel("contact point of pair #2 on the line of action", fontsize=_FONT_SIZE,
                   labelpad=4)


def _loaded_slots(cycle: MeshCycle) -> list[int]:
    """Slots whose pair carries load somewhere in the cycle (the ``F -> 0+`` share at T = 0)."""
    return [k for k in range(cycle.slot_offset.size)
            if bool(np.any(cycle.load_sharing_ratio[:, k] > 0))]


def _lsr_for_plot(lsr: np.ndarray) -> np.ndarray:
    """The LSR of one pair with NaN where it is unloaded and so are both its neighbours.

    The line then drops to zero where the pair takes up or sheds its load, without a run along
    the axis while it is out of contact.
    """
    loaded = lsr > 0
    near = loaded.copy()
    near[1:] |= loaded[:-1]
    near[:-1] |= loaded[1:]
    return np.where(near, lsr, np.nan)


def _coincident_run(curves: Sequence[np.ndarray]) -> slice | None:
    """The longest run of phases where all ``curves`` (rows: phases) agree to 1e-9, or None."""
    if len(curves) < 2:
        return None
    ref = curves[0]
    same = np.all([np.all(np.isclose(c, ref, rtol=1e-9, atol=0.0).reshape(ref.shape[0], -1),
                          axis=1) for c in curves[1:]], axis=0)
    best, start = (0, 0), None
    for i, s in enumerate([*same.tolist(), False]):
        if s and start is None:
            start = i
        elif not s and start is not None:
            if i - start > best[1] - best[0]:
                best = (start, i)
            start = None
    return slice(*best) if best[1] > best[0] else None


def _note_coincidence(ax: Axes, phase: np.ndarray, run: slice | None, y: np.ndarray, text: str,
                      *, below: bool) -> None:
    """Say where every case lies on one line, so that hidden lines are not taken as missing."""
    if run is None or phase[run.stop - 1] - phase[run.start] < _NOTE_MIN_RUN:
        return
    mid = (run.start + run.stop - 1) // 2
    ax.annotate(text, (phase[mid], y[mid]), xytext=(0, -7 if below else 7),
                textcoords="offset points", ha="center", va="top" if below else "bottom",
                fontsize=_FONT_SIZE - 1, color="0.3", zorder=4, gid="note")


def _style_axes(ax: Axes) -> None:
    ax.tick_params(labelsize=_FONT_SIZE)
    ax.grid(True, color="0.88", lw=0.5)
    ax.set_axisbelow(True)
    for side in ("top", "right"):
        ax.spines[side].set_visible(False)


def _header_height_in(n_entries: int, ncols: int, has_legend_title: bool) -> float:
    rows = math.ceil(n_entries / ncols)
    return 0.3 + (0.18 if has_legend_title else 0.0) + 0.19 * rows


# --- the public functions ----------------------------------------------------------------------
def plot_mesh_cycle(
    cycles: Sequence[MeshCycle],
    labels: Sequence[str],
    *,
    title: str = "Mesh stiffness, load sharing and transmission error over one mesh cycle",
    legend_title: str | None = None,
    face_width_m: float | None = None,
    colors: Sequence[str] | None = None,
) -> Figure:
    r"""Three stacked panels over one mesh cycle: VVMS/FVMS, load-sharing ratio, LSTE.

    Parameters
    ----------
    cycles : sequence of MeshCycle
        The cases to compare (e.g. torques, relief amounts), all of one gear pair on one phase
        grid (from :func:`models.stiffness.mesh_cycle` or ``MeshCycleGeometry.solve``).
    labels : sequence of str
        One legend label per cycle (e.g. ``"340 N·m"``).
    title : str
        Figure title.
    legend_title : str, optional
        Title of the legend of the cases (e.g. ``"Pinion torque"``).
    face_width_m : float, optional
        Face width ``b`` (m). Given: stiffness per unit face width, ``K / b`` in N/(mm·µm)
        (ISO 6336-1's unit). None: the whole-face stiffness ``K`` in N/µm.
    colors : sequence of str, optional
        One matplotlib colour per cycle; default: colour-blind-safe colours in order, running
        cool to warm.

    Returns
    -------
    matplotlib.figure.Figure
        ``FIGURE_WIDTH_IN`` wide, on the Agg canvas. ``fig.axes`` holds the three panels top to
        bottom (stiffness, load-sharing ratio, LSTE), sharing the phase axis; the title and the
        legend of the cases sit in the header subfigure ``fig.subfigs[0]``. Each data line
        carries a ``gid``: ``"vvms/<i>"``; ``"fvms"`` (one line when every cycle has the same
        FVMS, as when only torque or profile errors differ) or else ``"fvms/<i>"``;
        ``"lsr/<i>/<m>"`` for slot offset ``m``, only for pairs that carry load in cycle
        ``i``, NaN where the pair and both its neighbouring phases are unloaded;
        ``"lste/<i>"``; ``i`` is the index of the cycle.

    Raises
    ------
    ValueError
        When ``cycles`` is empty, ``labels`` or ``colors`` has another length, or the cycles
        do not share a phase grid and gear pair.

    Notes
    -----
    Drawn as in seed 003 Figs. 4 and 6: ``K_V = F / x`` (Eq. 20b) and ``K_F`` (Eqs. 18-19);
    ``LSR_i = F_i / F``; ``x`` the LSTE (drawn in µm). The shaded band is the theoretical zone
    with one pair fewer in contact (single contact for ``1 < eps < 2``), from pair #2 at the
    LPSTC (``tau = eps - 1``) to pair #2 at the HPSTC (``tau = 1``). Corner contact lets pairs
    carry load outside the theoretical path, so under load the loaded zones differ from the
    shaded ones. Where every case lies on one curve (e.g. the double-contact zone without
    profile errors, where ``K_V = K_F`` at any load), a note says so.
    """
    cycles = _check_cycles(cycles, labels)
    b = _check_face_width(face_width_m)
    colours = _check_colors(colors, len(cycles))
    if b is None:
        k_scale, k_unit = 1.0 / _N_PER_UM, "whole face (N/µm)"
    else:
        k_scale, k_unit = 1.0 / (b * _N_PER_MM_UM), "per face width (N/(mm·µm))"
    phase = cycles[0].phase
    n_entries = len(cycles) + 1
    ncols = min(n_entries, 5)
    head_h = _header_height_in(n_entries, ncols, legend_title is not None)

    fig = Figure(figsize=(FIGURE_WIDTH_IN, _FIGURE_HEIGHT_IN), layout="constrained")
    FigureCanvasAgg(fig)
    grid = fig.add_gridspec(2, 1, height_ratios=(head_h, _FIGURE_HEIGHT_IN - head_h))
    head, body = fig.add_subfigure(grid[0]), fig.add_subfigure(grid[1])
    ax_k, ax_lsr, ax_x = body.subplots(3, 1, sharex=True,
                                       gridspec_kw={"height_ratios": (1.25, 1.0, 0.9)})
    for ax in (ax_k, ax_lsr, ax_x):
        _style_axes(ax)
        _shade_zones(ax, cycles[0], label=ax is ax_k)

    # stiffness: VVMS per case, FVMS dashed on top
    ref_fvms = cycles[0].fvms_N_m
    shared_fvms = all(np.array_equal(c.fvms_N_m, ref_fvms) for c in cycles)
    case_handles: list[Line2D] = []
    for i, (c, lab) in enumerate(zip(cycles, labels, strict=True)):
        (line,) = ax_k.plot(phase, c.vvms_N_m * k_scale, color=colours[i], lw=1.6,
                            label=str(lab), gid=f"vvms/{i}", zorder=2)
        case_handles.append(line)
        if not shared_fvms:
            ax_k.plot(phase, c.fvms_N_m * k_scale, color=colours[i], lw=1.0, ls="--",
                      gid=f"fvms/{i}", zorder=3)
    if shared_fvms:
        (fvms_line,) = ax_k.plot(phase, ref_fvms * k_scale, color=_FVMS_COLOUR, lw=0.9,
                                 ls=(0, (4, 2.5)), label="FVMS (all cases)", gid="fvms",
                                 zorder=3)
        run = _coincident_run([ref_fvms] + [c.vvms_N_m for c in cycles])
        _note_coincidence(ax_k, phase, run, ref_fvms * k_scale,
                          "every case here: VVMS = FVMS", below=True)
    else:
        fvms_line = Line2D([], [], color="0.3", lw=1.0, ls="--",
                           label="FVMS (dashed, colour of its case)")
    ax_k.set_ylabel(f"VVMS (solid), FVMS (dashed)\n{k_unit}", fontsize=_FONT_SIZE)
    lo, hi = ax_k.get_ylim()
    ax_k.set_ylim(lo, hi + 0.3 * (hi - lo))  # headroom for the zone names
    _contact_point_axis(ax_k, cycles[0])

    # load sharing: colour per case, line style per pair
    slots_seen: set[int] = set()
    for i, c in enumerate(cycles):
        for k in _loaded_slots(c):
            m = int(c.slot_offset[k])
            slots_seen.add(m)
            ax_lsr.plot(phase, _lsr_for_plot(c.load_sharing_ratio[:, k]), color=colours[i],
                        lw=1.3, ls=_pair_style(m), gid=f"lsr/{i}/{m}", zorder=2)
    run = _coincident_run([c.load_sharing_ratio for c in cycles])
    _note_coincidence(ax_lsr, phase, run, cycles[0].load_sharing_ratio.max(axis=1),
                      "same load split for every case here", below=False)
    pair_handles = [Line2D([], [], color="0.25", lw=1.3, ls=_pair_style(m), label=_pair_name(m))
                    for m in sorted(slots_seen, reverse=True)]
    ax_lsr.set_ylabel("load-sharing ratio\n$F_i/F$ (–)", fontsize=_FONT_SIZE)
    ax_lsr.set_ylim(-0.04, 1.32)
    ax_lsr.set_yticks([0.0, 0.25, 0.5, 0.75, 1.0])
    ax_lsr.legend(handles=pair_handles, loc="upper center", ncols=max(1, len(pair_handles)),
                  fontsize=_FONT_SIZE - 0.5, frameon=True, framealpha=0.9, edgecolor="none",
                  handlelength=2.6, borderaxespad=0.2, columnspacing=1.4)

    # transmission error
    for i, c in enumerate(cycles):
        ax_x.plot(phase, c.lste_m * _UM, color=colours[i], lw=1.6, gid=f"lste/{i}", zorder=2)
    ax_x.set_ylabel("LSTE $x$ (µm)", fontsize=_FONT_SIZE)
    ax_x.set_xlabel("mesh-cycle phase τ (base pitches of pinion roll; τ = 0: pair #2 at A)",
                    fontsize=_FONT_SIZE)
    ax_x.set_xlim(0.0, 1.0)
    lo, hi = ax_x.get_ylim()
    if hi - lo < 1e-3:  # a flat LSTE (T = 0 only): a line at 0, not magnified rounding
        ax_x.set_ylim(-0.5, 0.5)

    head.suptitle(title, fontsize=_FONT_SIZE + 1.5)
    head.legend(handles=[*case_handles, fvms_line], loc="outside lower center", ncols=ncols,
                title=legend_title, fontsize=_FONT_SIZE, title_fontsize=_FONT_SIZE,
                frameon=False, handlelength=2.4, columnspacing=1.6)
    return fig


def _potential_energy_compliance(gear_set: GearSet) -> TabulatedCompliance:
    pair = gear_set.pair
    return tabulate_compliance(pair, lambda s: pair_compliance(pair, s).total_m_per_N)


def _format_number(x: float) -> str:
    return f"{x:g}"


def mesh_cycle_figures(
    gear_set: str | Path | GearSet = "kahraman-blankenship",
    torques_Nm: Sequence[float] = (0.0, 100.0, 200.0, 340.0),
    reliefs: Sequence[float] = (0.0, 0.5, 1.0),
    relief_torque_Nm: float = 340.0,
    *,
    n_phases: int = 400,
) -> dict[str, Figure]:
    """The two mesh-cycle figures of seed 003 (Figs. 4 and 6(b)) for a gear set.

    The tooth-pair compliance is the potential-energy one
    (:func:`models.stiffness.pair_compliance`, Hertz included), tabulated on the path of
    contact; corner contact is modelled. The relief case without relief keeps the colour of
    the same torque in the torque figure.

    Parameters
    ----------
    gear_set : str, path or GearSet
        A shipped gear-set name, a gear-set file, or a loaded :class:`~models.geometry.GearSet`.
    torques_Nm : sequence of float
        Pinion torques (N m), >= 0, for the ``"torque"`` figure (no profile errors).
    reliefs : sequence of float
        Normalised tip-relief amounts ``Delta`` (-), >= 0, linear relief of both gears with
        ``Ln = 1``, for the ``"relief"`` figure (:func:`models.stiffness.normalised_tip_relief`;
        ``Delta = 1`` is the combined deflection at HPSTC under ``relief_torque_Nm``).
    relief_torque_Nm : float
        Pinion torque (N m) of the ``"relief"`` figure, also the design torque of the relief.
    n_phases : int
        Phases per mesh cycle (>= 16).

    Returns
    -------
    dict of str to matplotlib.figure.Figure
        ``"torque"`` and ``"relief"``, from :func:`plot_mesh_cycle`.
    """
    if not isinstance(gear_set, GearSet):
        gear_set = load_gear_set(gear_set)
    torques = [float(t) for t in torques_Nm]
    amounts = [float(d) for d in reliefs]
    if not torques:
        raise ValueError("`torques_Nm` must hold at least one torque, was empty")
    if not amounts:
        raise ValueError("`reliefs` must hold at least one relief amount, was empty")
    pair = gear_set.pair
    name = gear_set.name
    compliance = _potential_energy_compliance(gear_set)

    geo = prepare_mesh_cycle(pair, compliance, n_phases=n_phases)
    by_torque = [geo.solve(t) for t in torques]
    torque_colours = [_CASE_COLOURS[i % len(_CASE_COLOURS)] for i in range(len(torques))]
    torque_fig = plot_mesh_cycle(
        by_torque, [f"{_format_number(t)} N·m" for t in torques],
        title=f"Gear set {name}, no profile modification: effect of torque",
        legend_title="pinion torque", face_width_m=pair.face_width_m, colors=torque_colours)

    by_relief, relief_labels, relief_colours = [], [], []
    spare = iter(_RELIEF_COLOURS * (1 + len(amounts) // len(_RELIEF_COLOURS)))
    for delta in amounts:
        relief = normalised_tip_relief(pair, compliance, relief_torque_Nm, delta)
        cyc = prepare_mesh_cycle(pair, compliance, error=relief, n_phases=n_phases)
        by_relief.append(cyc.solve(relief_torque_Nm))
        if delta == 0:
            relief_labels.append("Δ = 0 (none)")
            same = [i for i, t in enumerate(torques) if t == relief_torque_Nm]
            relief_colours.append(torque_colours[same[0]] if same else next(spare))
        else:
            amount_um = relief.pinion_amount_m * _UM
            relief_labels.append(f"Δ = {_format_number(delta)} ({amount_um:.1f} µm)")
            relief_colours.append(next(spare))
    relief_fig = plot_mesh_cycle(
        by_relief, relief_labels,
        title=(f"Gear set {name} at {_format_number(relief_torque_Nm)} N·m: "
               "effect of linear tip relief (both gears, Ln = 1)"),
        legend_title="tip-relief amount (Δ = 1: combined deflection at HPSTC)",
        face_width_m=pair.face_width_m, colors=relief_colours)
    return {"torque": torque_fig, "relief": relief_fig}


def save_png(fig: Figure, path: str | Path, dpi: float = 200) -> Path:
    """Write ``fig`` as a PNG file through the Agg canvas and return its path.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
    path : str or path
        Destination; its parent directory is created if missing.
    dpi : float
        Resolution (dots per inch), > 0; 200 gives 1400 px across a 7 in figure.

    Returns
    -------
    pathlib.Path
    """
    if not isinstance(fig, Figure):
        raise ValueError(f"`fig` must be a matplotlib Figure, was {type(fig).__name__}")
    if not (math.isfinite(dpi) and dpi > 0):
        raise ValueError(f"`dpi` must be finite and > 0, was {dpi!r}")
    out = Path(path)
    out.parent.mkdir(parents=True, exist_ok=True)
    FigureCanvasAgg(fig)
    fig.savefig(out, format="png", dpi=dpi)
    return out

r"""Figure of the converged tribo-dynamic state of seed 002 (film, Lambda, friction, mesh force).

The presentation layer over :mod:`models.dynamics.tribo_ehl_coupling`:
:func:`plot_tribo_solution` takes a :class:`~models.dynamics.tribo_ehl_coupling.TriboSolution`
and returns a :class:`matplotlib.figure.Figure` on the Agg canvas (no ``pyplot``, no global
state), four stacked panels in the manner of seed 002's result figures:

1. central film thickness ``h_c`` (um) of one tooth pair along its passage over the line of
   action, dynamic (solid, converged loop) and quasi-static load share (dashed);
2. film parameter ``Lambda`` (-), with the mixed (1-3) band shaded;
3. signed friction coefficient ``f`` (-), changing sign at the pitch point;
4. dynamic mesh force (N) over one mesh cycle, with the nominal load ``W_0``.

Panels 1-3 are drawn against the position on the line of action (mm from T1), marking the
pitch point and, when the gear pair is given, the single-contact zone (LPSTC-HPSTC).
"""

from __future__ import annotations

import math
from typing import Final

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from models.dynamics.tribo_ehl_coupling import TriboSolution
from models.geometry.gear_pair import GearPair

__all__ = ["plot_tribo_solution"]

_WIDTH_IN: Final = 7.0
_HEIGHT_IN: Final = 8.6
_FONT_SIZE: Final = 8.5
_DYNAMIC: Final = "#0072B2"
_STEADY: Final = "#D55E00"
_ZONE: Final = "#E8E8E8"
_MM: Final = 1e3
_UM: Final = 1e6


def plot_tribo_solution(
    solution: TriboSolution, pair: GearPair | None = None, *, title: str | None = None
) -> Figure:
    """Film thickness, Lambda, friction coefficient and dynamic mesh force at convergence.

    Parameters
    ----------
    solution : TriboSolution
        From :func:`~models.dynamics.tribo_ehl_coupling.solve_tribo_dynamics` or
        :func:`~models.dynamics.tribo_case.solve_tribo_case`.
    pair : GearPair, optional
        The gear pair, to mark the pitch point and the single-contact zone.
    title : str, optional
        Figure title (default: iterations and last relative change).

    Returns
    -------
    matplotlib.figure.Figure
    """
    if not isinstance(solution, TriboSolution):
        raise ValueError(f"`solution` must be a TriboSolution, was {type(solution).__name__}")
    fig = Figure(figsize=(_WIDTH_IN, _HEIGHT_IN), layout="constrained")
    FigureCanvasAgg(fig)
    axes = fig.subplots(4, 1)
    fields = (
        ("film_thickness_m", _UM, "film thickness $h_c$ (µm)"),
        ("film_parameter", 1.0, r"film parameter $\Lambda$ (-)"),
        ("friction", 1.0, "friction coefficient $f$ (-)"),
    )
    for ax, (name, scale, ylabel) in zip(axes[:3], fields, strict=True):
        for contact, style, colour, label in (
            (solution.contact, "-", _DYNAMIC, "dynamic (converged)"),
            (solution.steady_contact, "--", _STEADY, "quasi-static load share"),
        ):
            s, v = contact.along_path(name)
            order = np.argsort(s, kind="stable")
            ax.plot(s[order] * _MM, v[order] * scale, style, color=colour, lw=1.2, label=label)
        ax.set_ylabel(ylabel, fontsize=_FONT_SIZE)
        ax.set_xlabel("position on the line of action from T$_1$ (mm)", fontsize=_FONT_SIZE)
        ax.tick_params(labelsize=_FONT_SIZE - 0.5)
        if pair is not None:
            ax.axvspan(
                pair.lowest_point_single_contact * _MM,
                pair.highest_point_single_contact * _MM,
                color=_ZONE,
                lw=0,
                zorder=0,
                gid="single-contact",
            )
            ax.axvline(pair.pitch_point * _MM, color="0.4", lw=0.8, ls=":", gid="pitch")
    axes[0].legend(fontsize=_FONT_SIZE - 1, loc="best")
    axes[1].axhspan(1.0, 3.0, color="#F0E442", alpha=0.25, lw=0, zorder=0, gid="mixed")
    axes[2].axhline(0.0, color="0.5", lw=0.6)
    ax = axes[3]
    ax.plot(
        solution.phase,
        solution.mesh_force_N,
        "-",
        color=_DYNAMIC,
        lw=1.2,
        label="dynamic mesh force",
    )
    ax.axhline(
        solution.model.load_N,
        color="0.3",
        lw=0.8,
        ls="--",
        label=f"nominal $W_0$ = {solution.model.load_N:.0f} N",
    )
    ax.set_xlabel("mesh-cycle phase (-)", fontsize=_FONT_SIZE)
    ax.set_ylabel("mesh force (N)", fontsize=_FONT_SIZE)
    ax.set_xlim(0, 1)
    ax.tick_params(labelsize=_FONT_SIZE - 0.5)
    ax.legend(fontsize=_FONT_SIZE - 1, loc="best")
    if title is None:
        last = float(np.max(solution.history[-1]))
        title = (
            f"tribo-dynamic state after {solution.iterations} iterations "
            f"(last relative change {last:.1e})"
        )
    fig.suptitle(title, fontsize=_FONT_SIZE + 0.5)
    if not math.isfinite(float(np.nanmax(solution.mesh_force_N))):
        raise ValueError("`solution` holds non-finite mesh forces")
    return fig

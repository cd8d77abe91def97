"""Figures for reports: result objects in, :class:`matplotlib.figure.Figure` out.

The presentation layer (STYLE.md, convention 5): plotting functions read the result objects of
``models`` and ``rigtools`` analysis and return figures drawn on the Agg canvas, without
``matplotlib.pyplot`` and its global state; nothing here computes physics of its own.

Modules: ``stiffness`` (VVMS/FVMS, load sharing and LSTE over a mesh cycle; seed 003 Figs. 4, 6).
"""

from rigtools.plots.stiffness import (
    FIGURE_WIDTH_IN,
    mesh_cycle_figures,
    plot_mesh_cycle,
    save_png,
)

__all__ = [
    "FIGURE_WIDTH_IN",
    "mesh_cycle_figures",
    "plot_mesh_cycle",
    "save_png",
]

"""Figures for reports: result objects in, :class:`matplotlib.figure.Figure` out.

The presentation layer (STYLE.md, convention 5): plotting functions read the result objects of
``models`` and ``rigtools`` analysis and return figures drawn on the Agg canvas, without
``matplotlib.pyplot`` and its global state; nothing here computes physics of its own.

Modules: ``stiffness`` (VVMS/FVMS, load sharing and LSTE over a mesh cycle; seed 003 Figs. 4, 6),
``thermal`` (thermoelastic mean mesh stiffness and mesh natural frequency against torque, with
the critical compensation gap and the jammed state; seed 000 Tables 5-6), ``dynamics`` (up/down
Arms sweeps with contact-loss markers and the jump band, Poincare bifurcation diagrams of the
SDOF models; seed 003 Figs. 8-11), ``runup`` (measured Arms against mesh frequency, up and
down, with each SDOF model's posterior predictive band and the jump frequencies: the run-up
calibration, issue 20), ``two_stage`` (peak-DTE
maps over mesh frequency x bulk temperature and bifurcation diagrams of the two-stage model;
seed 001), ``tribo`` (film thickness, Lambda, friction and mesh force at the converged
tribo-dynamic state; seed 002).
"""

from rigtools.plots.dynamics import plot_sweep, plot_sweep_bifurcation
from rigtools.plots.runup import RunUpBand, RunUpFigureData, plot_runup, write_runup_figures
from rigtools.plots.spectrum import plot_spectrum
from rigtools.plots.stiffness import (
    FIGURE_WIDTH_IN,
    mesh_cycle_figures,
    plot_mesh_cycle,
    save_png,
)
from rigtools.plots.thermal import (
    plot_natural_frequency_vs_load,
    plot_stiffness_vs_load,
    thermal_figures,
)
from rigtools.plots.tribo import plot_tribo_solution
from rigtools.plots.two_stage import plot_peak_dte_map, plot_two_stage_bifurcation

__all__ = [
    "FIGURE_WIDTH_IN",
    "RunUpBand",
    "RunUpFigureData",
    "mesh_cycle_figures",
    "plot_mesh_cycle",
    "plot_natural_frequency_vs_load",
    "plot_peak_dte_map",
    "plot_runup",
    "plot_spectrum",
    "plot_stiffness_vs_load",
    "plot_sweep",
    "plot_sweep_bifurcation",
    "plot_tribo_solution",
    "plot_two_stage_bifurcation",
    "save_png",
    "thermal_figures",
    "write_runup_figures",
]

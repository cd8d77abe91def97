"""Gear dynamics: single-DOF models with backlash and frequency sweeps (seed 003 section 3).

* :mod:`models.dynamics.sdof`: the non-dimensional equation, dead-zone backlash, and the
  FVMS / VVMS / LSTE models built from a :func:`~models.stiffness.mesh_cycle.mesh_cycle`;
* :mod:`models.dynamics.integrate`: fixed-step RK4 (numba, and a plain-Python reference);
* :mod:`models.dynamics.sweep`: up/down frequency sweeps with Arms and contact flags;
* :mod:`models.dynamics.two_stage`: the two-stage torsional model of seed 001 (two relative
  DTE coordinates, coupled through the intermediate shaft), RK4 and steady response, and the
  seed's six-state system with a flexible intermediate shaft as a plain reference;
* :mod:`models.dynamics.two_stage_maps`: peak-DTE maps over mesh frequency x bulk temperature
  (seed 001's temperature stiffness), parallel over temperature rows, and Poincare data for
  bifurcation diagrams.
"""

from models.dynamics.integrate import periods, periods_reference, periods_solve_ivp, settle
from models.dynamics.sdof import (
    MODELS,
    SDOFModel,
    dead_zone,
    dead_zone_potential,
    printed_contact_force,
    sdof_from_mesh_cycle,
)
from models.dynamics.sweep import SweepResult, steady_state, sweep, sweep_up_down
from models.dynamics.two_stage import (
    MeshStage,
    SixStateSystem,
    TwoStageModel,
    TwoStageResponse,
    disc_inertia,
    rigid_shaft_model,
    six_state_from_gear_sets,
    six_state_reference,
    static_state,
    two_stage_from_gear_sets,
    two_stage_periods,
    two_stage_periods_reference,
    two_stage_steady_response,
)
from models.dynamics.two_stage_maps import (
    Bifurcation,
    PeakDTEMap,
    ThermalStiffness,
    TwoStageThermalSetup,
    bifurcation_over_frequency,
    bifurcation_over_temperature,
    peak_dte_map,
    thermal_stiffness_component,
    two_stage_at_temperature,
)

__all__ = [
    "MODELS",
    "Bifurcation",
    "MeshStage",
    "PeakDTEMap",
    "SDOFModel",
    "SixStateSystem",
    "SweepResult",
    "ThermalStiffness",
    "TwoStageModel",
    "TwoStageResponse",
    "TwoStageThermalSetup",
    "bifurcation_over_frequency",
    "bifurcation_over_temperature",
    "dead_zone",
    "dead_zone_potential",
    "disc_inertia",
    "peak_dte_map",
    "periods",
    "periods_reference",
    "periods_solve_ivp",
    "printed_contact_force",
    "rigid_shaft_model",
    "sdof_from_mesh_cycle",
    "settle",
    "six_state_from_gear_sets",
    "six_state_reference",
    "static_state",
    "steady_state",
    "sweep",
    "sweep_up_down",
    "thermal_stiffness_component",
    "two_stage_at_temperature",
    "two_stage_from_gear_sets",
    "two_stage_periods",
    "two_stage_periods_reference",
    "two_stage_steady_response",
]

"""Gear dynamics: single-DOF models with backlash and frequency sweeps (seed 003 section 3).

* :mod:`models.dynamics.sdof`: the non-dimensional equation, dead-zone backlash, and the
  FVMS / VVMS / LSTE models built from a :func:`~models.stiffness.mesh_cycle.mesh_cycle`;
* :mod:`models.dynamics.integrate`: fixed-step RK4 (numba, and a plain-Python reference);
* :mod:`models.dynamics.sweep`: up/down frequency sweeps with Arms and contact flags;
* :mod:`models.dynamics.two_stage`: the two-stage torsional model of seed 001 (two relative
  DTE coordinates, coupled through the intermediate shaft), RK4 and steady response.
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
    TwoStageModel,
    TwoStageResponse,
    static_state,
    two_stage_from_gear_sets,
    two_stage_periods,
    two_stage_periods_reference,
    two_stage_steady_response,
)

__all__ = [
    "MODELS",
    "MeshStage",
    "SDOFModel",
    "SweepResult",
    "TwoStageModel",
    "TwoStageResponse",
    "dead_zone",
    "dead_zone_potential",
    "periods",
    "periods_reference",
    "periods_solve_ivp",
    "printed_contact_force",
    "sdof_from_mesh_cycle",
    "settle",
    "static_state",
    "steady_state",
    "sweep",
    "sweep_up_down",
    "two_stage_from_gear_sets",
    "two_stage_periods",
    "two_stage_periods_reference",
    "two_stage_steady_response",
]

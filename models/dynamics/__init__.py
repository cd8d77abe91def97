"""Gear dynamics: single-DOF models with backlash and frequency sweeps (seed 003 section 3).

* :mod:`models.dynamics.sdof`: the non-dimensional equation, dead-zone backlash, and the
  FVMS / VVMS / LSTE models built from a :func:`~models.stiffness.mesh_cycle.mesh_cycle`;
* :mod:`models.dynamics.integrate`: a model's tables, periods and settling to a periodic
  steady state from Python, with plain-Python and solve_ivp references;
* :mod:`models.dynamics.sdof_kernels`: the compiled SDOF/ITMS kernels (RK4, settling and
  period detection, recording, sweeps);
* :mod:`models.dynamics.walker_kernels`: the compiled walker sweeps (Newton shooting on the
  period-1 map with its basin check), their disk cache tied to ``sdof_kernels``;
* :mod:`models.dynamics.kernel_cache`: :func:`~models.dynamics.kernel_cache.tie_cache`, which
  flushes a module's cached kernels when a file they inline changes;
* :mod:`models.dynamics.sweep`: up/down frequency sweeps with Arms, contact flags and period
  detection, and the hysteresis (jump) bands where the up and down branches differ;
* :mod:`models.dynamics.itms`: the ITMS model (seed 003 Eq. 28), one dead-zone spring per tooth
  pair;
* :mod:`models.dynamics.back_flank`: what the back flanks carry of the drive flanks' profile
  errors, shared by the SDOF and ITMS models;
* :mod:`models.dynamics.checks`: the argument checks the modules share (counts of steps and
  periods, the settle loop's bounds);
* :mod:`models.dynamics.dimensional`: equivalent mass, omega_n, Lambda <-> Hz <-> rpm, DTE in um;
* :mod:`models.dynamics.parallel`: :func:`sweep_many`, independent sweeps in parallel (numba
  prange);
* :mod:`models.dynamics.walkers`: many parameter sets ("walkers": zeta, stiffness scale,
  fluctuation scale, backlash) of one FVMS/VVMS/LSTE model swept along a time-ordered run-up
  path in one compiled call (a :class:`CycleBank` of cycles at T / s, Newton shooting with the
  settling fallback), its plain per-walker reference and their agreement (issue 20);
* :mod:`models.dynamics.two_stage`: the two-stage torsional model of seed 001 (two relative
  DTE coordinates, coupled through the intermediate shaft), RK4 and steady response, and the
  seed's six-state system with a flexible intermediate shaft as a plain reference;
* :mod:`models.dynamics.two_stage_thermal`: the two-stage model at a bulk temperature (seed
  001's temperature stiffness, the inputs of the shipped two-stage gear sets);
* :mod:`models.dynamics.two_stage_maps`: peak-DTE maps over mesh frequency x bulk temperature,
  parallel over temperature rows, and Poincare data for bifurcation diagrams;
* :mod:`models.dynamics.two_stage_kernels`: all compiled two-stage kernels (RK4, map rows) in
  one file, so numba's disk cache cannot go stale across modules;
* :mod:`models.dynamics.tribo`, :mod:`~models.dynamics.tribo_integrate`,
  :mod:`~models.dynamics.tribo_ehl_coupling`, :mod:`~models.dynamics.tribo_case`: the six-DOF
  tribo-dynamic model of seed 002 with mixed EHL, its compiled RK4 to the periodic steady
  state (all its kernels in one file), its iterative decoupling loop, and the shipped cases
  ``seed-002-tribo`` (the seed's tables, suspect mu_r) and ``seed-002-tribo-mixed`` (mu_r =
  0.142 Pa s, reproduces the seed's statements).
"""

from models.dynamics.back_flank import BACK_FLANKS, BackFlank, back_flank_offset
from models.dynamics.dimensional import (
    DimensionalScaling,
    DimensionalSweep,
    dimensional_scaling,
    to_dimensional,
)
from models.dynamics.integrate import (
    POINCARE_POINTS,
    Settled,
    periods,
    periods_reference,
    periods_solve_ivp,
    settle,
    settle_periodic,
    static_pair_count,
)
from models.dynamics.itms import ITMSModel, itms_from_mesh_cycle
from models.dynamics.parallel import SweepJob, sweep_many
from models.dynamics.sdof import (
    MODELS,
    DynamicModel,
    PeriodicCurve,
    SDOFModel,
    dead_zone,
    dead_zone_potential,
    fvms_error_curve,
    printed_contact_force,
    sdof_from_mesh_cycle,
)
from models.dynamics.sdof_kernels import MAX_PERIOD
from models.dynamics.sweep import (
    SweepResult,
    hysteresis_band,
    hysteresis_bands,
    steady_state,
    sweep,
    sweep_up_down,
)
from models.dynamics.tribo import TriboDynamics, build_tribo_dynamics, series_stiffness
from models.dynamics.tribo_case import (
    TriboCase,
    load_tribo_case,
    shipped_tribo_cases,
    solve_tribo_case,
)
from models.dynamics.tribo_ehl_coupling import (
    ContactCycle,
    Lubrication,
    TriboSolution,
    contact_cycle,
    solve_tribo_dynamics,
    tribo_iteration,
)
from models.dynamics.tribo_integrate import (
    TriboRecord,
    tribo_periods,
    tribo_periods_reference,
    tribo_settle,
)
from models.dynamics.two_stage import (
    MAX_STEP_OMEGA,
    MeshStage,
    SixStateSystem,
    TwoStageModel,
    TwoStageResponse,
    highest_frequency_bound,
    min_steps_per_period,
    natural_frequencies,
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
    bifurcation_over_frequency,
    bifurcation_over_temperature,
    peak_dte_map,
)
from models.dynamics.two_stage_thermal import (
    ThermalStiffness,
    TwoStageThermalSetup,
    thermal_stiffness_component,
    two_stage_at_temperature,
)
from models.dynamics.walkers import (
    CycleBank,
    SweepAgreement,
    WalkerSweep,
    cycle_bank,
    sweep_agreement,
    sweep_walkers,
    sweep_walkers_reference,
)

__all__ = [
    "BACK_FLANKS",
    "MAX_PERIOD",
    "MAX_STEP_OMEGA",
    "MODELS",
    "POINCARE_POINTS",
    "BackFlank",
    "Bifurcation",
    "ContactCycle",
    "CycleBank",
    "DimensionalScaling",
    "DimensionalSweep",
    "DynamicModel",
    "ITMSModel",
    "Lubrication",
    "MeshStage",
    "PeakDTEMap",
    "PeriodicCurve",
    "SDOFModel",
    "Settled",
    "SixStateSystem",
    "SweepAgreement",
    "SweepJob",
    "SweepResult",
    "ThermalStiffness",
    "TriboCase",
    "TriboDynamics",
    "TriboRecord",
    "TriboSolution",
    "TwoStageModel",
    "TwoStageResponse",
    "TwoStageThermalSetup",
    "WalkerSweep",
    "back_flank_offset",
    "bifurcation_over_frequency",
    "bifurcation_over_temperature",
    "build_tribo_dynamics",
    "contact_cycle",
    "cycle_bank",
    "dead_zone",
    "dead_zone_potential",
    "dimensional_scaling",
    "fvms_error_curve",
    "highest_frequency_bound",
    "hysteresis_band",
    "hysteresis_bands",
    "itms_from_mesh_cycle",
    "load_tribo_case",
    "min_steps_per_period",
    "natural_frequencies",
    "peak_dte_map",
    "periods",
    "periods_reference",
    "periods_solve_ivp",
    "printed_contact_force",
    "rigid_shaft_model",
    "sdof_from_mesh_cycle",
    "series_stiffness",
    "settle",
    "settle_periodic",
    "shipped_tribo_cases",
    "six_state_from_gear_sets",
    "six_state_reference",
    "solve_tribo_case",
    "solve_tribo_dynamics",
    "static_pair_count",
    "static_state",
    "steady_state",
    "sweep",
    "sweep_agreement",
    "sweep_many",
    "sweep_up_down",
    "sweep_walkers",
    "sweep_walkers_reference",
    "thermal_stiffness_component",
    "to_dimensional",
    "tribo_iteration",
    "tribo_periods",
    "tribo_periods_reference",
    "tribo_settle",
    "two_stage_at_temperature",
    "two_stage_from_gear_sets",
    "two_stage_periods",
    "two_stage_periods_reference",
    "two_stage_steady_response",
]

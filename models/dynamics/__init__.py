"""Gear dynamics: single-DOF models with backlash and frequency sweeps (seed 003 section 3).

* :mod:`models.dynamics.sdof`: the non-dimensional equation, dead-zone backlash, and the
  FVMS / VVMS / LSTE models built from a :func:`~models.stiffness.mesh_cycle.mesh_cycle`;
* :mod:`models.dynamics.integrate`: fixed-step RK4 (numba, and a plain-Python reference);
* :mod:`models.dynamics.sweep`: up/down frequency sweeps with Arms and contact flags.
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

__all__ = [
    "MODELS",
    "SDOFModel",
    "SweepResult",
    "dead_zone",
    "dead_zone_potential",
    "periods",
    "periods_reference",
    "periods_solve_ivp",
    "printed_contact_force",
    "sdof_from_mesh_cycle",
    "settle",
    "steady_state",
    "sweep",
    "sweep_up_down",
]

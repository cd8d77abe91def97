"""Thermal effects on spur gear meshing (seeds 000 and 001).

Contact temperature, thermal expansion, and the thermoelastic-backlash mesh stiffness with its
critical compensation gap.

Modules: ``flash`` (Blok's flash temperature along the path of contact with the thermal
effusivity, the Hertzian half-width, the frictional heat flux ``q = gamma p f V``; seeds 001 and
000), ``reference_state`` (what the temperatures of a thermal deformation count from, and what
the centre distance does; SEED-NOTES 8), ``expansion`` (thermal normal deformation of the
flanks along the line of action, seed 000's ``Delta r_k`` reconstructed with an angular update
that keeps similarity; seed 001's temperature stiffness), ``thermoelastic`` (seed 000's
thermoelastic pair stiffness with backlash, the critical compensation gap ``c* = (1 - chi)
(Delta_1 + Delta_2)``, Table 5's regimes, the jammed state; the thermal closure is an input),
``natural_frequency`` (mesh natural frequency from the cycle-mean thermoelastic stiffness and the
gears' equivalent mass, prepared once and vectorised over runs and parameter sets),
``torque_sweep`` (seed 000's hot-state thermal closure and the mean stiffness and natural
frequency swept over torque and backlash at it, with the jammed torque ranges; drawn by
:mod:`rigtools.plots.thermal`), ``checks`` (the argument checks the modules share).
"""

from models.geometry.inertia import equivalent_mass, gear_inertia
from models.thermal.expansion import (
    DEFAULT_BORE_FRACTION,
    FlankDeformation,
    GearTemperature,
    TemperatureStiffness,
    ThermalDeformation,
    disc_mean_temperature_rise,
    disc_rim_expansion,
    temperature_stiffness,
    thermal_deformation,
)
from models.thermal.flash import (
    BLOK_COEFFICIENT_HERTZIAN,
    BLOK_COEFFICIENT_SEED_001,
    ETA_SEED_001,
    FRICTION_SEED_000,
    HEAT_CONVERSION_SEED_000,
    FlashTemperature,
    blok_flash_temperature,
    flash_temperature,
    frictional_heat_flux,
    hertz_half_width,
    thermal_effusivity,
)
from models.thermal.natural_frequency import (
    JAMMED_MODELS,
    JammedModel,
    NaturalFrequency,
    NaturalFrequencyModel,
    mesh_natural_frequency,
    mesh_natural_frequency_scalar,
    prepare_natural_frequency,
)
from models.thermal.reference_state import HOUSING_MODELS, HousingModel, ThermalReference
from models.thermal.thermoelastic import (
    CRITICAL_GAP_ATOL_M,
    FALLS,
    JAMMED_STAND_IN,
    RISES,
    SEED_000_CHI,
    UNCHANGED,
    CriticalGapSearch,
    DoubleFlankContact,
    ThermalJamError,
    ThermoelasticStiffness,
    critical_gap,
    critical_gap_numerical,
    double_flank_contact,
    elastic_backlash_stiffness,
    stiffness_regime,
    thermoelastic_mesh_stiffness,
    thermoelastic_pair_stiffness,
    thermoelastic_stiffness,
)
from models.thermal.torque_sweep import (
    TABLE_6_TORQUES_NM,
    JamSpan,
    ThermalClosure,
    ThermalSweep,
    default_backlash,
    jammed_torque_spans,
    seed_000_hot_state_closure,
    thermal_sweep,
    torque_grid,
)

__all__ = [
    "BLOK_COEFFICIENT_HERTZIAN",
    "BLOK_COEFFICIENT_SEED_001",
    "CRITICAL_GAP_ATOL_M",
    "DEFAULT_BORE_FRACTION",
    "ETA_SEED_001",
    "FALLS",
    "FRICTION_SEED_000",
    "HEAT_CONVERSION_SEED_000",
    "HOUSING_MODELS",
    "JAMMED_MODELS",
    "JAMMED_STAND_IN",
    "RISES",
    "SEED_000_CHI",
    "TABLE_6_TORQUES_NM",
    "UNCHANGED",
    "CriticalGapSearch",
    "DoubleFlankContact",
    "FlankDeformation",
    "FlashTemperature",
    "GearTemperature",
    "HousingModel",
    "JamSpan",
    "JammedModel",
    "NaturalFrequency",
    "NaturalFrequencyModel",
    "TemperatureStiffness",
    "ThermalClosure",
    "ThermalDeformation",
    "ThermalJamError",
    "ThermalReference",
    "ThermalSweep",
    "ThermoelasticStiffness",
    "blok_flash_temperature",
    "critical_gap",
    "critical_gap_numerical",
    "default_backlash",
    "disc_mean_temperature_rise",
    "disc_rim_expansion",
    "double_flank_contact",
    "elastic_backlash_stiffness",
    "equivalent_mass",
    "flash_temperature",
    "frictional_heat_flux",
    "gear_inertia",
    "hertz_half_width",
    "jammed_torque_spans",
    "mesh_natural_frequency",
    "mesh_natural_frequency_scalar",
    "prepare_natural_frequency",
    "seed_000_hot_state_closure",
    "stiffness_regime",
    "temperature_stiffness",
    "thermal_deformation",
    "thermal_effusivity",
    "thermal_sweep",
    "thermoelastic_mesh_stiffness",
    "thermoelastic_pair_stiffness",
    "thermoelastic_stiffness",
    "torque_grid",
]

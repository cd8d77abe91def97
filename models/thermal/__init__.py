"""Thermal effects on spur gear meshing (seeds 000 and 001).

Contact temperature, thermal expansion, and the thermoelastic-backlash mesh stiffness with its
critical compensation gap.

Modules: ``flash`` (Blok's flash temperature along the path of contact with the thermal
effusivity, the Hertzian half-width, the frictional heat flux ``q = gamma p f V``; seeds 001 and
000), ``reference_state`` (what the temperatures of a thermal deformation count from, and what
the centre distance does; SEED-NOTES 8), ``expansion`` (thermal normal deformation of the
flanks along the line of action, seed 000's ``Delta r_k`` reconstructed with an angular update
that keeps similarity; seed 001's temperature stiffness).
"""

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
from models.thermal.reference_state import HOUSING_MODELS, HousingModel, ThermalReference

__all__ = [
    "BLOK_COEFFICIENT_HERTZIAN",
    "BLOK_COEFFICIENT_SEED_001",
    "DEFAULT_BORE_FRACTION",
    "ETA_SEED_001",
    "FRICTION_SEED_000",
    "HEAT_CONVERSION_SEED_000",
    "HOUSING_MODELS",
    "FlankDeformation",
    "FlashTemperature",
    "GearTemperature",
    "HousingModel",
    "TemperatureStiffness",
    "ThermalDeformation",
    "ThermalReference",
    "blok_flash_temperature",
    "disc_mean_temperature_rise",
    "disc_rim_expansion",
    "flash_temperature",
    "frictional_heat_flux",
    "hertz_half_width",
    "temperature_stiffness",
    "thermal_deformation",
    "thermal_effusivity",
]

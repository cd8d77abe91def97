"""Spur gear pair geometry: radii, pressure angles, contact ratio, the path of contact."""

from models.geometry.gear_pair import STEEL, Gear, GearPair, Material
from models.geometry.gear_sets import GearSet, load_gear_set, shipped_gear_sets
from models.geometry.inertia import (
    DEFAULT_BORE_FRACTION,
    EQUIVALENT_MASS_CONVENTION,
    DiscRadius,
    equivalent_mass,
    gear_inertia,
    pair_equivalent_mass,
)
from models.geometry.involute import inv, inv_inverse
from models.geometry.kinematics import (
    check_teeth,
    mesh_frequency_Hz,
    speed_rpm_from_mesh_frequency,
)

__all__ = [
    "DEFAULT_BORE_FRACTION",
    "EQUIVALENT_MASS_CONVENTION",
    "STEEL",
    "DiscRadius",
    "Gear",
    "GearPair",
    "GearSet",
    "Material",
    "check_teeth",
    "equivalent_mass",
    "gear_inertia",
    "inv",
    "inv_inverse",
    "load_gear_set",
    "mesh_frequency_Hz",
    "pair_equivalent_mass",
    "shipped_gear_sets",
    "speed_rpm_from_mesh_frequency",
]

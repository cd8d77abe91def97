"""Spur gear pair geometry: radii, pressure angles, contact ratio, the path of contact."""

from models.geometry.gear_pair import STEEL, Gear, GearPair, Material
from models.geometry.gear_sets import GearSet, load_gear_set, shipped_gear_sets
from models.geometry.involute import inv, inv_inverse
from models.geometry.kinematics import (
    check_teeth,
    mesh_frequency_Hz,
    speed_rpm_from_mesh_frequency,
)

__all__ = [
    "STEEL",
    "Gear",
    "GearPair",
    "GearSet",
    "Material",
    "check_teeth",
    "inv",
    "inv_inverse",
    "load_gear_set",
    "mesh_frequency_Hz",
    "shipped_gear_sets",
    "speed_rpm_from_mesh_frequency",
]

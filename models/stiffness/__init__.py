"""Tooth and mesh stiffness of spur gear pairs.

Modules: ``ishikawa`` (Ishikawa's equivalent-tooth deflection, single-tooth and pair stiffness,
mean mesh stiffness), ``load_distribution`` (seed 000's load sharing R(theta), the normal load
from torque, the 52 points on the path of contact). Other stiffness modules re-export their
names here as they land.
"""

from models.stiffness.ishikawa import (
    HERTZ_OPTIONS,
    EquivalentTooth,
    HertzOption,
    IshikawaDeflection,
    ToothPairStiffness,
    equivalent_tooth,
    form_radius,
    ishikawa_deflection,
    ishikawa_terms,
    mean_mesh_stiffness,
    tooth_pair_stiffness,
)
from models.stiffness.load_distribution import (
    SEED_000_SHARE_AT_ENDS,
    SEED_000_SHARE_AT_SINGLE_ZONE,
    contact_path_positions,
    load_share_seed_000,
    normal_load_from_torque,
    normal_load_seed_000,
    normalised_position,
)

__all__ = [
    "HERTZ_OPTIONS",
    "SEED_000_SHARE_AT_ENDS",
    "SEED_000_SHARE_AT_SINGLE_ZONE",
    "EquivalentTooth",
    "HertzOption",
    "IshikawaDeflection",
    "ToothPairStiffness",
    "contact_path_positions",
    "equivalent_tooth",
    "form_radius",
    "ishikawa_deflection",
    "ishikawa_terms",
    "load_share_seed_000",
    "mean_mesh_stiffness",
    "normal_load_from_torque",
    "normal_load_seed_000",
    "normalised_position",
    "tooth_pair_stiffness",
]

"""Tooth and mesh stiffness of spur gear pairs.

Modules: ``ishikawa`` (Ishikawa's equivalent-tooth deflection, single-tooth and pair stiffness,
mean mesh stiffness; seed 000), ``potential_energy`` (tooth-pair compliance by the potential
energy method with fillet foundation; seed 003 section 2.1), ``hertz`` (linearised line-contact
stiffness), ``load_distribution`` (seed 000's load sharing R(theta), the normal load from
torque, the 52 points on the path of contact).
"""

from models.stiffness.hertz import contact_modulus, hertz_compliance, hertz_stiffness
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
from models.stiffness.potential_energy import (
    DEFAULT_NODES,
    Integration,
    PairCompliance,
    ToothCompliance,
    pair_compliance,
    pair_stiffness,
    tooth_compliance,
    tooth_stiffness,
)

__all__ = [
    "DEFAULT_NODES",
    "HERTZ_OPTIONS",
    "SEED_000_SHARE_AT_ENDS",
    "SEED_000_SHARE_AT_SINGLE_ZONE",
    "EquivalentTooth",
    "HertzOption",
    "Integration",
    "IshikawaDeflection",
    "PairCompliance",
    "ToothCompliance",
    "ToothPairStiffness",
    "contact_modulus",
    "contact_path_positions",
    "equivalent_tooth",
    "form_radius",
    "hertz_compliance",
    "hertz_stiffness",
    "ishikawa_deflection",
    "ishikawa_terms",
    "load_share_seed_000",
    "mean_mesh_stiffness",
    "normal_load_from_torque",
    "normal_load_seed_000",
    "normalised_position",
    "pair_compliance",
    "pair_stiffness",
    "tooth_compliance",
    "tooth_pair_stiffness",
    "tooth_stiffness",
]

"""Tooth and mesh stiffness of spur gear pairs.

Modules: ``ishikawa`` (Ishikawa's equivalent-tooth deflection, single-tooth and pair stiffness,
mean mesh stiffness; seed 000), ``potential_energy`` (tooth-pair compliance by the potential
energy method with fillet foundation; seed 003 section 2.1), ``hertz`` (linearised line-contact
stiffness), ``load_distribution`` (seed 000's load sharing R(theta), the normal load from
torque, the 52 points on the path of contact), ``load_sharing`` (compatibility solution for n
pairs with profile errors; seed 003 Eqs. 5-8), ``corner_contact`` (exact separation distances
and the case logic of seed 003 Eqs. 9-17), ``tip_relief`` (linear, parabolic I and II relief,
normalised amount and length), ``mesh_cycle`` (FVMS, VVMS and LSTE over a mesh cycle, with
Fourier coefficients; seed 003 Eqs. 18-20).
"""

from models.stiffness.corner_contact import ncr_corner_contact, separation_distance
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
from models.stiffness.load_sharing import (
    LoadSharing,
    load_sharing_closed_form,
    load_sharing_two_pairs,
    solve_load_sharing,
)
from models.stiffness.mesh_cycle import (
    Harmonics,
    MeshCycle,
    MeshCycleGeometry,
    TabulatedCompliance,
    ToothPairHistory,
    mesh_cycle,
    prepare_mesh_cycle,
    tabulate_compliance,
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
from models.stiffness.tip_relief import (
    RELIEF_SHAPES,
    ReliefShape,
    TipRelief,
    normalised_tip_relief,
    reference_relief_amount,
    relief_shape,
    tip_relief,
)

__all__ = [
    "DEFAULT_NODES",
    "HERTZ_OPTIONS",
    "RELIEF_SHAPES",
    "SEED_000_SHARE_AT_ENDS",
    "SEED_000_SHARE_AT_SINGLE_ZONE",
    "EquivalentTooth",
    "Harmonics",
    "HertzOption",
    "Integration",
    "IshikawaDeflection",
    "LoadSharing",
    "MeshCycle",
    "MeshCycleGeometry",
    "PairCompliance",
    "ReliefShape",
    "TabulatedCompliance",
    "TipRelief",
    "ToothCompliance",
    "ToothPairHistory",
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
    "load_sharing_closed_form",
    "load_sharing_two_pairs",
    "mean_mesh_stiffness",
    "mesh_cycle",
    "ncr_corner_contact",
    "normal_load_from_torque",
    "normal_load_seed_000",
    "normalised_position",
    "normalised_tip_relief",
    "pair_compliance",
    "pair_stiffness",
    "prepare_mesh_cycle",
    "reference_relief_amount",
    "relief_shape",
    "separation_distance",
    "solve_load_sharing",
    "tabulate_compliance",
    "tip_relief",
    "tooth_compliance",
    "tooth_pair_stiffness",
    "tooth_stiffness",
]

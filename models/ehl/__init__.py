"""Mixed elastohydrodynamic lubrication of a spur tooth contact (seed 002).

Modules: ``lubricant`` (Doolittle-Tait viscosity ``mu(p, T)``, Carreau effective viscosity),
``film`` (Moes' line-contact central film with the thermal factor ``C_t``, the film parameter
``Lambda``, the film stiffness ``k_h = -dF/dh_c``), ``asperity`` (Greenwood-Tripp ``F_n``
integrals and asperity pressure, the film/asperity load split ``gamma_1, gamma_2`` by bisection,
the signed mixed friction coefficient). The six-DOF dynamics and the decoupling loop
that use them are in :mod:`models.dynamics.tribo` and :mod:`models.dynamics.tribo_ehl_coupling`.
"""

from models.ehl.asperity import (
    ETA_BETA_SIGMA_DEFAULT,
    SEED_002_ROUGHNESS,
    MixedContact,
    Roughness,
    asperity_pressure,
    greenwood_tripp_integral,
    mixed_contact,
    mixed_contact_along_path,
    mixed_film_stiffness,
)
from models.ehl.film import (
    FilmState,
    central_film_thickness,
    composite_roughness,
    film_parameter,
    film_stiffness,
    film_stiffness_from_steps,
    moes_central_film,
    moes_groups,
    thermal_reduction_factor,
)
from models.ehl.lubricant import SEED_002_LUBRICANT, Lubricant

__all__ = [
    "ETA_BETA_SIGMA_DEFAULT",
    "SEED_002_LUBRICANT",
    "SEED_002_ROUGHNESS",
    "FilmState",
    "Lubricant",
    "MixedContact",
    "Roughness",
    "asperity_pressure",
    "central_film_thickness",
    "composite_roughness",
    "film_parameter",
    "film_stiffness",
    "film_stiffness_from_steps",
    "greenwood_tripp_integral",
    "mixed_contact",
    "mixed_contact_along_path",
    "mixed_film_stiffness",
    "moes_central_film",
    "moes_groups",
    "thermal_reduction_factor",
]

r"""The thermal reference state: what the temperatures of a thermal deformation count from.

The thermal closure ``Delta_1 + Delta_2`` of a drive-side flank pair, and with it seed 000's
critical compensation gap ``c* = (1 - chi)(Delta_1 + Delta_2)``, depends on two choices the
seed leaves open (SEED-NOTES 8). :class:`ThermalReference` makes them explicit inputs of
:func:`models.thermal.thermal_deformation`:

``reference_temperature_C``
    The temperature at which the gears have their nominal geometry and the backlash ``c`` is
    defined (assembly, typically 20 deg C). Every gear temperature counts from it.
``housing``
    ``"fixed-centre-distance"``: the shafts keep the nominal centre distance ``a'``, so a
    uniform rise ``dT`` of both gears closes the drive-side flank gap by
    ``xi dT (rho_1 + rho_2) = xi dT a' sin(alpha')`` (each flank moves along its own normal by
    ``xi dT rho_i``, :mod:`models.thermal.expansion`).
    ``"follows-oil"``: the housing (and so the centre distance) is at the oil temperature; the
    centre distance grows by ``Delta a = xi_h (t_oil - t_ref) a'``, which opens the drive-side
    gap by ``Delta a sin(alpha')`` (the component of the wheel-centre shift along the line of
    action). With ``xi_h = xi`` only the gears' excess over the oil counts: gears uniformly at
    the oil temperature have ``Delta_1 + Delta_2 = 0`` exactly. (Equivalently,
    ``fixed-centre-distance`` with the reference temperature set to the oil temperature.)
``flash_counts_as_local_rise``
    Whether the flash temperature (:func:`models.thermal.flash_temperature`) is added to the
    local rise ``Delta t_k`` of the tooth at the contact point (seed 000 heats the tooth with
    the frictional flux, and its ``Delta t_k`` is "the temperature rise at point k"), or the
    flanks carry only the bulk field.

Which reading reproduces seed 000 (FZG-C)
-----------------------------------------
Seed 000 runs its FZG tests at 90 deg C oil (Table 6; 183.4 and 302 N m), computes thermal
deformations "on the order of 1e-6 m" and a critical gap "approximately 10 um"; a companion
module derives ``c* = (1 - chi)(Delta_1 + Delta_2)`` with ``chi = 0.0285``. Take the gears at
the oil temperature (bore = base circle = 90 deg C), an assembly (reference) temperature of
20 deg C, 302 N m, 1500 rpm, ``f = 0.132``, seed 000's load share and the seed-001 flash
temperature (4 to 182 K along the 52 points of the path; 0 at the pitch point itself). The mean
of ``Delta_1 + Delta_2`` over the path (range in brackets) is, from
:func:`models.thermal.thermal_deformation` and asserted in
``tests/models/test_thermal_expansion.py``:

=======================================  ===========  ====================  =====================
reading                                  flash        xi = 1.15e-5 /K       xi = 3.43e-5 /K
=======================================  ===========  ====================  =====================
fixed centre distance, from 20 deg C     no           28.1 um (uniform)     83.9 um (uniform)
fixed centre distance, from 20 deg C     local rise   38.7 um (28.5-48.2)   115 um (85-144)
housing follows the oil (90 deg C)       no           0                     0
housing follows the oil (90 deg C)       local rise   10.6 um (0.4-20.1)    31.5 um (1.3-60)
=======================================  ===========  ====================  =====================

Only the housing that follows the oil, with the flash temperature counted as the local rise and
steel's ``xi = 1.15e-5 /K``, reproduces both statements: per-flank deformations ``Delta_1``,
``Delta_2`` of 0.2-11.5 um, and ``c* = 0.9715 x 10.6 = 10.3 um`` (7.1 um at 183.4 N m,
12.2 um at the seed's 381.96 N m). A fixed centre distance counted from the assembly
temperature gives 27 um of ``c*`` before any flash; the printed coefficient read as
3.43e-5 /K triples every number (``c*`` 31 um under the one reading that otherwise fits), and
read literally as 3.43e-5 % per kelvin (3.43e-7 /K) it gives at most 1.4 um. So the seed's
numbers are consistent with ``xi = 1.15e-5 /K``, temperatures counted from the oil, and the
flash temperature acting on the flank.

That reading is what the seed's numbers imply, not what the physics recommends: a flash
temperature lasts about ``2 b / v`` (tens of microseconds) and penetrates some
``sqrt(kappa 2 b / v)`` (about 10 um) into the flank, so it cannot expand the tooth between
the base circle and the contact point as the seed's ``Delta t_k xi (r_k - r_b)`` lets it. A
steady surface-temperature rise from a thermal network or FE model (seed 000's "high-low-high"
field) is the physically meaningful ``Delta t_k``; pass it as ``GearTemperature.local_rise_K``
with ``flash_counts_as_local_rise=False``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Final, Literal

from models.errors import ModelError

__all__ = ["HOUSING_MODELS", "HousingModel", "ThermalReference"]

HousingModel = Literal["fixed-centre-distance", "follows-oil"]
#: The housing readings :class:`ThermalReference` accepts.
HOUSING_MODELS: Final[tuple[str, ...]] = ("fixed-centre-distance", "follows-oil")


@dataclass(frozen=True)
class ThermalReference:
    """What gear temperatures count from, and what the centre distance does (SEED-NOTES 8).

    Parameters
    ----------
    reference_temperature_C : float
        Temperature of the nominal geometry (assembly), at which the backlash is defined
        (deg C).
    housing : {"fixed-centre-distance", "follows-oil"}
        Whether the centre distance stays nominal, or grows with a housing at the oil
        temperature.
    oil_temperature_C : float or None
        Oil (and housing) temperature (deg C); required for ``"follows-oil"``, ignored
        otherwise.
    flash_counts_as_local_rise : bool
        Add the flash temperature to the local rise ``Delta t_k`` of the flank at the
        contact point.
    housing_expansion_per_K : float or None
        Linear expansion coefficient of the housing (1/K); None takes the gears' (the
        pinion's) coefficient, so that gears at the oil temperature give zero closure.

    Examples
    --------
    >>> ref = ThermalReference(20.0, "follows-oil", oil_temperature_C=90.0)
    >>> round(ref.centre_distance_change(0.0915, 1.15e-5) * 1e6, 3)  # um
    73.657
    >>> ThermalReference(20.0).centre_distance_change(0.0915, 1.15e-5)
    0.0
    """

    reference_temperature_C: float
    housing: HousingModel = "fixed-centre-distance"
    oil_temperature_C: float | None = None
    flash_counts_as_local_rise: bool = False
    housing_expansion_per_K: float | None = None

    def __post_init__(self) -> None:
        t = self.reference_temperature_C
        if isinstance(t, bool) or not isinstance(t, int | float) or not math.isfinite(t) \
                or t <= -273.15:
            raise ModelError(f"`reference_temperature_C` must be a finite temperature above "
                             f"absolute zero, was {t!r}")
        if self.housing not in HOUSING_MODELS:
            raise ModelError(f"`housing` must be one of {', '.join(HOUSING_MODELS)}, "
                             f"was {self.housing!r}")
        if self.housing == "follows-oil":
            oil = self.oil_temperature_C
            if oil is None:
                raise ModelError("`oil_temperature_C` is required when `housing` is "
                                 "'follows-oil', was None")
            if isinstance(oil, bool) or not isinstance(oil, int | float) \
                    or not math.isfinite(oil) or oil <= -273.15:
                raise ModelError(f"`oil_temperature_C` must be a finite temperature above "
                                 f"absolute zero, was {oil!r}")
        if not isinstance(self.flash_counts_as_local_rise, bool):
            raise ModelError(f"`flash_counts_as_local_rise` must be a bool, was "
                             f"{self.flash_counts_as_local_rise!r}")
        xi = self.housing_expansion_per_K
        if xi is not None and not (math.isfinite(xi) and 0 <= xi < 1e-3):
            raise ModelError(f"`housing_expansion_per_K` must lie in [0, 1e-3) 1/K, was {xi!r}")

    def centre_distance_change(self, centre_distance_m: float,
                               gear_expansion_per_K: float) -> float:
        r"""Growth of the centre distance from its nominal value (m).

        Parameters
        ----------
        centre_distance_m : float
            Nominal operating centre distance ``a'`` (m).
        gear_expansion_per_K : float
            Coefficient used when ``housing_expansion_per_K`` is None (1/K).

        Returns
        -------
        float
            0 for ``"fixed-centre-distance"``;
            ``Delta a = xi_h (t_oil - t_ref) a'`` for ``"follows-oil"``.
        """
        if self.housing == "fixed-centre-distance":
            return 0.0
        xi = self.housing_expansion_per_K if self.housing_expansion_per_K is not None \
            else gear_expansion_per_K
        oil = self.oil_temperature_C
        if oil is None:  # unreachable: __post_init__ requires it for "follows-oil"
            raise ModelError("`oil_temperature_C` is required when `housing` is 'follows-oil'")
        return xi * (oil - self.reference_temperature_C) * centre_distance_m

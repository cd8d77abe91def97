r"""Blok's flash temperature along the path of contact, the Hertzian band, frictional heat flux.

Seed 001 writes the contact temperature of a spur tooth pair as the bulk temperature plus
Blok's flash temperature, and seed 000 heats its finite-element tooth with the frictional heat
flux ``q = gamma p f V``. This module gives both, vectorised over positions on the line of
action (and over torques, speeds and bulk temperatures by NumPy broadcasting).

Blok's flash temperature
------------------------
For two surfaces sliding through a band-shaped contact of half-width ``b`` at high Péclet
number (heat penetrates a depth small against ``b`` while a surface point crosses the band),
each surface sees a one-dimensional transient conduction problem; Blok (1937) postulates that
both surfaces reach the same maximum temperature and splits the heat accordingly. The result is

.. math::

    \Delta\vartheta_f = u \, \frac{f \, w \, |v_1 - v_2|}
        {\left(\sqrt{\lambda_1 \rho_1 c_1 v_1} + \sqrt{\lambda_2 \rho_2 c_2 v_2}\right)
         \sqrt{b}}

with the friction coefficient ``f``, the normal load per unit face width ``w`` (N/m), the
tangential (rolling) velocities ``v_i = omega_i rho_i`` of the surfaces relative to the
contact (m/s), and the *thermal effusivity* (Blok's "thermal contact coefficient")
``B_i = sqrt(lambda_i rho_i c_i)`` (W s^1/2 m^-2 K^-1).

**Deviation from the seed (SEED-NOTES 12).** Seed 001 prints the denominator as
``g_i sqrt(rho_i c_i v_i)`` with the conductivity ``g_i`` *outside* the root. In SI base
units that form gives kg^-1/2 m^-1/2 s^3/2 K^3/2 instead of K, and its value depends on the
unit system the inputs are given in (both shown in ``tests/models/test_flash_temperature.py``):
for FZG-C steel it is ``sqrt(lambda) = 6.5`` times too small. The effusivity
``sqrt(lambda rho c)`` is implemented.

**The coefficient u.** Integrating the surface temperature of a half-space under a moving band
source at high Péclet number gives, with the *half*-width ``b`` in the formula above,
``u = sqrt(2/pi) = 0.798`` for a uniform heat flux and ``u = 0.786`` for the semi-elliptic
(Hertzian) distribution a constant friction coefficient produces; the latter is Blok's 1.11
written for the full band width ``2 b`` (``1.11 / sqrt(2) = 0.785``). Seed 001 takes
``u = 0.83`` "for spur gears", 5.6 % above Blok's value; 0.83 is the default here
(:data:`BLOK_COEFFICIENT_SEED_001`) and :data:`BLOK_COEFFICIENT_HERTZIAN` is available. The
test suite recomputes both theoretical values by numerical integration.

The Hertzian half-width
-----------------------
For two cylinders in line contact (Hertz; Johnson 1985, ch. 4) the half-width is

.. math::

    b_H = \sqrt{\frac{8 w R'}{\pi E'}} = \sqrt{\frac{4 w R'}{\pi E^*}}, \qquad
    \frac{1}{R'} = \frac{1}{\rho_1} + \frac{1}{\rho_2}, \qquad
    \frac{2}{E'} = \frac{1}{E^*} = \frac{1 - \nu_1^2}{E_1} + \frac{1 - \nu_2^2}{E_2},

with the profile radii of curvature ``rho_i`` at the contact point. Seed 001 writes
``B = eta sqrt(2 (1 - mu^2) / E * F / b * R1 R2 / (R1 + R2))`` with ``eta`` unstated
(SEED-NOTES 13); for equal materials ``2 (1 - mu^2) / E = 1 / E*``, so ``B`` is the Hertzian
half-width exactly when ``eta = 2 / sqrt(pi) = 1.128`` (:data:`ETA_SEED_001`), which is what
is used. The maximum and mean Hertz pressures are ``p_0 = 2 w / (pi b)`` and
``p_m = w / (2 b) = pi p_0 / 4``.

Frictional heat flux (seed 000)
-------------------------------
.. math:: q = \gamma \, p \, f \, |v_1 - v_2|

with the heat conversion coefficient ``gamma = 0.9`` of seed 000 and ``p`` taken as the **mean**
Hertz pressure ``p_m = w / (2 b)``, so that ``2 b q`` is ``gamma`` times the frictional power
per unit face width ``f w |v_1 - v_2|`` (with ``p_0`` it would be ``4/pi`` times more than
the friction dissipates). Blok's postulate splits it between the flanks in the ratio
``B_1 sqrt(v_1) : B_2 sqrt(v_2)``.

Load along the path
-------------------
``w = F_n R / b``: the exact normal load ``F_n = T_1 / r_b1``
(:func:`models.stiffness.normal_load_from_torque`) times the load share ``R`` of the tooth
pair, by default seed 000's ``R(theta)`` (:func:`models.stiffness.load_share_seed_000`),
or a given share (``1.0`` for the whole load on one pair, as seed 001's ``F/b`` reads).
Seed 000 measured ``f = 0.132`` on an SRV tester (:data:`FRICTION_SEED_000`).

References
----------
.. [1] H. Blok, "Theoretical study of temperature rise at surfaces of actual contact under
   oiliness lubricating conditions", Proc. General Discussion on Lubrication, IMechE, London,
   1937, vol. 2, pp. 222-235.
.. [2] J. C. Jaeger, "Moving sources of heat and the temperature at sliding contacts",
   Proc. R. Soc. N.S.W. 76 (1942) 203-224.
.. [3] T. A. Stolarski, *Tribology in Machine Design*, Heinemann Newnes, 1990, ch. 3 (Blok's
   formulas with 1.11 for the full band width, semi-elliptic heat source).
.. [4] K. L. Johnson, *Contact Mechanics*, Cambridge University Press, 1985, ch. 4.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike

from models.errors import ModelError
from models.geometry.gear_pair import GearPair
from models.stiffness.hertz import contact_modulus
from models.stiffness.load_distribution import load_share_seed_000, normal_load_from_torque
from models.thermal.checks import as_finite

__all__ = [
    "BLOK_COEFFICIENT_HERTZIAN",
    "BLOK_COEFFICIENT_SEED_001",
    "ETA_SEED_001",
    "FRICTION_SEED_000",
    "HEAT_CONVERSION_SEED_000",
    "FlashTemperature",
    "blok_flash_temperature",
    "flash_temperature",
    "frictional_heat_flux",
    "hertz_half_width",
    "thermal_effusivity",
]

#: Seed 001's temperature-rise coefficient u for spur gears (-).
BLOK_COEFFICIENT_SEED_001 = 0.83
#: Blok's coefficient for a semi-elliptic (Hertzian) heat source, written with the half-width:
#: 1.11 / sqrt(2) (-).
BLOK_COEFFICIENT_HERTZIAN = 1.11 / math.sqrt(2.0)
#: The eta that makes seed 001's B the Hertzian half-width of a line contact: 2 / sqrt(pi) (-).
ETA_SEED_001 = 2.0 / math.sqrt(math.pi)
#: Seed 000's heat conversion coefficient gamma (share of the friction power that heats the
#: teeth) (-).
HEAT_CONVERSION_SEED_000 = 0.9
#: Friction coefficient measured on an SRV tester in seed 000 (-).
FRICTION_SEED_000 = 0.132


def _nonnegative(name: str, value: ArrayLike) -> np.ndarray:
    a = as_finite(name, value)
    if np.any(a < 0):
        raise ModelError(f"`{name}` must be >= 0, was {float(a.min()):.6g} (minimum)")
    return a


def _positive(name: str, value: ArrayLike) -> np.ndarray:
    a = as_finite(name, value)
    if np.any(a <= 0):
        raise ModelError(f"`{name}` must be > 0, was {float(a.min()):.6g} (minimum)")
    return a


def thermal_effusivity(
    conductivity_W_mK: ArrayLike, density_kg_m3: ArrayLike, specific_heat_J_kgK: ArrayLike
) -> np.ndarray:
    r"""Thermal effusivity (Blok's thermal contact coefficient) ``sqrt(lambda rho c)``.

    Parameters
    ----------
    conductivity_W_mK : array_like
        Thermal conductivity lambda (W/(m K)).
    density_kg_m3 : array_like
        Density rho (kg/m^3).
    specific_heat_J_kgK : array_like
        Specific heat c (J/(kg K)).

    Returns
    -------
    numpy.ndarray
        ``B = sqrt(lambda rho c)`` (W s^1/2 m^-2 K^-1).

    Examples
    --------
    FZG-C steel of seed 000 Table 2:

    >>> round(float(thermal_effusivity(41.804, 7838.0, 521.7)))
    13074
    """
    lam = _positive("conductivity_W_mK", conductivity_W_mK)
    rho = _positive("density_kg_m3", density_kg_m3)
    c = _positive("specific_heat_J_kgK", specific_heat_J_kgK)
    return np.sqrt(lam * rho * c)


def hertz_half_width(
    load_per_width_N_m: ArrayLike, reduced_radius_m: ArrayLike, reduced_modulus_Pa: float
) -> np.ndarray:
    r"""Hertzian half-width of a line contact (m).

    Parameters
    ----------
    load_per_width_N_m : array_like
        Normal load per unit length of the contact line w (N/m), >= 0.
    reduced_radius_m : array_like
        Reduced radius of curvature ``R' = rho_1 rho_2 / (rho_1 + rho_2)`` (m), > 0.
    reduced_modulus_Pa : float
        ``E'`` with ``2 / E' = (1 - nu_1^2)/E_1 + (1 - nu_2^2)/E_2``, i.e. twice the contact
        modulus ``E*`` of :func:`models.stiffness.contact_modulus` (Pa).

    Returns
    -------
    numpy.ndarray
        ``b_H`` (m), broadcast shape of the inputs.

    Notes
    -----
    .. math:: b_H = \sqrt{\frac{8 w R'}{\pi E'}} = \sqrt{\frac{4 w R'}{\pi E^*}}

    (Hertz 1882; Johnson 1985, ch. 4). Seed 001's ``B`` equals this with
    ``eta = 2/sqrt(pi)`` (:data:`ETA_SEED_001`).

    Examples
    --------
    Steel cylinders, 1 kN per mm (1e6 N/m), R' = 10 mm, E' = 2.26e11 Pa:

    >>> round(float(hertz_half_width(1e6, 0.010, 2.26e11)) * 1e6, 1)  # um
    335.7
    """
    w = _nonnegative("load_per_width_N_m", load_per_width_N_m)
    r = _positive("reduced_radius_m", reduced_radius_m)
    e = float(_positive("reduced_modulus_Pa", reduced_modulus_Pa))
    return np.sqrt(8.0 * w * r / (math.pi * e))


def blok_flash_temperature(
    load_per_width_N_m: ArrayLike,
    velocity_1_m_s: ArrayLike,
    velocity_2_m_s: ArrayLike,
    half_width_m: ArrayLike,
    effusivity_1: ArrayLike,
    effusivity_2: ArrayLike,
    friction_coefficient: ArrayLike = FRICTION_SEED_000,
    blok_coefficient: float = BLOK_COEFFICIENT_SEED_001,
) -> np.ndarray:
    r"""Blok's flash temperature of a band contact (K).

    Parameters
    ----------
    load_per_width_N_m : array_like
        Normal load per unit face width w (N/m), >= 0.
    velocity_1_m_s, velocity_2_m_s : array_like
        Tangential velocities of the two surfaces relative to the contact (m/s), >= 0.
    half_width_m : array_like
        Half-width of the contact band b (m), >= 0 (:func:`hertz_half_width`).
    effusivity_1, effusivity_2 : array_like
        Thermal effusivities ``sqrt(lambda rho c)`` of the bodies (W s^1/2 m^-2 K^-1)
        (:func:`thermal_effusivity`).
    friction_coefficient : array_like
        f (-), >= 0; 0.132 (seed 000) by default.
    blok_coefficient : float
        u (-); 0.83 (seed 001) by default, 0.785 is Blok's value for a Hertzian source
        (:data:`BLOK_COEFFICIENT_HERTZIAN`).

    Returns
    -------
    numpy.ndarray
        Flash temperature (K), broadcast shape of the inputs; 0 where the band has zero width
        (no load) or where both velocities vanish.

    Notes
    -----
    .. math::

        \Delta\vartheta_f = u \frac{f w |v_1 - v_2|}
            {(B_1 \sqrt{v_1} + B_2 \sqrt{v_2}) \sqrt{b}}

    Blok (1937); the thermal effusivity replaces seed 001's ``g sqrt(rho c v)``
    (SEED-NOTES 12, see the module docstring). Valid at high Péclet numbers
    ``v b / (2 kappa) >> 1`` (about 5 and above), which gear contacts reach except within a few
    micrometres of the pitch point, where the sliding speed, and with it the flash
    temperature, vanishes anyway.

    Examples
    --------
    >>> round(float(blok_flash_temperature(1e6, 10.0, 5.0, 1e-4, 13074, 13074)), 2)
    776.16
    """
    w = _nonnegative("load_per_width_N_m", load_per_width_N_m)
    v1 = _nonnegative("velocity_1_m_s", velocity_1_m_s)
    v2 = _nonnegative("velocity_2_m_s", velocity_2_m_s)
    b = _nonnegative("half_width_m", half_width_m)
    e1 = _positive("effusivity_1", effusivity_1)
    e2 = _positive("effusivity_2", effusivity_2)
    f = _nonnegative("friction_coefficient", friction_coefficient)
    u = float(_positive("blok_coefficient", blok_coefficient))
    num = u * f * w * np.abs(v1 - v2)
    den = (e1 * np.sqrt(v1) + e2 * np.sqrt(v2)) * np.sqrt(b)
    num, den = np.broadcast_arrays(num, den)
    return np.divide(num, den, out=np.zeros(num.shape), where=den > 0)


def frictional_heat_flux(
    mean_pressure_Pa: ArrayLike,
    sliding_velocity_m_s: ArrayLike,
    friction_coefficient: ArrayLike = FRICTION_SEED_000,
    heat_conversion: float = HEAT_CONVERSION_SEED_000,
) -> np.ndarray:
    r"""Frictional heat flux into the flanks, ``q = gamma p f V`` (W/m^2), seed 000.

    Parameters
    ----------
    mean_pressure_Pa : array_like
        Contact pressure p (Pa); take the mean Hertz pressure ``w / (2 b)`` so that
        ``2 b q = gamma f w V`` (see the module docstring).
    sliding_velocity_m_s : array_like
        Sliding velocity ``v_1 - v_2`` (m/s); its magnitude is used.
    friction_coefficient : array_like
        f (-); 0.132 (seed 000) by default.
    heat_conversion : float
        gamma (-), the share of the friction power that enters the teeth; 0.9 (seed 000).

    Returns
    -------
    numpy.ndarray
        q (W/m^2), total for both flanks.

    Examples
    --------
    >>> float(frictional_heat_flux(1e9, 2.0, 0.1, 0.9)) / 1e6  # MW/m^2
    180.0
    """
    p = _nonnegative("mean_pressure_Pa", mean_pressure_Pa)
    v = as_finite("sliding_velocity_m_s", sliding_velocity_m_s)
    f = _nonnegative("friction_coefficient", friction_coefficient)
    g = float(as_finite("heat_conversion", heat_conversion))
    if not 0.0 <= g <= 1.0:
        raise ModelError(f"`heat_conversion` must lie in [0, 1], was {heat_conversion!r}")
    return g * p * f * np.abs(v)


@dataclass(frozen=True)
class FlashTemperature:
    """Flash and contact temperature along the path of contact.

    All arrays share the broadcast shape of the positions with the torque, speed, bulk
    temperature and load share.

    Attributes
    ----------
    position_m : numpy.ndarray
        Positions on the line of action from T1 (m).
    load_per_width_N_m : numpy.ndarray
        Normal load per unit face width carried by the tooth pair, ``F_n R / b`` (N/m).
    reduced_radius_m : numpy.ndarray
        ``R' = rho_1 rho_2 / (rho_1 + rho_2)`` (m).
    half_width_m : numpy.ndarray
        Hertzian half-width ``b_H`` (m).
    max_pressure_Pa, mean_pressure_Pa : numpy.ndarray
        Hertz pressures ``p_0 = 2 w / (pi b_H)`` and ``p_m = w / (2 b_H)`` (Pa).
    velocity_pinion_m_s, velocity_wheel_m_s : numpy.ndarray
        Tangential velocities ``v_i = omega_i rho_i`` (m/s).
    sliding_velocity_m_s : numpy.ndarray
        ``v_1 - v_2`` (m/s): negative in approach, zero at the pitch point, positive in recess.
    flash_K : numpy.ndarray
        Blok flash temperature (K).
    bulk_temperature_C : numpy.ndarray
        Bulk (body) temperature (deg C).
    contact_temperature_C : numpy.ndarray
        ``bulk + flash`` (deg C), seed 001's ``Delta_B = Delta_M + Delta_f``.
    heat_flux_W_m2 : numpy.ndarray
        ``q = gamma p_m f |v_1 - v_2|`` (W/m^2), seed 000.
    heat_flux_pinion_W_m2, heat_flux_wheel_W_m2 : numpy.ndarray
        Blok's partition of ``q`` in the ratio ``B_1 sqrt(v_1) : B_2 sqrt(v_2)`` (W/m^2).
    friction_coefficient, blok_coefficient, heat_conversion : float
        The f, u and gamma used (-).
    """

    position_m: np.ndarray
    load_per_width_N_m: np.ndarray
    reduced_radius_m: np.ndarray
    half_width_m: np.ndarray
    max_pressure_Pa: np.ndarray
    mean_pressure_Pa: np.ndarray
    velocity_pinion_m_s: np.ndarray
    velocity_wheel_m_s: np.ndarray
    sliding_velocity_m_s: np.ndarray
    flash_K: np.ndarray
    bulk_temperature_C: np.ndarray
    contact_temperature_C: np.ndarray
    heat_flux_W_m2: np.ndarray
    heat_flux_pinion_W_m2: np.ndarray
    heat_flux_wheel_W_m2: np.ndarray
    friction_coefficient: float
    blok_coefficient: float
    heat_conversion: float


def flash_temperature(
    pair: GearPair,
    s_m: ArrayLike,
    torque_Nm: ArrayLike,
    pinion_speed_rpm: ArrayLike,
    *,
    bulk_temperature_C: ArrayLike,
    friction_coefficient: float = FRICTION_SEED_000,
    load_share: Literal["seed-000"] | ArrayLike = "seed-000",
    blok_coefficient: float = BLOK_COEFFICIENT_SEED_001,
    heat_conversion: float = HEAT_CONVERSION_SEED_000,
) -> FlashTemperature:
    r"""Blok flash temperature and contact temperature of a spur pair along the line of action.

    Parameters
    ----------
    pair : GearPair
        Pinion (1) drives the wheel (2); materials from ``pair.pinion.material`` and
        ``pair.wheel.material``.
    s_m : array_like
        Positions on the line of action from T1 (m), strictly between T1 and T2 (at the
        tangent points a radius of curvature vanishes).
    torque_Nm : array_like
        Pinion torque (N m), >= 0; broadcast against ``s_m`` (e.g. shape ``(m, 1)``).
    pinion_speed_rpm : array_like
        Pinion speed (1/min), > 0; broadcast against ``s_m``.
    bulk_temperature_C : array_like
        Bulk temperature of the teeth (deg C); broadcast against ``s_m``.
    friction_coefficient : float
        f (-); 0.132, measured in seed 000.
    load_share : "seed-000" or array_like
        Share R of the normal load on this tooth pair: ``"seed-000"`` for seed 000's
        ``R(theta)`` (0 outside the path of contact), or values broadcast against ``s_m``
        (``1.0``: the whole load on one pair, seed 001's ``F/b``).
    blok_coefficient : float
        u (-); 0.83 (seed 001).
    heat_conversion : float
        gamma (-) for the heat flux; 0.9 (seed 000).

    Returns
    -------
    FlashTemperature

    Notes
    -----
    .. math::

        w = \frac{T_1}{r_{b1}} \frac{R}{b}, \quad
        b_H = \sqrt{\frac{8 w R'}{\pi E'}}, \quad
        \Delta\vartheta_f = u \frac{f w |v_1 - v_2|}{(B_1\sqrt{v_1} + B_2\sqrt{v_2})\sqrt{b_H}},
        \quad \vartheta_B = \vartheta_M + \Delta\vartheta_f

    (seed 001 with the effusivity ``B_i = sqrt(lambda_i rho_i c_i)``, SEED-NOTES 12; seed
    001's ``B`` with ``eta = 2/sqrt(pi)``, SEED-NOTES 13; seed 000's load share and friction).
    The flash temperature vanishes at the pitch point (pure rolling), and grows with
    ``w^{3/4}`` and roughly with the square root of the speed.

    Examples
    --------
    FZG-C at 302 N m (load stage 9), 1500 rpm, bulk 90 deg C: highest at the start of
    contact A, zero at the pitch point C, high again at the end of contact E.

    >>> from models.geometry import load_gear_set
    >>> g = load_gear_set("fzg-c").pair
    >>> s = [g.start_of_contact, g.pitch_point, g.end_of_contact]
    >>> ft = flash_temperature(g, s, 302.0, 1500.0, bulk_temperature_C=90.0)
    >>> [round(float(t), 1) for t in ft.flash_K]  # K
    [182.4, 0.0, 135.5]
    >>> [round(float(t), 1) for t in ft.contact_temperature_C]  # deg C
    [272.4, 90.0, 225.5]
    """
    s = as_finite("s_m", s_m)
    length = pair.line_of_action_length
    if np.any(s <= 0) or np.any(s >= length):
        raise ModelError(f"`s_m` must lie strictly between T1 (0) and T2 ({length:.6g} m), "
                         f"was in [{float(s.min()):.6g}, {float(s.max()):.6g}] m")
    torque = _nonnegative("torque_Nm", torque_Nm)
    speed = _positive("pinion_speed_rpm", pinion_speed_rpm)
    bulk = as_finite("bulk_temperature_C", bulk_temperature_C)
    if isinstance(load_share, str):
        if load_share != "seed-000":
            raise ModelError(f"`load_share` must be 'seed-000' or numbers, was {load_share!r}")
        share = load_share_seed_000(pair, s)
    else:
        share = _nonnegative("load_share", load_share)
        if np.any(share > 1):
            raise ModelError(f"`load_share` must lie in [0, 1], was {float(share.max()):.6g}")
    f = float(_nonnegative("friction_coefficient", friction_coefficient))

    m1, m2 = pair.pinion.material, pair.wheel.material
    e_red = 2.0 * contact_modulus(m1.youngs_modulus_Pa, m1.poisson_ratio,
                                  m2.youngs_modulus_Pa, m2.poisson_ratio)
    b1 = thermal_effusivity(m1.conductivity_W_mK, m1.density_kg_m3, m1.specific_heat_J_kgK)
    b2 = thermal_effusivity(m2.conductivity_W_mK, m2.density_kg_m3, m2.specific_heat_J_kgK)

    w = normal_load_from_torque(pair, torque) * share / pair.face_width_m
    rho1, rho2 = pair.curvature_radii(s)
    r_red = rho1 * rho2 / (rho1 + rho2)
    bh = hertz_half_width(w, r_red, e_red)
    omega1 = speed * 2.0 * math.pi / 60.0
    v1 = omega1 * rho1
    v2 = omega1 / pair.gear_ratio * rho2
    w, r_red, bh, v1, v2, bulk = np.broadcast_arrays(w, r_red, bh, v1, v2, bulk)
    s_b = np.broadcast_to(s, w.shape)
    flash = blok_flash_temperature(w, v1, v2, bh, b1, b2, f, blok_coefficient)
    p_max = np.divide(2.0 * w, math.pi * bh, out=np.zeros(w.shape), where=bh > 0)
    p_mean = math.pi * p_max / 4.0
    q = frictional_heat_flux(p_mean, v1 - v2, f, heat_conversion)
    k1, k2 = b1 * np.sqrt(v1), b2 * np.sqrt(v2)
    q1 = q * k1 / (k1 + k2)
    return FlashTemperature(
        position_m=np.array(s_b),
        load_per_width_N_m=np.array(w),
        reduced_radius_m=np.array(r_red),
        half_width_m=np.array(bh),
        max_pressure_Pa=p_max,
        mean_pressure_Pa=p_mean,
        velocity_pinion_m_s=np.array(v1),
        velocity_wheel_m_s=np.array(v2),
        sliding_velocity_m_s=np.array(v1 - v2),
        flash_K=flash,
        bulk_temperature_C=np.array(bulk),
        contact_temperature_C=bulk + flash,
        heat_flux_W_m2=q,
        heat_flux_pinion_W_m2=q1,
        heat_flux_wheel_W_m2=q - q1,
        friction_coefficient=f,
        blok_coefficient=float(blok_coefficient),
        heat_conversion=float(heat_conversion),
    )

r"""Thermal deformation of the flanks along the line of action; seed 001's temperature stiffness.

Seed 000's thermal normal deformation ``Delta_1 + Delta_2``. Each gear is a plane-stress
annular disc from its bore ``r_n`` to its base circle ``r_b``, with the steady logarithmic
temperature profile between the bore temperature ``t_n`` and the base-circle temperature
``t_b``, carrying teeth at the local temperature ``t_b + Delta t_k`` (``Delta t_k`` the local
rise at the contact point: the flash temperature, or zero). All temperatures count from the
reference state of :class:`~models.thermal.ThermalReference` (``theta = t - t_ref``).

The disc: seed 000's Delta r_k, reconstructed and checked
---------------------------------------------------------
The free thermoelastic annular disc ``a <= r <= b`` in plane stress has the radial displacement
(Timoshenko and Goodier 1970, ch. 13)

.. math::

    u(r) = \frac{(1 + \nu)\,\xi}{r} \int_a^r \theta r' dr'
         + \frac{\xi}{b^2 - a^2}\left[(1 - \nu) r + (1 + \nu)\frac{a^2}{r}\right]
           \int_a^b \theta r' dr',

so its rim moves by ``u(b) = xi b theta_bar`` with the area-mean temperature
``theta_bar = 2 / (b^2 - a^2) int_a^b theta r dr``, whatever Poisson's ratio. For the
logarithmic profile ``theta(r) = theta_n + (theta_b - theta_n) ln(r/a) / ln(b/a)``,
with ``a = r_n``, ``b = r_b``:

.. math::

    u(r_b) = \xi r_b \theta_n + \frac{\xi r_b^3 (\theta_b - \theta_n)}{r_b^2 - r_n^2}
             - \frac{\xi r_b (\theta_b - \theta_n)}{2 (\ln r_b - \ln r_n)},

which is term for term the first three terms of seed 000's ``Delta r_k``: the seed's disc is
the plane-stress free disc truncated at the base circle (the test suite integrates the
Timoshenko-Goodier solution numerically against this closed form). Seed 000's last term,
``Delta t_k xi (r_k - r_b)``, is the free radial growth of the tooth between the base circle
and the contact radius.

The tooth, and where the seed's formulas break similarity (SEED-NOTES 9)
-----------------------------------------------------------------------
A uniform rise ``dT`` must scale the gear about its centre: every point moves radially by
``xi dT r`` and polar angles do not change. Seed 000's formulas fail this under either
reading of ``Delta t_k`` (both shown in ``tests/models/test_thermal_expansion.py``):

* with ``Delta t_k`` the local *excess* over the body (zero for a uniform rise), its
  ``Delta r_k = xi dT r_b``, not ``xi dT r_k``: the tooth above the base circle does not grow;
* with ``Delta t_k`` the tooth's whole rise (``dT``), ``Delta r_k = xi dT r_k`` is right, but
  ``Delta s_k = Delta t_k xi s_k / 2`` and ``Delta phi_k = Delta s_k / r_k'`` then turn the
  flank point by ``xi dT s / (2 r_k')``: the circumferential growth of the tooth is already in
  the new radius (an arc ``phi r`` grows with ``r`` at fixed ``phi``), and the angular update
  counts it a second time. The normal deformation comes out ``xi dT s cos(alpha_k) / 2``
  too large (by 25 % on the pinion and 17 % on the wheel at the FZG-C pitch point).

Implemented instead is the displacement field the seed's radial formula is the radial part of:
the tooth rides on the disc's rim, which scales it about the gear centre by the area-mean
strain ``xi theta_bar``, and its excess ``theta_t - theta_bar`` over the disc expands it freely
about its root centre ``P_0`` (the point of the tooth's centreline on the base circle):

.. math::

    \mathbf{u}(P) = \xi \bar\theta\, \vec{OP} + \xi (\theta_t - \bar\theta)\, \vec{P_0 P},
    \qquad \theta_t = \theta_b + \Delta t_k .

Its radial component is ``xi theta_bar r_b cos(phi_k) + xi theta_t (r_k - r_b cos(phi_k))``,
seed 000's ``Delta r_k`` with ``cos(phi_k) -> 1`` and the tooth at ``theta_b + Delta t_k``
(the seed measures the tooth's height from the base circle along the radius, the field from
the root centre; the difference ``xi (theta_t - theta_bar) r_b (1 - cos phi_k)`` is at most
about 1 % of ``Delta r_k``: 0.3 um for a 100 K excess low on the FZG-C pinion flank);
its tangential component is ``Delta s_k = xi (theta_t - theta_bar) r_b sin(phi_k)``, zero for
a uniform rise. The tooth takes the local temperature at the contact point along its height
(the seed's simplification).

New coordinates and the normal deformation
------------------------------------------
In the tooth frame (``y`` along the centreline, ``x`` towards the loaded flank), the flank
point at radius ``r_k`` lies at ``(r_k sin phi_k, r_k cos phi_k)`` with the half-thickness
angle ``phi_k = s / (2 r) + inv(alpha) - inv(alpha_k)`` (seed 000's ``phi_k``;
``s = m (pi/2 + 2 x tan alpha)`` the reference tooth thickness, ``r = z m / 2``,
``cos(alpha_k) = r_b / r_k``). After the displacement it lies at ``r_k' = |OP + u|``,
``phi_k' = atan2(x', y')`` (``Delta phi_k = Delta s_k / r_k'`` to first order, the seed's
relation), and

.. math::

    \Delta x = r_k' \sin\varphi_k' - r_k \sin\varphi_k, \quad
    \Delta y = r_k' \cos\varphi_k' - r_k \cos\varphi_k, \quad
    \Delta_n = \Delta x \cos\omega_k + \Delta y \sin\omega_k,

with the load angle ``omega_k = alpha_k - phi_k``: ``(cos omega_k, sin omega_k)`` is the
outward normal of the flank, along the line of action, so ``Delta_n > 0`` is growth towards
the mating flank. In closed form

.. math::

    \Delta_n = \xi \bar\theta \rho_k + \xi (\theta_t - \bar\theta)(\rho_k - r_b \sin\omega_k),

``rho_k = r_k sin(alpha_k)`` the roll distance (radius of curvature): under a uniform rise
``Delta_n = xi dT rho_k``, and the two flanks close the gap by ``xi dT (rho_1 + rho_2) =
xi dT a' sin(alpha')`` at a fixed centre distance. ``Delta_1 + Delta_2`` subtracts the gap a
growing centre distance opens, ``Delta a sin(alpha')`` (:class:`ThermalReference`).

Temperature stiffness (seed 001)
--------------------------------
Seed 001 defines a "temperature stiffness" per tooth ``k_wi = F / (b sigma_i)`` with
``sigma_i`` the thermal profile deformation of tooth ``i`` at the contact point (here: the
normal deformation ``Delta_n`` of gear ``i`` under the contact temperature rise over the
initial temperature), the pair value ``k_w = k_w1 k_w2 / (k_w1 + k_w2) = F / (b (sigma_1 +
sigma_2))`` and the mesh stiffness ``k = k_t + k_w``. See :func:`temperature_stiffness` for the
units and for why this is not a stiffness in the usual sense.

References
----------
.. [1] S. P. Timoshenko, J. N. Goodier, *Theory of Elasticity*, 3rd ed., McGraw-Hill, 1970,
   ch. 13 (thermal stress in a thin circular disc).
.. [2] ISO 21771:2007, *Gears - Cylindrical involute gears and gear pairs - Concepts and
   geometry* (tooth thickness, involute function).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike

from models.errors import GeometryError, ModelError
from models.geometry.gear_pair import GearPair
from models.geometry.involute import inv
from models.thermal.checks import as_finite
from models.thermal.flash import FlashTemperature
from models.thermal.reference_state import ThermalReference

__all__ = [
    "DEFAULT_BORE_FRACTION",
    "FlankDeformation",
    "GearTemperature",
    "TemperatureStiffness",
    "ThermalDeformation",
    "disc_mean_temperature_rise",
    "disc_rim_expansion",
    "temperature_stiffness",
    "thermal_deformation",
]

#: Bore diameter as a fraction of the reference diameter when a gear states none (as in
#: :mod:`models.stiffness.potential_energy`).
DEFAULT_BORE_FRACTION = 0.3


@dataclass(frozen=True, eq=False)
class GearTemperature:
    """Temperature description of one gear (deg C, K); arrays broadcast with the positions.

    Parameters
    ----------
    bore_C : array_like
        Bore temperature ``t_n`` (deg C).
    base_circle_C : array_like
        Base-circle temperature ``t_b`` (deg C); the tooth body is at this temperature.
    local_rise_K : array_like
        Local rise ``Delta t_k`` of the tooth at the contact point over ``t_b`` (K), e.g. a
        flash temperature (or pass the flash through ``ThermalReference``), 0 by default.

    Examples
    --------
    >>> GearTemperature.uniform(90.0).base_circle_C
    90.0
    """

    bore_C: ArrayLike
    base_circle_C: ArrayLike
    local_rise_K: ArrayLike = 0.0

    @classmethod
    def uniform(cls, temperature_C: ArrayLike) -> GearTemperature:
        """A gear at one temperature throughout, no local rise."""
        return cls(temperature_C, temperature_C, 0.0)


def disc_mean_temperature_rise(
    bore_radius_m: float, outer_radius_m: float, bore_rise_K: ArrayLike, outer_rise_K: ArrayLike
) -> np.ndarray:
    r"""Area-mean temperature rise of an annulus with a logarithmic radial profile (K).

    Parameters
    ----------
    bore_radius_m, outer_radius_m : float
        Inner and outer radii ``0 < r_n < r_b`` (m).
    bore_rise_K, outer_rise_K : array_like
        Temperature rises ``theta_n``, ``theta_b`` at the two radii (K).

    Returns
    -------
    numpy.ndarray
        .. math::
            \bar\theta = \theta_n + (\theta_b - \theta_n)
                \left[\frac{r_b^2}{r_b^2 - r_n^2} - \frac{1}{2 \ln(r_b / r_n)}\right]

    Examples
    --------
    >>> float(disc_mean_temperature_rise(0.01, 0.03, 70.0, 70.0))
    70.0
    """
    a, b = float(bore_radius_m), float(outer_radius_m)
    if not (math.isfinite(a) and math.isfinite(b) and 0 < a < b):
        raise ModelError(f"radii must satisfy 0 < `bore_radius_m` < `outer_radius_m`, were "
                         f"{bore_radius_m!r} and {outer_radius_m!r}")
    tn = as_finite("bore_rise_K", bore_rise_K)
    tb = as_finite("outer_rise_K", outer_rise_K)
    weight = b * b / (b * b - a * a) - 1.0 / (2.0 * math.log(b / a))
    return tn + (tb - tn) * weight


def disc_rim_expansion(
    bore_radius_m: float,
    outer_radius_m: float,
    bore_rise_K: ArrayLike,
    outer_rise_K: ArrayLike,
    expansion_per_K: float,
) -> np.ndarray:
    r"""Radial growth of the rim of a free plane-stress disc, log temperature profile (m).

    Parameters
    ----------
    bore_radius_m, outer_radius_m : float
        ``r_n`` and ``r_b`` (m), ``0 < r_n < r_b``.
    bore_rise_K, outer_rise_K : array_like
        ``theta_n`` and ``theta_b`` (K), counted from the reference state.
    expansion_per_K : float
        Linear expansion coefficient xi (1/K).

    Returns
    -------
    numpy.ndarray
        The first three terms of seed 000's ``Delta r_k``:

        .. math::

            u(r_b) = r_b \xi \theta_n + \frac{\xi r_b^3 (\theta_b - \theta_n)}{r_b^2 - r_n^2}
                     - \frac{\xi r_b (\theta_b - \theta_n)}{2 (\ln r_b - \ln r_n)}
                   = \xi r_b \bar\theta

        (Timoshenko and Goodier 1970, ch. 13; see the module docstring).

    Examples
    --------
    A uniform rise scales the rim: ``xi dT r_b``.

    >>> round(float(disc_rim_expansion(0.01, 0.03, 70.0, 70.0, 1.15e-5)) * 1e6, 4)  # um
    24.15
    """
    xi = float(expansion_per_K)
    if not (math.isfinite(xi) and 0 <= xi < 1e-3):
        raise ModelError(f"`expansion_per_K` must lie in [0, 1e-3) 1/K, was {expansion_per_K!r}")
    return xi * float(outer_radius_m) * disc_mean_temperature_rise(
        bore_radius_m, outer_radius_m, bore_rise_K, outer_rise_K)


@dataclass(frozen=True)
class FlankDeformation:
    """Thermal displacement of one gear's flank point at each contact position.

    Attributes
    ----------
    gear : int
        1 (pinion) or 2 (wheel).
    radius_m : numpy.ndarray
        ``r_k``, radius of the contact point (m).
    polar_angle_rad : numpy.ndarray
        ``phi_k``, angle of the flank point from the tooth centreline (rad).
    load_angle_rad : numpy.ndarray
        ``omega_k = alpha_k - phi_k`` (rad).
    roll_distance_m : numpy.ndarray
        ``rho_k = r_k sin(alpha_k)``, the profile radius of curvature (m).
    disc_mean_rise_K : numpy.ndarray
        ``theta_bar``, area-mean rise of the disc (K).
    tooth_rise_K : numpy.ndarray
        ``theta_t = theta_b + Delta t_k`` (K).
    radial_m : numpy.ndarray
        ``Delta r_k = r_k' - r_k`` (m).
    tangential_m : numpy.ndarray
        ``Delta s_k = r_k' Delta phi_k`` (m), positive away from the centreline.
    angle_change_rad : numpy.ndarray
        ``Delta phi_k = phi_k' - phi_k`` (rad).
    new_radius_m, new_polar_angle_rad : numpy.ndarray
        ``r_k'`` (m) and ``phi_k'`` (rad).
    dx_m, dy_m : numpy.ndarray
        ``Delta x``, ``Delta y`` in the tooth frame (m).
    normal_m : numpy.ndarray
        ``Delta_n = Delta x cos(omega_k) + Delta y sin(omega_k)`` (m), growth of the flank
        towards its mate along the line of action.
    """

    gear: int
    radius_m: np.ndarray
    polar_angle_rad: np.ndarray
    load_angle_rad: np.ndarray
    roll_distance_m: np.ndarray
    disc_mean_rise_K: np.ndarray
    tooth_rise_K: np.ndarray
    radial_m: np.ndarray
    tangential_m: np.ndarray
    angle_change_rad: np.ndarray
    new_radius_m: np.ndarray
    new_polar_angle_rad: np.ndarray
    dx_m: np.ndarray
    dy_m: np.ndarray
    normal_m: np.ndarray


@dataclass(frozen=True)
class ThermalDeformation:
    """Thermal closure of the drive-side flanks along the path of contact.

    Attributes
    ----------
    position_m : numpy.ndarray
        Positions on the line of action from T1 (m).
    pinion, wheel : FlankDeformation
        Each flank's displacement; ``pinion.normal_m`` and ``wheel.normal_m`` are seed 000's
        ``Delta_1`` and ``Delta_2`` before the centre-distance change.
    centre_distance_change_m : float
        ``Delta a`` (m), 0 at a fixed centre distance.
    housing_gap_opening_m : float
        ``Delta a sin(alpha')`` (m), the drive-side gap the growing centre distance opens.
    delta_pinion_m, delta_wheel_m : numpy.ndarray
        Seed 000's ``Delta_1`` and ``Delta_2`` (m): each flank's normal deformation less its
        share of the housing opening, ``Delta_i = Delta_ni - (Delta a / a') rho_i`` (the
        housing growth read as a dilatation of the whole pair by ``Delta a / a'``; the shares
        add up to ``Delta a sin(alpha')`` because ``rho_1 + rho_2 = a' sin(alpha')``). With a
        fixed centre distance ``Delta_i = Delta_ni``.
    total_m : numpy.ndarray
        ``Delta_1 + Delta_2 = Delta_n1 + Delta_n2 - Delta a sin(alpha')`` (m): how far the
        drive-side flanks approach along the line of action, what seed 000's
        ``c* = (1 - chi)(Delta_1 + Delta_2)`` takes.
    expansion_per_K : tuple of float
        xi of pinion and wheel (1/K).
    reference : ThermalReference
    """

    position_m: np.ndarray
    pinion: FlankDeformation
    wheel: FlankDeformation
    centre_distance_change_m: float
    housing_gap_opening_m: float
    delta_pinion_m: np.ndarray
    delta_wheel_m: np.ndarray
    total_m: np.ndarray
    expansion_per_K: tuple[float, float]
    reference: ThermalReference = field(repr=False)


def _bore_radius(pair: GearPair, gear: int) -> float:
    g = pair.pinion if gear == 1 else pair.wheel
    bore = g.bore_diameter_m if g.bore_diameter_m is not None \
        else DEFAULT_BORE_FRACTION * 2.0 * pair.reference_radius(gear)
    r_n = bore / 2.0
    if not 0 < r_n < pair.base_radius(gear):
        who = "pinion" if gear == 1 else "wheel"
        raise GeometryError(f"{who}.bore_diameter_m", bore,
                            f"must lie in (0, base diameter {2 * pair.base_radius(gear):.6g} m) "
                            "for the disc model")
    return r_n


def _flank(pair: GearPair, gear: int, s: np.ndarray, temp: GearTemperature,
           extra_rise: np.ndarray, t_ref: float, xi: float) -> FlankDeformation:
    g = pair.pinion if gear == 1 else pair.wheel
    a0 = pair.pressure_angle_rad
    r_b = pair.base_radius(gear)
    r_n = _bore_radius(pair, gear)
    rho = s if gear == 1 else pair.line_of_action_length - s
    r_k = np.hypot(r_b, rho)
    alpha_k = np.arctan2(rho, r_b)
    phi = (math.pi / (2 * g.teeth) + 2 * g.profile_shift * math.tan(a0) / g.teeth
           + float(inv(a0)) - (np.tan(alpha_k) - alpha_k))
    omega = alpha_k - phi
    theta_n = as_finite("bore_C", temp.bore_C) - t_ref
    theta_b = as_finite("base_circle_C", temp.base_circle_C) - t_ref
    local = as_finite("local_rise_K", temp.local_rise_K) + extra_rise
    theta_bar = disc_mean_temperature_rise(r_n, r_b, theta_n, theta_b)
    theta_t = theta_b + local
    theta_bar, theta_t, r_k, phi, omega, rho = np.broadcast_arrays(theta_bar, theta_t, r_k, phi,
                                                                   omega, rho)
    x, y = r_k * np.sin(phi), r_k * np.cos(phi)
    excess = xi * (theta_t - theta_bar)
    ux = xi * theta_bar * x + excess * x
    uy = xi * theta_bar * y + excess * (y - r_b)
    x1, y1 = x + ux, y + uy
    r_new = np.hypot(x1, y1)
    phi_new = np.arctan2(x1, y1)
    dx = r_new * np.sin(phi_new) - r_k * np.sin(phi)
    dy = r_new * np.cos(phi_new) - r_k * np.cos(phi)
    d_phi = phi_new - phi
    return FlankDeformation(
        gear=gear, radius_m=np.array(r_k), polar_angle_rad=np.array(phi),
        load_angle_rad=np.array(omega), roll_distance_m=np.array(rho),
        disc_mean_rise_K=np.array(theta_bar), tooth_rise_K=np.array(theta_t),
        radial_m=r_new - r_k, tangential_m=r_new * d_phi, angle_change_rad=d_phi,
        new_radius_m=r_new, new_polar_angle_rad=phi_new, dx_m=dx, dy_m=dy,
        normal_m=dx * np.cos(omega) + dy * np.sin(omega),
    )


def thermal_deformation(
    pair: GearPair,
    s_m: ArrayLike,
    reference: ThermalReference,
    temperature: GearTemperature,
    wheel_temperature: GearTemperature | None = None,
    *,
    flash: FlashTemperature | None = None,
    expansion_per_K: float | None = None,
) -> ThermalDeformation:
    r"""Thermal normal deformation ``Delta_1 + Delta_2`` of a spur pair along the line of action.

    Parameters
    ----------
    pair : GearPair
        Bores from ``Gear.bore_diameter_m`` (0.3 d when None); expansion coefficients from the
        gears' materials unless ``expansion_per_K`` is given.
    s_m : array_like
        Positions on the line of action from T1 (m), strictly between T1 and T2.
    reference : ThermalReference
        Reference temperature, housing model, and whether the flash temperature is part of
        the local rise (SEED-NOTES 8).
    temperature : GearTemperature
        Pinion temperatures (and the wheel's when ``wheel_temperature`` is None); arrays
        broadcast against ``s_m``.
    wheel_temperature : GearTemperature or None
        Wheel temperatures; None: the same as the pinion's.
    flash : FlashTemperature or None
        Required when ``reference.flash_counts_as_local_rise``: its ``flash_K`` (broadcast
        against ``s_m``, so computed at the same positions) is added to both flanks' local
        rise (Blok's postulate: both surfaces reach the same flash temperature).
    expansion_per_K : float or None
        xi for both gears and, unless the reference says otherwise, the housing (1/K); None
        takes each gear's ``material.thermal_expansion_per_K``.

    Returns
    -------
    ThermalDeformation

    Notes
    -----
    Per gear, with ``theta = t - t_ref`` (see the module docstring for the derivation):

    .. math::

        \bar\theta &= \theta_n + (\theta_b - \theta_n)\left[\frac{r_b^2}{r_b^2 - r_n^2}
                    - \frac{1}{2\ln(r_b/r_n)}\right], \qquad
        \theta_t = \theta_b + \Delta t_k, \\
        \mathbf{u} &= \xi\bar\theta\,\vec{OP} + \xi(\theta_t - \bar\theta)\,\vec{P_0P}, \\
        \Delta_n &= \Delta x \cos\omega_k + \Delta y \sin\omega_k
                  = \xi\bar\theta\rho_k + \xi(\theta_t - \bar\theta)(\rho_k - r_b\sin\omega_k),

    ``Delta_i = Delta_ni - (Delta a / a') rho_i`` and
    ``Delta_1 + Delta_2 = Delta_n1 + Delta_n2 - Delta a sin(alpha')``. Seed 000's
    ``Delta r_k`` is the radial part of ``u`` (to ``cos(phi_k) = 1``); its angular update
    ``Delta phi_k = xi Delta t_k s / (2 r_k')`` is replaced because it counts the
    circumferential growth twice (SEED-NOTES 9).

    Examples
    --------
    FZG-C, both gears uniformly 70 K above a 20 deg C assembly at a fixed centre distance:
    the closure is ``xi dT a' sin(alpha')`` everywhere.

    >>> from models.geometry import load_gear_set
    >>> g = load_gear_set("fzg-c").pair
    >>> d = thermal_deformation(g, [g.pitch_point], ThermalReference(20.0),
    ...                         GearTemperature.uniform(90.0))
    >>> round(float(d.total_m[0]) * 1e6, 3), round(1.15e-5 * 70 * g.line_of_action_length * 1e6, 3)
    (28.115, 28.115)
    """
    s = as_finite("s_m", s_m)
    length = pair.line_of_action_length
    if np.any(s <= 0) or np.any(s >= length):
        raise ModelError(f"`s_m` must lie strictly between T1 (0) and T2 ({length:.6g} m), "
                         f"was in [{float(s.min()):.6g}, {float(s.max()):.6g}] m")
    if not isinstance(reference, ThermalReference):
        raise ModelError(f"`reference` must be a ThermalReference, was {type(reference).__name__}")
    if expansion_per_K is None:
        xi1 = pair.pinion.material.thermal_expansion_per_K
        xi2 = pair.wheel.material.thermal_expansion_per_K
    else:
        xi1 = xi2 = float(expansion_per_K)
        if not (math.isfinite(xi1) and 0 <= xi1 < 1e-3):
            raise ModelError(f"`expansion_per_K` must lie in [0, 1e-3) 1/K, was "
                             f"{expansion_per_K!r}")
    extra = np.zeros(())
    if reference.flash_counts_as_local_rise:
        if flash is None:
            raise ModelError("`flash` is required when `reference.flash_counts_as_local_rise` "
                             "is True, was None")
        extra = as_finite("flash.flash_K", flash.flash_K)
    t_ref = reference.reference_temperature_C
    wheel_t = temperature if wheel_temperature is None else wheel_temperature
    try:
        p1 = _flank(pair, 1, s, temperature, extra, t_ref, xi1)
        p2 = _flank(pair, 2, s, wheel_t, extra, t_ref, xi2)
    except ValueError as exc:
        if isinstance(exc, ModelError):
            raise
        raise ModelError(f"temperatures and `s_m` do not broadcast together: {exc}") from exc
    da = reference.centre_distance_change(pair.centre_distance, xi1)
    opening = da * math.sin(pair.operating_pressure_angle)
    strain = da / pair.centre_distance
    d1 = p1.normal_m - strain * p1.roll_distance_m
    d2 = p2.normal_m - strain * p2.roll_distance_m
    d1, d2 = np.broadcast_arrays(d1, d2)
    total = d1 + d2
    return ThermalDeformation(
        position_m=np.broadcast_to(s, total.shape).copy(), pinion=p1, wheel=p2,
        centre_distance_change_m=da, housing_gap_opening_m=opening,
        delta_pinion_m=np.array(d1), delta_wheel_m=np.array(d2), total_m=total,
        expansion_per_K=(xi1, xi2), reference=reference,
    )


@dataclass(frozen=True)
class TemperatureStiffness:
    """Seed 001's temperature stiffness, per tooth and per pair.

    Attributes
    ----------
    tooth_pinion_N_m2, tooth_wheel_N_m2 : numpy.ndarray
        ``k_w1 = F / (b sigma_1)``, ``k_w2 = F / (b sigma_2)``: per unit face width
        (N/m per m = N/m^2); NaN where ``sigma_i = 0`` (undefined, see ``undefined``).
    pair_N_m2 : numpy.ndarray
        ``k_w = k_w1 k_w2 / (k_w1 + k_w2) = F / (b (sigma_1 + sigma_2))`` (N/m^2); NaN where
        both deformations vanish.
    pair_N_m : numpy.ndarray
        ``b k_w = F / (sigma_1 + sigma_2)`` (N/m), the pair value over the whole face width.
    mesh_N_m : numpy.ndarray or None
        ``k = k_t + b k_w`` (N/m) when a ``k_t`` was given; NaN where undefined.
    undefined : numpy.ndarray
        Where ``sigma_1 + sigma_2 = 0``: the formula has no finite value there (it is not a
        stiffness that vanishes with the heating, it diverges); the caller decides what a
        cold pair means (seed 000's deflection balance has no such singularity).
    """

    tooth_pinion_N_m2: np.ndarray
    tooth_wheel_N_m2: np.ndarray
    pair_N_m2: np.ndarray
    pair_N_m: np.ndarray
    mesh_N_m: np.ndarray | None
    undefined: np.ndarray | None = None


def temperature_stiffness(
    load_N: ArrayLike,
    face_width_m: float,
    sigma_pinion_m: ArrayLike,
    sigma_wheel_m: ArrayLike,
    mesh_stiffness_N_m: ArrayLike | None = None,
) -> TemperatureStiffness:
    r"""Seed 001's "temperature stiffness" ``k_w = F / (b sigma)``, per tooth and in series.

    Parameters
    ----------
    load_N : array_like
        Normal load ``F`` on the tooth pair (N), >= 0.
    face_width_m : float
        Face width ``b`` (m).
    sigma_pinion_m, sigma_wheel_m : array_like
        Thermal profile deformations ``sigma_i`` of the two teeth at the contact point (m),
        >= 0: the normal deformation of each flank under the contact temperature rise over the
        initial temperature (``FlankDeformation.normal_m`` of :func:`thermal_deformation` with
        the reference at seed 001's initial temperature ``Delta_0``, the tooth at the bulk
        temperature and the flash temperature as the local rise).
    mesh_stiffness_N_m : array_like or None
        The load-sharing mesh stiffness ``k_t`` (N/m) to add ``b k_w`` to.

    Returns
    -------
    TemperatureStiffness

    Raises
    ------
    ModelError
        Negative, non-finite load or deformation (a negative ``sigma`` would give a negative
        "stiffness"), or a face width that is not a positive number.

    Notes
    -----
    .. math::

        k_{wi} = \frac{F}{b\,\sigma_i}, \qquad
        k_w = \frac{k_{w1} k_{w2}}{k_{w1} + k_{w2}} = \frac{F}{b(\sigma_1 + \sigma_2)}, \qquad
        k = k_t + b\,k_w

    (seed 001). **Units.** ``F / (b sigma)`` is N/m^2, a stiffness per unit face width; the
    seed adds it to ``k_t`` without saying in which units. Here ``k_t`` is in N/m, the unit of
    the other stiffness modules, and ``k_w`` is multiplied by ``b`` first, which makes the sum
    ``k_t + F / (sigma_1 + sigma_2)``.

    **A physical oddity, implemented as written.** ``sigma`` is not caused by ``F``: it is a
    thermal deformation that exists with no load at all, so ``F / sigma`` is not the slope of a
    load-deflection curve, and it grows linearly with the load at a fixed temperature. Its
    limits are the wrong way round for a stiffness correction: as the temperature rise and
    ``sigma`` vanish, ``k_w`` does not vanish but diverges, so a cold gear pair would be
    infinitely stiff. (Seed 000's treatment, the thermal closure entering the deflection
    balance ``f_n / k_EP - (1 - chi)(Delta_1 + Delta_2) + c``, does not have this defect.)
    **Limit:** the formula diverges as ``sigma -> 0``; rigtools never returns an infinite
    stiffness: ``sigma_i = 0`` gives NaN for that tooth, ``sigma_1 + sigma_2 = 0`` NaN for the
    pair and for ``k``, flagged in ``undefined``. A zero load with a positive ``sigma`` gives 0.

    Examples
    --------
    1 kN on 14 mm with 5 um and 3 um thermal deformation:

    >>> kw = temperature_stiffness(1000.0, 0.014, 5e-6, 3e-6, mesh_stiffness_N_m=3e8)
    >>> round(float(kw.pair_N_m) / 1e6, 1), round(float(kw.mesh_N_m) / 1e6, 1)  # N/um
    (125.0, 425.0)
    >>> cold = temperature_stiffness(1000.0, 0.014, 0.0, 0.0)
    >>> float(cold.pair_N_m), bool(cold.undefined)
    (nan, True)
    """
    f = as_finite("load_N", load_N)
    b = float(face_width_m)
    if not (math.isfinite(b) and b > 0):
        raise ModelError(f"`face_width_m` must be a finite number > 0, was {face_width_m!r}")
    s1 = as_finite("sigma_pinion_m", sigma_pinion_m)
    s2 = as_finite("sigma_wheel_m", sigma_wheel_m)
    for name, a in (("load_N", f), ("sigma_pinion_m", s1), ("sigma_wheel_m", s2)):
        if np.any(a < 0):
            raise ModelError(f"`{name}` must be >= 0, was {float(a.min()):.6g} (minimum); a "
                             "negative thermal deformation would give a negative k_w")
    f, s1, s2 = np.broadcast_arrays(f, s1, s2)
    nan = np.full(f.shape, np.nan)
    k1 = np.divide(f, b * s1, out=nan.copy(), where=s1 > 0)
    k2 = np.divide(f, b * s2, out=nan.copy(), where=s2 > 0)
    undefined = (s1 + s2) <= 0
    k_pair = np.divide(f, b * (s1 + s2), out=nan.copy(), where=~undefined)
    mesh = None
    if mesh_stiffness_N_m is not None:
        kt = as_finite("mesh_stiffness_N_m", mesh_stiffness_N_m)
        if np.any(kt < 0):
            raise ModelError(f"`mesh_stiffness_N_m` must be >= 0, was {float(kt.min()):.6g}")
        mesh = kt + b * k_pair
    return TemperatureStiffness(tooth_pinion_N_m2=k1, tooth_wheel_N_m2=k2, pair_N_m2=k_pair,
                                pair_N_m=b * k_pair, mesh_N_m=mesh, undefined=undefined)

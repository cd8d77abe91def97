r"""The two-stage model of seed 001 at a bulk temperature: temperature stiffness and inputs.

Seed 001 studies its two-stage torsional model (:mod:`models.dynamics.two_stage`) over the
bulk (body) temperature of the gears. This module builds that model at a bulk temperature
and mesh frequency from the shipped gear sets (``two-stage-45-steel`` and
``two-stage-45-steel-stage2``, seed 001's parameter table): :class:`TwoStageThermalSetup`
holds the inputs, :func:`thermal_stiffness_component` seed 001's temperature stiffness of one
stage, :func:`two_stage_models_at_temperature` and :func:`two_stage_at_temperature` the model.
The peak-DTE maps and bifurcation data over these models are in
:mod:`models.dynamics.two_stage_maps`.

What depends on temperature, and from which equation
----------------------------------------------------
Only the mesh stiffness, through seed 001's temperature stiffness (its ``k = k_t + k_w``):

* the contact temperature rise over the initial temperature ``Delta_0`` is
  ``Delta(t) = Delta_M + Delta_f(t) - Delta_0`` (seed 001, ``Delta_B = Delta_M + Delta_f``),
  ``Delta_M`` the bulk temperature (the map axis) and ``Delta_f`` Blok's flash temperature
  (:func:`models.thermal.flash_temperature`, effusivity form of SEED-NOTES 12, Hertz
  half-width of SEED-NOTES 13, seed 000's load share ``R`` and friction 0.132 since seed 001
  gives no value), evaluated at the speed of each map column (``n_1 = 60 f_mesh / z_1``,
  stage 2 at ``n_1 z_1 / z_2``);
* the profile deformation of flank ``i`` is ``sigma_i = sigma_M,i + sigma_f,i``: the body
  part ``sigma_M,i`` is the flank normal deformation of
  :func:`models.thermal.thermal_deformation` with the reference at ``Delta_0``, the gear
  uniformly at the bulk temperature and a fixed centre distance (seed 001 says nothing about
  the housing), which is ``xi (Delta_M - Delta_0) rho_i`` by similarity; the flash part
  ``sigma_f,i`` is that of a heated surface layer (next section);
* per tooth pair ``j`` in the path of contact at mesh phase ``tau``,
  ``k_{w,j} = F R_j / (sigma_1 + sigma_2)`` (seed 001's ``k_wi = F/(b sigma_i)`` in series,
  times the face width, :func:`models.thermal.temperature_stiffness`), and the pairs in contact
  add in parallel: ``k_w(tau) = sum_j k_{w,j}``. Divided by the stage's mean ``k_t`` and
  expanded in ``n_harmonics`` mesh harmonics, it is the ``thermal`` series of
  :class:`~models.dynamics.MeshStage`. Without flash ``sigma_1 + sigma_2 = xi dT (rho_1 +
  rho_2) = xi dT T_1T_2`` for every pair, so ``k_w = F / (xi dT T_1T_2)`` at every phase (the
  shares sum to 1) and the series is a constant; the flash layer adds a ripple of about
  1e-4 of the mean (``ThermalStiffness.fit_residual``).

What seed 001 says about ``k_w``, and what is implemented: ``k_wi = F / (b sigma_i)`` with
``sigma_i`` "the resultant profile deformation ... derived considering the thermal state of
the gear body" under ``Delta(t) = Delta_B(t) - Delta_0``, the two teeth in series, and
``k = k_t + k_w``; it gives no depth for the flash temperature and no numbers for ``k_w``.
Implemented are the seed's formulas with ``F`` the pair's share ``F R_j``, ``b k_w`` in N/m
(units: :func:`models.thermal.temperature_stiffness`), the body at ``Delta_M`` and the flash
temperature confined to the surface layer it heats.

The flash temperature: a surface layer, not the whole tooth
-----------------------------------------------------------
Blok's flash temperature is a surface temperature reached while a surface point crosses the
Hertzian band, in the contact time ``t_c,i = 2 b_H / v_i`` (``v_i`` the flank's tangential
velocity); Blok's formula itself rests on the heat penetrating only a depth small against
the band (high Peclet number). Over a time ``t`` a surface flux ``q`` into a half-space
gives ``theta(z, t) = (2 q / lambda) sqrt(kappa t) ierfc(z / (2 sqrt(kappa t)))``
(Carslaw and Jaeger 1959, sec. 2.9), surface value ``(2 q / lambda) sqrt(kappa t / pi)``,
``kappa = lambda / (rho c)`` the diffusivity: the heat stays within the thermal penetration
depth ``delta = sqrt(kappa t)``. A free layer expands normal to the surface by
``xi int_0^inf theta dz = xi q t / (rho c) = (sqrt(pi)/2) xi theta_s delta``. Implemented:

.. math:: \sigma_{f,i} = \xi_i\, \Delta_f\, \delta_i, \qquad
          \delta_i = \sqrt{\kappa_i\, 2 b_H / v_i},

leaving out the factor ``sqrt(pi)/2 = 0.89`` and the lateral constraint of a layer bonded to
the colder body (``(1 + nu)/(1 - nu) = 1.86`` in plane strain), both of order one. For seed
001's 45 steel (``kappa = 1.23e-5 m^2/s``) at 10 kN and 40 deg C the flash temperature
reaches 74.5 K at 10000 rpm, ``delta`` is about 13 um, and ``sigma_f,1 + sigma_f,2`` is
0.018 um at most, against 10.6 um from the 20 K bulk rise. ``Delta_f delta_i`` is
proportional to ``q t_c / (rho c)``, the frictional heat per unit flank area
(``f w |v_1 - v_2| / v_i``, shared between the flanks), which does not depend on the speed:
in this reading ``k_w`` does not depend on the mesh frequency.

``flash_model="whole-tooth"`` keeps the other reading, the flash temperature as the local
rise of the whole tooth (``ThermalReference(flash_counts_as_local_rise=True)``, seed 000's
``Delta t_k``): it is what seed 001's sentence says if read literally, and the only reading
in which ``k_w`` depends on speed (its maps are over mesh frequency). It heats the whole
tooth to a temperature reached only within ~13 um of the surface and overstates
``sigma_f`` about 350-fold (6.3 um instead of 0.018 um in the example above; ``k_w`` 12 %
lower at 10000 rpm than at 1000 rpm): it is kept for comparison with that literal
reading, not as physics.

Validity near the initial temperature
-------------------------------------
``k_w`` *falls* as the temperature rises (``sigma`` grows linearly with the rise) and
diverges as the rise vanishes (the seed's formula; see
:func:`models.thermal.temperature_stiffness`). With the defaults ``k_w / k_t`` is 0.50 at
40 deg C and 0.10 at 120 deg C on stage 1, 0.74 and 0.15 on stage 2 (twice the load over a
longer ``T_1T_2``). Below a minimum rise the "temperature stiffness" dominates the mesh stiffness
and, as the stiffest mode grows without bound, the fixed-step integration needs ever more
steps: :class:`TwoStageThermalSetup` refuses bulk temperatures at which ``k_w`` exceeds
``max_thermal_ratio`` (default 1) times the mean ``k_t`` (with the defaults: below 34.9 deg C,
set by stage 2), and warns when the harmonic series misses ``k_w`` by more than
``fit_tolerance``. The mesh stiffness is always above ``k_t``, so the natural frequencies sit
above the isothermal ones and drift down as the gears heat.

The backlash does not depend on temperature in seed 001 (its ``D_12``, ``D_34`` are fixed
parameters of each map). Seed 000's physics (thermal expansion closes the gap) is available
as an option: with ``TwoStageThermalSetup.backlash_reference`` a
:class:`~models.thermal.ThermalReference`, each stage's half backlash becomes
``b - (Delta_1 + Delta_2) / 2`` at the pitch point for the gears uniformly at the bulk
temperature (no flash); a closure larger than the gap is the jammed state of SEED-NOTES 10
and raises :class:`~models.errors.ModelError`.

Other inputs seed 001 leaves open (defaults of :class:`TwoStageThermalSetup`): the load
(seed 001's "moderate" 10 kN normal load on stage 1), the mean mesh stiffness (ISO 6336-1's
typical ``c_gamma = 20 N/(mm um)`` times the 95 mm face width), the non-dimensional length
(10 um, so the seed's ``D = 1`` is a 10 um half backlash), the stiffness fluctuation (one
harmonic, the seed's ``k = 0.2``; or, with ``stiffness_source="mesh-cycle"``, the VVMS of
:func:`models.stiffness.mesh_cycle` from the potential-energy compliance, whose means, 1.72e9
and 1.79e9 N/m at 10 and 20 kN, are within 11 % of the ISO default), the error (one harmonic,
the seed's ``e = 0.2``) and 5 % damping.

References
----------
.. [1] Seed 001, "Nonlinear Dynamics of Spur Gear Systems: The Critical Role of Contact
   Temperature" (two-stage model, temperature stiffness, maps over mesh frequency and bulk
   temperature).
.. [2] ISO 6336-1:2019, *Calculation of load capacity of spur and helical gears - Part 1*,
   mesh stiffness ``c_gamma``.
.. [3] H. S. Carslaw, J. C. Jaeger, *Conduction of Heat in Solids*, 2nd ed., Oxford, 1959,
   sec. 2.9 (constant flux into a semi-infinite solid; penetration depth ``sqrt(kappa t)``).
.. [4] H. Blok, "Theoretical study of temperature rise at surfaces of actual contact under
   oiliness lubricating conditions", IMechE, 1937 (flash temperature, high-Peclet premise).
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass
from functools import lru_cache
from typing import Literal

import numpy as np

from models.dynamics.two_stage import TwoStageModel, rigid_shaft_model, six_state_from_gear_sets
from models.errors import ModelError
from models.geometry import GearSet, load_gear_set
from models.geometry.gear_pair import GearPair
from models.geometry.kinematics import speed_rpm_from_mesh_frequency
from models.stiffness.load_distribution import load_share_seed_000
from models.stiffness.mesh_cycle import Harmonics, mesh_cycle, tabulate_compliance
from models.stiffness.potential_energy import pair_compliance
from models.thermal import (
    FRICTION_SEED_000,
    GearTemperature,
    ThermalReference,
    flash_temperature,
    temperature_stiffness,
    thermal_deformation,
)

__all__ = [
    "ThermalStiffness",
    "TwoStageThermalSetup",
    "thermal_stiffness_component",
    "two_stage_at_temperature",
    "two_stage_models_at_temperature",
]


# ----------------------------------------------------------------------------- setup
@dataclass(frozen=True)
class TwoStageThermalSetup:
    """Inputs of the thermal two-stage model (defaults: the choices in the module docstring).

    Attributes
    ----------
    stage1, stage2 : str
        Names of the shipped gear sets (gears 1-2 and 3-4).
    normal_load_N : float
        Stage-1 normal load ``F = T_1 / r_b1`` (N); ``T_1`` follows, ``T_2`` by static balance.
    mean_stiffness_N_m : tuple of 2 float
        Mean load-sharing mesh stiffness ``k_t`` of each stage (N/m).
    stiffness_fluctuation : tuple of 2 float
        ``k_t / k_mean = 1 + k cos(2 pi tau)`` (-), seed 001's ``k``.
    stiffness_source : {"harmonic", "mesh-cycle"}
        ``"harmonic"``: ``k_t`` from ``mean_stiffness_N_m`` and ``stiffness_fluctuation``
        (seed 001's parametrisation). ``"mesh-cycle"``: ``k_t(tau)`` is the VVMS of
        :func:`models.stiffness.mesh_cycle` at the stage's normal load with the
        potential-energy tooth-pair compliance (Hertz term included, corner contact on),
        its mean and ``n_harmonics`` harmonics; ``mean_stiffness_N_m`` and
        ``stiffness_fluctuation`` are then ignored.
    error_amplitude_m : tuple of 2 float
        Static transmission error ``e cos(2 pi tau)`` (m).
    half_backlash_m : tuple of 2 float
        Half backlash ``b`` at the initial temperature (m).
    length_scale_m : float
        Non-dimensional length ``L`` (m): seed 001's ``D = b / L``.
    zeta : tuple of 2 float
        Damping ratios (-).
    initial_temperature_C : float
        Seed 001's ``Delta_0`` (deg C), from which the thermal deformation counts.
    friction_coefficient : float
        For the flash temperature (-).
    flash : bool
        Add the flash temperature to the contact temperature rise (seed 001: yes).
    flash_model : {"surface-layer", "whole-tooth"}
        How the flash temperature deforms the flank (module docstring): ``"surface-layer"``
        (default) expands only the layer it penetrates during the contact time,
        ``sigma_f = xi Delta_f sqrt(kappa 2 b_H / v)``; ``"whole-tooth"`` heats the whole
        tooth to it (seed 001 read literally, kept for comparison; overstates ``sigma_f``
        by two to three orders of magnitude).
    thermal : bool
        Include the temperature stiffness at all (False: isothermal ``k_t`` only).
    backlash_reference : ThermalReference or None
        None: backlash independent of temperature (seed 001). Otherwise the reference of
        seed 000's thermal closure of the gap (module docstring).
    n_phases, n_harmonics : int
        Samples of ``k_w`` over a mesh cycle, and harmonics kept.
    max_thermal_ratio : float
        Refuse (:class:`~models.errors.ModelError`) a bulk temperature at which ``k_w``
        exceeds this multiple of the stage's mean ``k_t`` anywhere in the cycle (-).
        Seed 001's ``k_w ~ 1/(Delta_M - Delta_0)`` diverges at the initial temperature; with
        the defaults ``k_w = k_t`` at 29.9 deg C on stage 1 and 34.9 deg C on stage 2
        (``k_w / k_t`` = 0.50 and 0.74 at 40 deg C). ``math.inf`` disables the check.
    fit_tolerance : float
        Warn (``RuntimeWarning``) when the ``n_harmonics`` series misses the sampled ``k_w``
        by more than this fraction of its mean (``ThermalStiffness.fit_residual``).
    """

    stage1: str = "two-stage-45-steel"
    stage2: str = "two-stage-45-steel-stage2"
    normal_load_N: float = 1.0e4
    mean_stiffness_N_m: tuple[float, float] = (1.9e9, 1.9e9)
    stiffness_fluctuation: tuple[float, float] = (0.2, 0.2)
    stiffness_source: Literal["harmonic", "mesh-cycle"] = "harmonic"
    error_amplitude_m: tuple[float, float] = (2.0e-6, 2.0e-6)
    half_backlash_m: tuple[float, float] = (10.0e-6, 10.0e-6)
    length_scale_m: float = 10.0e-6
    zeta: tuple[float, float] = (0.05, 0.05)
    initial_temperature_C: float = 20.0
    friction_coefficient: float = FRICTION_SEED_000
    flash: bool = True
    flash_model: Literal["surface-layer", "whole-tooth"] = "surface-layer"
    thermal: bool = True
    backlash_reference: ThermalReference | None = None
    n_phases: int = 128
    n_harmonics: int = 10
    max_thermal_ratio: float = 1.0
    fit_tolerance: float = 0.05

    def __post_init__(self) -> None:
        if not (self.normal_load_N >= 0 and self.length_scale_m > 0):
            raise ModelError("`normal_load_N` must be >= 0 and `length_scale_m` > 0")
        if not (self.n_phases >= 2 * self.n_harmonics + 2 and self.n_harmonics >= 0):
            raise ModelError("`n_phases` must be >= 2 n_harmonics + 2")
        if self.flash_model not in ("surface-layer", "whole-tooth"):
            raise ModelError(
                f"`flash_model` must be 'surface-layer' or 'whole-tooth', was {self.flash_model!r}"
            )
        if not (self.max_thermal_ratio > 0 and self.fit_tolerance > 0):
            raise ModelError("`max_thermal_ratio` and `fit_tolerance` must be > 0")
        if self.stiffness_source not in ("harmonic", "mesh-cycle"):
            raise ModelError(
                f"`stiffness_source` must be 'harmonic' or 'mesh-cycle', was "
                f"{self.stiffness_source!r}"
            )

    def gear_sets(self) -> tuple[GearSet, GearSet]:
        """The two shipped gear sets (stage 1, stage 2)."""
        return load_gear_set(self.stage1), load_gear_set(self.stage2)


# ----------------------------------------------------------------------------- thermal part
@dataclass(frozen=True)
class ThermalStiffness:
    """Seed 001's temperature stiffness of one stage over a mesh cycle, for several speeds.

    Attributes
    ----------
    phase : numpy.ndarray
        Mesh-cycle phases ``tau`` (-), shape ``(n_phases,)`` (``tau = 0``: a pair at A).
    pinion_speed_rpm : numpy.ndarray
        Speeds (1/min), shape ``(n_speeds,)``.
    k_w_N_m : numpy.ndarray
        ``k_w(tau) = sum_j F R_j / (sigma_1 + sigma_2)`` (N/m), shape ``(n_speeds, n_phases)``.
    flash_max_K : numpy.ndarray
        Highest flash temperature over the cycle (K), shape ``(n_speeds,)``.
    harmonics : tuple of Harmonics
        ``k_w / k_mean`` as a mesh-harmonic series, one per speed.
    flash_deformation_max_m : numpy.ndarray
        Highest flash part ``sigma_f,1 + sigma_f,2`` of the deformation over the path of
        contact (m), shape ``(n_speeds,)``; 0 without flash.
    fit_residual : numpy.ndarray
        ``max |series - k_w / k_mean|`` at the sampled phases over the series mean (-), shape
        ``(n_speeds,)``: how well ``n_harmonics`` harmonics carry ``k_w``.
    """

    phase: np.ndarray
    pinion_speed_rpm: np.ndarray
    k_w_N_m: np.ndarray
    flash_max_K: np.ndarray
    harmonics: tuple[Harmonics, ...]
    flash_deformation_max_m: np.ndarray
    fit_residual: np.ndarray


def _fit(values: np.ndarray, n_harmonics: int) -> Harmonics:
    c = np.fft.rfft(values) / values.size
    k = slice(1, n_harmonics + 1)
    return Harmonics(float(c[0].real), 2 * np.abs(c[k]), np.angle(c[k]))


def _flash_layer_depth(pair: GearPair, ft) -> tuple[np.ndarray, np.ndarray]:
    """Thermal penetration depths ``delta_i = sqrt(kappa_i 2 b_H / v_i)`` of both flanks (m)."""
    out = []
    for gear, v in ((pair.pinion, ft.velocity_pinion_m_s), (pair.wheel, ft.velocity_wheel_m_s)):
        m = gear.material
        kappa = m.conductivity_W_mK / (m.density_kg_m3 * m.specific_heat_J_kgK)
        t_c = np.divide(2.0 * ft.half_width_m, v, out=np.zeros(np.shape(v)), where=v > 0)
        out.append(np.sqrt(kappa * t_c))
    return out[0], out[1]


def thermal_stiffness_component(
    pair: GearPair,
    bulk_temperature_C: float,
    pinion_speed_rpm,
    normal_load_N: float,
    *,
    mean_stiffness_N_m: float,
    initial_temperature_C: float = 20.0,
    friction_coefficient: float = FRICTION_SEED_000,
    flash: bool = True,
    flash_model: Literal["surface-layer", "whole-tooth"] = "surface-layer",
    n_phases: int = 128,
    n_harmonics: int = 10,
) -> ThermalStiffness:
    r"""Seed 001's temperature stiffness ``k_w(tau)`` of one spur stage (module docstring).

    Parameters
    ----------
    pair : GearPair
        Contact ratio in [1, 2) (seed 000's load share).
    bulk_temperature_C : float
        Bulk temperature ``Delta_M`` (deg C), > ``initial_temperature_C``.
    pinion_speed_rpm : array_like
        Pinion speeds (1/min), > 0 (only the flash temperature depends on them).
    normal_load_N : float
        Total normal load ``F`` of the stage (N).
    mean_stiffness_N_m : float
        ``k_t`` mean (N/m) that normalises the harmonics.
    initial_temperature_C, friction_coefficient, flash, flash_model, n_phases, n_harmonics
        As in :class:`TwoStageThermalSetup`.

    Returns
    -------
    ThermalStiffness

    Notes
    -----
    .. math:: k_w(\tau) = \sum_j \frac{F R(s_j)}{\sigma_1(s_j) + \sigma_2(s_j)}, \quad
              s_j = A + (\tau + j) p_b \in [A, E],
              \qquad \sigma_i = \sigma_{M,i} + \sigma_{f,i}

    ``sigma_M,i`` the normal flank deformation of gear ``i`` with the body uniformly at
    ``Delta_M`` (:func:`models.thermal.thermal_deformation`, reference ``Delta_0``; by
    similarity ``xi (Delta_M - Delta_0) rho_i``) and ``sigma_f,i`` the flash part:

    * ``"surface-layer"`` (default): ``sigma_f,i = xi_i Delta_f delta_i`` with the thermal
      penetration depth ``delta_i = sqrt(kappa_i t_c,i)`` over the contact time
      ``t_c,i = 2 b_H / v_i`` (module docstring, "The flash temperature");
    * ``"whole-tooth"``: the flash temperature as the local rise of the whole tooth
      (``ThermalReference(flash_counts_as_local_rise=True)``), seed 001's wording taken
      literally; overstates ``sigma_f`` by about 600x at 40 deg C, 10000 rpm.

    Examples
    --------
    Without flash, a uniform rise ``dT`` deforms the flanks by ``xi dT rho_i`` (similarity),
    so ``k_w = F / (xi dT (rho_1 + rho_2))`` per pair: halving the rise doubles ``k_w``.

    >>> from models.geometry import load_gear_set
    >>> g = load_gear_set("two-stage-45-steel").pair
    >>> kw = [thermal_stiffness_component(g, t, 1000.0, 1e4, mean_stiffness_N_m=1.9e9,
    ...       flash=False).k_w_N_m.mean() for t in (60.0, 100.0)]
    >>> round(float(kw[0] / kw[1]), 6)
    2.0
    """
    t_b = float(bulk_temperature_C)
    t0 = float(initial_temperature_C)
    if not t_b > t0:
        raise ModelError(
            f"`bulk_temperature_C` must exceed the initial temperature {t0} deg C, was {t_b}: "
            "seed 001's k_w = F / (b sigma) diverges as the thermal deformation vanishes"
        )
    if flash_model not in ("surface-layer", "whole-tooth"):
        raise ModelError(
            f"`flash_model` must be 'surface-layer' or 'whole-tooth', was {flash_model!r}"
        )
    speed = np.atleast_1d(np.asarray(pinion_speed_rpm, dtype=float))
    if speed.ndim != 1 or np.any(~(speed > 0)):
        raise ModelError("`pinion_speed_rpm` must be a 1-d array of speeds > 0")
    phase = np.arange(int(n_phases)) / int(n_phases)
    a, e, pb = pair.start_of_contact, pair.end_of_contact, pair.base_pitch
    n_slots = math.ceil(pair.contact_ratio) + 1
    s = a + (phase[:, None] + np.arange(n_slots)[None, :]) * pb  # (P, slots)
    share = np.where(s <= e, load_share_seed_000(pair, np.minimum(s, e)), 0.0)
    s_eval = np.minimum(s, e)
    torque = normal_load_N * pair.base_radius(1)
    ft = flash_temperature(
        pair,
        s_eval,
        torque,
        speed[:, None, None],
        bulk_temperature_C=t_b,
        friction_coefficient=friction_coefficient,
        load_share=share,
    )
    shape = (speed.size, *s.shape)
    bulk = thermal_deformation(pair, s_eval, ThermalReference(t0), GearTemperature.uniform(t_b))
    sig_m = bulk.pinion.normal_m + bulk.wheel.normal_m
    sig1 = np.broadcast_to(bulk.pinion.normal_m, shape)
    sig2 = np.broadcast_to(bulk.wheel.normal_m, shape)
    if flash and flash_model == "surface-layer":
        d1, d2 = _flash_layer_depth(pair, ft)
        fk = np.broadcast_to(ft.flash_K, shape)
        sig1 = sig1 + pair.pinion.material.thermal_expansion_per_K * fk * d1
        sig2 = sig2 + pair.wheel.material.thermal_expansion_per_K * fk * d2
    elif flash:
        ref = ThermalReference(t0, flash_counts_as_local_rise=True)
        d = thermal_deformation(pair, s_eval, ref, GearTemperature.uniform(t_b), flash=ft)
        sig1 = np.broadcast_to(d.pinion.normal_m, shape)
        sig2 = np.broadcast_to(d.wheel.normal_m, shape)
    kw = temperature_stiffness(normal_load_N * share, pair.face_width_m, sig1, sig2)
    k_pair = np.where(share > 0, kw.pair_N_m, 0.0)
    k_w = k_pair.sum(axis=-1)
    harm = tuple(_fit(row / mean_stiffness_N_m, int(n_harmonics)) for row in k_w)
    resid = np.array(
        [
            np.max(np.abs(h(phase) - row / mean_stiffness_N_m)) / h.mean
            for h, row in zip(harm, k_w, strict=True)
        ]
    )
    inside = share > 0
    sig_f = np.where(inside, sig1 + sig2 - sig_m, 0.0).max(axis=(1, 2))
    fmax = np.broadcast_to(ft.flash_K, shape).max(axis=(1, 2))
    return ThermalStiffness(phase, speed, k_w, fmax, harm, sig_f, resid)


def _closure_half_backlash(
    setup: TwoStageThermalSetup, pair: GearPair, b: float, temperature_C: float
) -> float:
    ref = setup.backlash_reference
    if ref is None:
        return b
    d = thermal_deformation(pair, [pair.pitch_point], ref, GearTemperature.uniform(temperature_C))
    b_t = b - 0.5 * float(d.total_m[0])
    if b_t < 0:
        raise ModelError(
            f"thermal closure {float(d.total_m[0]) * 1e6:.3g} um at {temperature_C} deg C "
            f"exceeds the gap 2b = {2 * b * 1e6:.3g} um: the gears are jammed (SEED-NOTES 10)"
        )
    return b_t


@lru_cache(maxsize=16)
def _vvms(gear_set: str, normal_load_N: float, n_phases: int, n_harmonics: int) -> Harmonics:
    """VVMS harmonics (N/m) of a shipped gear set at a normal load (potential energy + Hertz)."""
    pair = load_gear_set(gear_set).pair
    comp = tabulate_compliance(pair, lambda s: pair_compliance(pair, s).total_m_per_N)
    cyc = mesh_cycle(
        pair,
        comp,
        normal_load_N * pair.base_radius(1),
        n_phases=n_phases,
        n_harmonics=n_harmonics,
    )
    return cyc.vvms_harmonics


def _check_thermal(
    setup: TwoStageThermalSetup,
    temperature_C: float,
    comps: list[ThermalStiffness],
    k_mean: tuple[float, float],
) -> None:
    """Refuse ``k_w > max_thermal_ratio k_t``; warn when the harmonic fit misses ``k_w``."""
    rise = temperature_C - setup.initial_temperature_C
    for st, (c, km) in enumerate(zip(comps, k_mean, strict=True)):
        ratio = float(np.max(c.k_w_N_m)) / km
        if not ratio <= setup.max_thermal_ratio:
            raise ModelError(
                f"stage {st + 1}: seed 001's temperature stiffness k_w reaches {ratio:.3g} k_t "
                f"at {temperature_C} deg C ({rise:.3g} K above the initial temperature), above "
                f"max_thermal_ratio = {setup.max_thermal_ratio}: k_w = F / (b sigma) diverges "
                f"as the rise vanishes (it is ~1/rise), so the model is not meaningful this "
                f"close to {setup.initial_temperature_C} deg C; choose a higher bulk temperature"
            )
        worst = float(np.max(c.fit_residual))
        if worst > setup.fit_tolerance:
            warnings.warn(
                f"stage {st + 1} at {temperature_C} deg C: {setup.n_harmonics} harmonics miss "
                f"k_w by up to {worst:.3g} of its mean (fit_tolerance {setup.fit_tolerance})",
                RuntimeWarning,
                stacklevel=3,
            )


def two_stage_models_at_temperature(
    setup: TwoStageThermalSetup, temperature_C: float, frequencies_Hz: np.ndarray
) -> list[tuple[TwoStageModel, dict, float]]:
    """The model at one bulk temperature for each stage-1 mesh frequency (module docstring).

    The temperature stiffness is computed once for all the frequencies (one row of a
    peak-DTE map, :func:`models.dynamics.two_stage_maps.prepare_map_grid`).

    Parameters
    ----------
    setup : TwoStageThermalSetup
        Model inputs.
    temperature_C : float
        Bulk temperature (deg C).
    frequencies_Hz : numpy.ndarray
        Stage-1 mesh frequencies (Hz), shape ``(n_f,)``, > 0.

    Returns
    -------
    list of tuple
        Per frequency, as :func:`two_stage_at_temperature`: the non-dimensional model, its
        scales and ``Lambda``.

    Raises
    ------
    ModelError
        A bulk temperature not above the initial one, ``k_w`` above
        ``setup.max_thermal_ratio`` times the mean ``k_t``, or the gears jammed by the
        thermal closure of the backlash.
    """
    g1, g2 = setup.gear_sets()
    p1, p2 = g1.pair, g2.pair
    r1, r2, r3 = p1.base_radius(1), p1.base_radius(2), p2.base_radius(1)
    t1 = setup.normal_load_N * r1
    f2 = t1 * (r2 / r1) / r3  # stage-2 normal load T_3 / r_b3, T_3 = T_1 r_2 / r_1
    n1 = speed_rpm_from_mesh_frequency(frequencies_Hz, p1.pinion.teeth)
    n3 = n1 * p1.pinion.teeth / p1.wheel.teeth
    kf, ea = setup.stiffness_fluctuation, setup.error_amplitude_m
    z = np.zeros(1)
    if setup.stiffness_source == "mesh-cycle":
        v1 = _vvms(setup.stage1, setup.normal_load_N, setup.n_phases, setup.n_harmonics)
        v2 = _vvms(setup.stage2, f2, setup.n_phases, setup.n_harmonics)
        km = (v1.mean, v2.mean)
        stiff = tuple(Harmonics(1.0, v.amplitude / v.mean, v.phase_rad.copy()) for v in (v1, v2))
    else:
        km = setup.mean_stiffness_N_m
        stiff = (Harmonics(1.0, np.array([kf[0]]), z), Harmonics(1.0, np.array([kf[1]]), z))
    if setup.thermal:
        comps = [
            thermal_stiffness_component(
                pair,
                temperature_C,
                speed,
                load,
                mean_stiffness_N_m=k_mean,
                initial_temperature_C=setup.initial_temperature_C,
                friction_coefficient=setup.friction_coefficient,
                flash=setup.flash,
                flash_model=setup.flash_model,
                n_phases=setup.n_phases,
                n_harmonics=setup.n_harmonics,
            )
            for pair, speed, load, k_mean in (
                (p1, n1, setup.normal_load_N, km[0]),
                (p2, n3, f2, km[1]),
            )
        ]
        _check_thermal(setup, temperature_C, comps, km)
        th1, th2 = comps[0].harmonics, comps[1].harmonics
    b = (
        _closure_half_backlash(setup, p1, setup.half_backlash_m[0], temperature_C),
        _closure_half_backlash(setup, p2, setup.half_backlash_m[1], temperature_C),
    )
    err = (Harmonics(0.0, np.array([ea[0]]), z), Harmonics(0.0, np.array([ea[1]]), z))
    out = []
    for i, f in enumerate(frequencies_Hz):
        system = six_state_from_gear_sets(
            g1,
            g2,
            mean_stiffness_N_m=km,
            input_torque_Nm=t1,
            half_backlash_m=b,
            zeta=setup.zeta,
            stiffness=(stiff[0], stiff[1]),
            error_m=err,
            thermal=(th1[i], th2[i]) if setup.thermal else (None, None),
        )
        model, scales = rigid_shaft_model(system, setup.length_scale_m)
        out.append((model, scales, 2 * math.pi * float(f) / scales["omega_n"]))
    return out


def two_stage_at_temperature(
    temperature_C: float, frequency_Hz: float, setup: TwoStageThermalSetup | None = None
) -> tuple[TwoStageModel, dict, float]:
    """The model at one bulk temperature and stage-1 mesh frequency (module docstring).

    Returns the non-dimensional model, its scales (``omega_n`` in rad/s, ``L`` in m, ...,
    as :func:`~models.dynamics.two_stage.rigid_shaft_model`) and ``Lambda``, the stage-1
    mesh frequency over ``omega_n`` to pass to :func:`~models.dynamics.two_stage_periods`.
    The frequency enters the model only through the flash temperature's speed.
    """
    s = setup or TwoStageThermalSetup()
    f = np.array([float(frequency_Hz)])
    return two_stage_models_at_temperature(s, float(temperature_C), f)[0]
